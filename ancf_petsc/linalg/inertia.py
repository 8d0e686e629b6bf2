"""Stability of a converged equilibrium: the number of negative eigenvalues of the tangent.

The default linear solver factors the symmetric Jacobian as LDLᵀ (MUMPS).  By Sylvester's law
of inertia the number of negative pivots of that factorisation is the number of negative
eigenvalues of the Jacobian, so every Newton iteration already knows whether the state it
linearised at is a minimum of the total potential (stable) or a saddle (unstable).  MUMPS
reports the count as INFOG(12).

Held DOFs carry unit diagonal rows, so the count is that of the free-DOF tangent.
"""
from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

def mumps_factor(ksp: PETSc.KSP) -> PETSc.Mat | None:
    """The MUMPS factor matrix of ``ksp``'s LU/Cholesky preconditioner, None when there is none
    (another preconditioner or package, or before the first factorisation)."""
    pc = ksp.getPC()
    if pc.getType() == "python":                # the compact factorisation (compact_factor.py)
        factor = getattr(pc.getPythonContext(), "factor", None)
        return factor() if factor is not None else None
    if pc.getType() not in ("cholesky", "lu") or pc.getFactorSolverType() != "mumps":
        return None
    try:
        return pc.getFactorMatrix()             # raises before the first factorisation
    except PETSc.Error:
        return None


def pivot_counts(ksp: PETSc.KSP) -> tuple[int, int] | None:
    """(negative, null) pivots of the matrix last factored by ``ksp``'s MUMPS Cholesky (LDLᵀ)
    preconditioner — INFOG(12) and INFOG(28), the latter with null-pivot detection on
    (ICNTL(24)) — also the compact one's (compact_factor.py) — or by the fascicle Schur
    preconditioner (``FascicleSchur.pivot_counts``); None when the preconditioner is none of
    these (collective; same on every rank)."""
    pc = ksp.getPC()
    if pc.getType() == "python":                # the fascicle Schur solver (fieldsplit.py)
        counts = getattr(pc.getPythonContext(), "pivot_counts", None)
        if counts is not None:
            return counts()
    if pc.getType() == "python" and not getattr(pc.getPythonContext(), "symmetric", True):
        return None                             # the compact factorisation's LU: no inertia
    factor = mumps_factor(ksp) if pc.getType() in ("cholesky", "python") else None
    if factor is None:
        return None
    # a root front factored by ScaLAPACK (ICNTL(13) = 0, MUMPS's default on many ranks) leaves
    # its pivots out of the count: only trust it with a sequential root
    if ksp.getComm().getSize() > 1 and factor.getMumpsIcntl(13) != 1:
        return None
    return int(factor.getMumpsInfog(12)), int(factor.getMumpsInfog(28))


def mumps_ldlt(J: PETSc.Mat, null_pivots: bool = True) -> PETSc.KSP:
    """A KSP (preonly) whose preconditioner is a MUMPS LDLᵀ of ``J`` made for its inertia: a
    sequential root (ICNTL(13) = 1, so that the count is whole on several ranks) and, with
    ``null_pivots``, the direct solver's null-pivot detection (ICNTL(24), CNTL(3) 1e-11).  Not
    set up; the caller destroys it."""
    ksp = PETSc.KSP().create(comm=J.getComm())
    ksp.setOperators(J, J)
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("cholesky")
    pc.setFactorSolverType("mumps")
    pc.setFactorSetUpSolverType()
    F = pc.getFactorMatrix()
    F.setMumpsIcntl(13, 1)
    F.setMumpsIcntl(24, 1 if null_pivots else 0)
    F.setMumpsCntl(3, 1e-11)
    return ksp


def exact_pivot_counts(J: PETSc.Mat) -> tuple[int, int] | None:
    """(negative, null) pivots of a MUMPS LDLᵀ of ``J`` itself (``mumps_ldlt``): the check of a
    preconditioner that counts another matrix's inertia (fieldsplit.py's J − K_×).  None where
    MUMPS fails.  Collective."""
    ksp = None
    try:
        ksp = mumps_ldlt(J)
        ksp.setUp()
        F = ksp.getPC().getFactorMatrix()
        return int(F.getMumpsInfog(12)), int(F.getMumpsInfog(28))
    except PETSc.Error:
        return None
    finally:
        if ksp is not None:
            ksp.destroy()


def mumps_error(ksp: PETSc.KSP) -> int | None:
    """MUMPS's error code INFOG(1) (< 0) after a failed factorisation by ``ksp``'s preconditioner,
    None when it did not fail or is not MUMPS."""
    factor = mumps_factor(ksp)
    if factor is None:
        return None
    code = int(factor.getMumpsInfog(1))
    return code if code < 0 else None


#: the SNES preconditioning matrices that are no assembled tangent (nothing to factor)
UNASSEMBLED = (PETSc.Mat.Type.MFFD, PETSc.Mat.Type.SHELL, PETSc.Mat.Type.PYTHON)
_own_count: list = [None, None]                 # (P's handle, state, norm), its counts


def own_factor_possible(snes: PETSc.SNES, symmetric: bool) -> bool:
    """Whether ``solver_pivot_counts`` can factor the SNES's assembled tangent itself: a
    symmetric Jacobian, assembled, and MUMPS in this PETSc."""
    P = snes.getJacobian()[1]
    return symmetric and P.getType() not in UNASSEMBLED and PETSc.Sys.hasExternalPackage("mumps")


def counts_inertia(snes: PETSc.SNES, symmetric: bool) -> bool:
    """Whether ``solver_pivot_counts`` counts: the linear solver's factor or one of its own."""
    return pivot_counts(snes.getKSP()) is not None or own_factor_possible(snes, symmetric)


def solver_pivot_counts(snes: PETSc.SNES, symmetric: bool) -> tuple[int, int] | None:
    """``pivot_counts`` of the SNES's linear solver; where that counts none (LU, PETSc's or
    SuperLU's factors, Krylov methods), of a MUMPS LDLᵀ of its last assembled tangent
    (``exact_pivot_counts``), once per state of that matrix, so that the stability verdict does
    not depend on the linear solver (a column at 3 x its Euler load: 'unstable' by default,
    'completed' with -pc_type lu).  None for an unsymmetric or unassembled Jacobian.  Collective."""
    counts = pivot_counts(snes.getKSP())
    if counts is not None or not own_factor_possible(snes, symmetric):
        return counts
    P = snes.getJacobian()[1]
    key = (P.handle, P.stateGet(), P.norm(PETSc.NormType.FROBENIUS))
    # one decision for all ranks (a state counter is a rank's own): the factorisation is collective
    if not P.getComm().tompi4py().allreduce(_own_count[0] == key, op=MPI.LAND):
        _own_count[:] = [key, exact_pivot_counts(P)]
    return _own_count[1]
