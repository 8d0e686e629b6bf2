"""physics/bspline.py against scipy.interpolate (issue 40): the same knots, coefficients, values
and derivative splines to the last bit, for every degree the sections use, inside and beyond
the knots (extrapolation) and at NaN."""
import numpy as np
import pytest
from scipy.interpolate import make_interp_spline

from ancf_petsc.physics.bspline import interpolating_spline


@pytest.mark.parametrize("k", [1, 2, 3, 5])
def test_bitwise_equal_to_scipy(k):
    rng = np.random.default_rng(k)
    for _ in range(40):
        m = int(rng.integers(k + 1, 25))
        x = np.cumsum(rng.random(m) + 0.01)
        y = rng.standard_normal((m, 2))
        ref, ours = make_interp_spline(x, y, k=k), interpolating_spline(x, y, k)
        assert np.array_equal(ref.t, ours.t) and np.array_equal(ref.c, ours.c)
        xs = np.concatenate([rng.uniform(x[0] - 1.0, x[-1] + 1.0, 100), x, [np.nan]])
        for nu in range(min(k, 2) + 1):
            r, o = (ref.derivative(nu), ours.derivative(nu)) if nu else (ref, ours)
            assert np.array_equal(r(xs), o(xs), equal_nan=True)
            assert np.array_equal(r(xs[3]), o(xs[3]))          # one point: shape (2,)


def test_even_degrees_above_two_are_refused_like_scipy():
    with pytest.raises(ValueError, match="Odd degree"):
        interpolating_spline(np.arange(6.0), np.zeros((6, 2)), 4)
