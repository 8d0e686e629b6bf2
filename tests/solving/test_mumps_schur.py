"""MUMPS called directly (linalg/mumps_schur.py): the structure mirrors the installed header, the
Schur complement, condensation and expansion, and the inertia, against numpy."""
import numpy as np
import pytest
import scipy.sparse as sp

from helpers import petsc_init


def _matrix(n: int, seed: int) -> np.ndarray:
    """A sparse symmetric indefinite matrix with a regular interior block."""
    rng = np.random.default_rng(seed)
    A = sp.random(n, n, density=0.15, random_state=seed).toarray()
    A = A + A.T
    d = rng.uniform(-3.0, 3.0, n)
    A[np.arange(n), np.arange(n)] += d + 4.0 * np.sign(d)
    return A


def _factor(A: np.ndarray, n_schur: int):
    from ancf_petsc.linalg.mumps_schur import SchurFactor
    U = sp.csr_matrix(np.triu(A))
    U.sort_indices()
    f = SchurFactor(U.indptr, U.indices, n_schur, {7: 0, 14: 100, 24: 0})
    f.values[:] = U.data
    return f, U


def test_structure_matches_the_installed_header():
    """MUMPS writes its version into the mirrored structure at initialisation; a wrong layout
    would put it elsewhere (SchurFactor refuses then)."""
    petsc_init()
    from ancf_petsc.linalg.mumps_schur import VERSION
    f, _ = _factor(_matrix(10, 0), 3)
    assert f.id.version_number.decode() == VERSION
    assert f.id.sym == 2 and f.id.n == 10
    f.destroy()


@pytest.mark.parametrize("n_schur", [0, 12])
def test_schur_complement_condensation_and_expansion_are_exact(n_schur):
    petsc_init()
    n = 60
    A = _matrix(n, 1)
    f, U = _factor(A, n_schur)
    assert f.factor()
    ni = n - n_schur
    A_ii, A_ig, A_gi, A_gg = A[:ni, :ni], A[:ni, ni:], A[ni:, :ni], A[ni:, ni:]
    assert f.negative_pivots == int(np.sum(np.linalg.eigvalsh(A_ii) < 0))
    b = np.random.default_rng(2).standard_normal(n)
    x = np.linalg.solve(A, b)
    if n_schur == 0:
        assert np.abs(f.solve(b) - x).max() <= 1e-12 * np.abs(x).max()
        f.destroy()
        return
    sigma = A_gg - A_gi @ np.linalg.solve(A_ii, A_ig)
    assert np.abs(f.schur() - sigma).max() <= 1e-12 * np.abs(sigma).max()
    g = f.condense(b[:ni], b[ni:])
    assert np.abs(g - (b[ni:] - A_gi @ np.linalg.solve(A_ii, b[:ni]))).max() <= 1e-12 * np.abs(g).max()
    x_g = np.linalg.solve(sigma, g)
    x_i = f.expand(x_g)
    assert np.abs(np.concatenate([x_i, x_g]) - x).max() <= 1e-10 * np.abs(x).max()
    # new values, same pattern: the analysis is kept, the numbers are new
    f.values[:] = 2.0 * U.data
    assert f.factor()
    assert np.abs(f.schur() - 2.0 * sigma).max() <= 1e-12 * np.abs(sigma).max()
    f.destroy()


def test_a_failed_factorisation_is_reported_not_raised():
    """INFOG(1) < 0 in the numeric phase (here MUMPS's working memory capped at 1 MB by
    ICNTL(23)) comes back as False and ``failed``: the caller makes every rank's solve NaN."""
    petsc_init()
    from ancf_petsc.linalg.mumps_schur import SchurFactor
    U = sp.csr_matrix(np.triu(_matrix(400, 5)))
    U.sort_indices()
    f = SchurFactor(U.indptr, U.indices, 20, {7: 0, 24: 0, 23: 1})
    f.values[:] = U.data
    assert not f.factor() and f.failed and f.id.infog[0] == -19
    f.destroy()


def test_only_the_upper_triangle_is_accepted():
    petsc_init()
    from ancf_petsc.linalg.mumps_schur import SchurFactor
    L = sp.csr_matrix(np.tril(_matrix(8, 4)))
    with pytest.raises(ValueError, match="upper triangle"):
        SchurFactor(L.indptr, L.indices, 2, {})
