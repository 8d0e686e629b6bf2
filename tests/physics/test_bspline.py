"""physics/bspline.py against scipy.interpolate (issue 40): the same knots, coefficients, values
and derivative splines to the last bit, for every degree the sections use, inside and beyond
the knots (extrapolation) and at NaN; evaluated by scipy's compiled routine (loaded without
scipy.interpolate) and by the numpy recursion that replaces it where it is absent."""
import numpy as np
import pytest
from scipy.interpolate import make_interp_spline

from ancf_petsc.physics import bspline
from ancf_petsc.physics.bspline import SplineSet, interpolating_spline


@pytest.fixture(params=["compiled", "numpy"])
def evaluation(request, monkeypatch):
    """Both ways of evaluating a spline: scipy's compiled routine and the numpy recursion."""
    if request.param == "numpy":
        monkeypatch.setattr(bspline, "compiled", lambda: None)
    else:
        assert bspline.compiled() is not None
    return request.param


@pytest.mark.parametrize("k", [1, 2, 3, 5])
def test_bitwise_equal_to_scipy(k, evaluation):
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


def test_a_spline_set_gives_each_spline_its_own_values():
    """Several splines of different degrees (a curve and its derivative splines) in one pass."""
    rng = np.random.default_rng(7)
    splines = []
    for k in (3, 3, 1, 2):
        x = np.cumsum(rng.random(9) + 0.01)
        s = interpolating_spline(x, rng.standard_normal((9, 2)), k)
        splines += [s] + [s.derivative(nu) for nu in range(1, k + 1)]
    which = rng.integers(0, len(splines), 500)
    xs = rng.uniform(-1.0, 6.0, 500)
    xs[7] = np.nan
    got = SplineSet(splines)(which, xs)
    for i in range(len(xs)):
        assert np.array_equal(got[i], splines[which[i]](xs[i]), equal_nan=True)



@pytest.mark.parametrize("k", [3, 5, 7])
def test_periodic_spline_of_odd_degree_is_scipys(k):
    """periodic_spline, odd k: scipy's make_interp_spline(..., bc_type="periodic") knots, and its
    values and derivatives to round-off (solved otherwise: densely, not by Woodbury's formula)."""
    rng = np.random.default_rng(10 + k)
    for m in (4, 5, 9, 24):
        x = np.cumsum(rng.random(m) + 0.05)
        y = rng.standard_normal((m, 2))
        y[-1] = y[0]
        ref, ours = make_interp_spline(x, y, k=k, bc_type="periodic"), bspline.periodic_spline(x, y, k)
        assert np.array_equal(ref.t, ours.t)
        xs = np.linspace(x[0], x[-1], 200)
        for nu in range(k):
            r, o = (ref.derivative(nu), ours.derivative(nu)) if nu else (ref, ours)
            assert np.allclose(o(xs), r(xs), rtol=0, atol=1e-11 * (1 + np.abs(r(xs)).max()))


@pytest.mark.parametrize("k", [2, 3, 5])
def test_periodic_spline_interpolates_closes_smoothly_and_ignores_the_way_round(k):
    """Through its points, C^(k-1) where it closes, and the same curve from the points reversed:
    scipy's even-degree knots keep x_0 and were not (8 points on a 4 x 2.5 mm ellipse, k = 2: the
    centroid 11.6 um off one way, the other way the mirror image); its knots are midpoints all round."""
    rng = np.random.default_rng(20 + k)
    for m in (4, 5, 9, 24):
        x = np.cumsum(rng.random(m) + 0.05) - 0.5
        y = rng.standard_normal((m, 2))
        y[-1] = y[0]
        s = bspline.periodic_spline(x, y, k)
        assert np.allclose(s(x), y, rtol=0, atol=1e-14)
        for nu in range(1, k):
            d = s.derivative(nu)
            assert np.allclose(d(x[:1]), d(x[-1:]), rtol=0, atol=1e-11 * np.abs(d(x)).max())
        back = bspline.periodic_spline(x[0] + x[-1] - x[::-1], y[::-1], k)
        xs = np.linspace(x[0], x[-1], 101)
        assert np.allclose(back(x[0] + x[-1] - xs), s(xs), rtol=0, atol=1e-13)
