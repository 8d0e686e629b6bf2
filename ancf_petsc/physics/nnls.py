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
import importlib.machinery
import importlib.util
import os

import numpy as np


@functools.lru_cache(maxsize=1)
def _fortran_module():
    """scipy's compiled ``__nnls`` module loaded by path, or None where there is none."""
    try:
        import scipy
        folder = os.path.join(os.path.dirname(scipy.__file__), "optimize")
        for suffix in importlib.machinery.EXTENSION_SUFFIXES:
            path = os.path.join(folder, "__nnls" + suffix)
            if os.path.exists(path):
                spec = importlib.util.spec_from_file_location("scipy.optimize.__nnls", path)
                module = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(module)
                return module if hasattr(module, "nnls") else None
    except (ImportError, OSError):
        pass
    return None


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
