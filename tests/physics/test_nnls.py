"""physics/nnls.py (issue 40): scipy's NNLS without importing scipy.optimize, bitwise equal to
``scipy.optimize.nnls`` (as the cubature compression calls it), and its compiled routine found."""
import numpy as np
import pytest
from scipy.optimize import nnls as scipy_nnls

from ancf_petsc.physics import nnls as ours


def test_the_compiled_routine_is_found():
    assert ours._fortran_module() is not None


@pytest.mark.parametrize("seed", range(5))
def test_bitwise_equal_to_scipy(seed):
    rng = np.random.default_rng(seed)
    m, n = int(rng.integers(5, 30)), int(rng.integers(5, 80))
    A, b = rng.standard_normal((m, n)), rng.standard_normal(m)
    x, r = ours.nnls(A, b, maxiter=50 * m)
    xs, rs = scipy_nnls(A, b, maxiter=50 * m)
    assert np.array_equal(x, xs) and r == rs


def test_too_many_iterations():
    rng = np.random.default_rng(0)
    with pytest.raises(RuntimeError, match="too many iterations"):
        ours.nnls(rng.standard_normal((20, 40)), rng.standard_normal(20), maxiter=1)
