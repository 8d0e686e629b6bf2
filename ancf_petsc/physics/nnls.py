"""Non-negative least squares, min |A x − b| with x >= 0 (the cubature compression of eq. 11):
scipy's own Lawson–Hanson routine, without importing ``scipy.optimize``.

``scipy.optimize.nnls`` calls the compiled ``scipy.optimize.__nnls``; importing it through
``scipy.optimize`` imports every optimiser (~50 ms of every run's start-up, which builds its
sections' cubature rules).  ``nnls`` loads that one extension module by its path and calls it
exactly as ``scipy.optimize.nnls`` does (same answers to the last bit: tests/physics/test_nnls.py);
a scipy without that module (another layout or version) is used through ``scipy.optimize``.
"""
from __future__ import annotations

import functools

import numpy as np

from . import scipy_extension


@functools.lru_cache(maxsize=1)
def _fortran_module():
    """scipy's compiled ``__nnls`` module (not through ``scipy.optimize``), or None."""
    return scipy_extension.load("optimize", "__nnls", "nnls")


def nnls(A: np.ndarray, b: np.ndarray, maxiter: int) -> tuple[np.ndarray, float]:
    """(x, |A x − b|) of ``scipy.optimize.nnls(A, b, maxiter)``; RuntimeError past ``maxiter``."""
    fortran = _fortran_module()
    if fortran is None:
        from scipy.optimize import nnls as scipy_nnls
        return scipy_nnls(A, b, maxiter=maxiter)
    A, b = np.asarray_chkfinite(A), np.asarray_chkfinite(b)
    m, n = A.shape
    x, rnorm, mode = fortran.nnls(A, m, n, b, np.zeros(n, dtype=np.double), np.zeros(m, dtype=np.double),
                                  np.zeros(n, dtype=int), int(maxiter))
    if mode != 1:
        raise RuntimeError("too many iterations")
    return x, rnorm
