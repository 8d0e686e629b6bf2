"""Stability of a converged equilibrium: the number of negative eigenvalues of the tangent.

The default linear solver factors the symmetric Jacobian as LDLᵀ (MUMPS).  By Sylvester's law
of inertia the number of negative pivots of that factorisation is the number of negative
eigenvalues of the Jacobian, so every Newton iteration already knows whether the state it
linearised at is a minimum of the total potential (stable) or a saddle (unstable).  MUMPS
reports the count as INFOG(12); petsc4py 3.18 does not wrap ``MatMumpsGetInfog``, so it is called
through ctypes from the PETSc library petsc4py itself loaded.

Held DOFs carry unit diagonal rows, so the count is that of the free-DOF tangent.
"""
from __future__ import annotations

import ctypes
import os

import numpy as np
from petsc4py import PETSc

_LIB = None


def petsc_library():
    """The libpetsc that petsc4py runs on (already loaded)."""
    global _LIB
    if _LIB is None:
        import petsc4py
        base = os.path.join(petsc4py.get_config()["PETSC_DIR"], "lib")
        names = sorted((f for f in os.listdir(base) if f.startswith("libpetsc") and ".so" in f), key=len)
        if not names:
            raise OSError(f"no libpetsc in {base}")
        # RTLD_NOLOAD: the copy petsc4py loaded, with its symbols kept local (RTLD_GLOBAL would
        # let them shadow later libraries': pymetis then called PT-Scotch's METIS shim and hung)
        _LIB = ctypes.CDLL(os.path.join(base, names[0]), mode=os.RTLD_NOLOAD | os.RTLD_LAZY)
        _LIB.MatMumpsGetInfog.restype = ctypes.c_int
        _LIB.MatMumpsGetIcntl.restype = ctypes.c_int
    return _LIB


def pivot_counts(ksp: PETSc.KSP) -> tuple[int, int] | None:
    """(negative, null) pivots of the matrix last factored by ``ksp``'s MUMPS Cholesky (LDLᵀ)
    preconditioner — INFOG(12) and INFOG(28), the latter with null-pivot detection on
    (ICNTL(24)) — or by the fascicle Schur preconditioner (``FascicleSchur.pivot_counts``);
    None when the preconditioner is neither (collective; same on every rank)."""
    pc = ksp.getPC()
    if pc.getType() == "python":                # the fascicle Schur solver (fieldsplit.py)
        counts = getattr(pc.getPythonContext(), "pivot_counts", None)
        return counts() if counts is not None else None
    if pc.getType() != "cholesky" or pc.getFactorSolverType() != "mumps":
        return None
    try:
        factor = pc.getFactorMatrix()          # raises before the first factorisation
        lib = petsc_library()
    except (PETSc.Error, OSError):
        return None
    int_t = ctypes.c_int64 if np.dtype(PETSc.IntType).itemsize == 8 else ctypes.c_int32
    handle, value = ctypes.c_void_p(factor.handle), int_t(0)
    if ksp.getComm().getSize() > 1:
        # a root front factored by ScaLAPACK (ICNTL(13) = 0, MUMPS's default on many ranks)
        # leaves its pivots out of the count: only trust it with a sequential root
        if lib.MatMumpsGetIcntl(handle, int_t(13), ctypes.byref(value)) != 0 or value.value != 1:
            return None
    counts = []
    for k in (12, 28):
        if lib.MatMumpsGetInfog(handle, int_t(k), ctypes.byref(value)) != 0:
            return None
        counts.append(int(value.value))
    return counts[0], counts[1]
