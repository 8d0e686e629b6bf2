"""The load stepper's messages: its solver in one line, the linear solver in effect, and why a
linear solve failed with what works instead."""
from __future__ import annotations

from petsc4py import PETSc

from ..petsc.inertia import mumps_error
from ..petsc.options import mumps_hint, solver_hint
from .options import factor_package, solver_options


def describe(stepper) -> str:
    """The solver in one line (the run's header)."""
    ksp = stepper.snes.getKSP()
    pc = ksp.getPC()
    ls = stepper.linesearch
    extra = ""
    if pc.getType() in ("lu", "cholesky"):
        extra = f" ({pc.getFactorSolverType()})"
    if stepper.linear == "fieldsplit":
        extra = " (fascicle Schur: dense fascicle factors, MUMPS LDLT on the multipliers)"
    rtol, atol, stol, maxit = stepper.snes.getTolerances()
    return (f"SNES {stepper.snes.getType()} line search {ls}; KSP {ksp.getType()} PC "
            f"{pc.getType()}{extra} on {stepper.problem.matrix_type.upper()}; rtol {rtol:.1e} atol {atol:.1e} "
            f"stol {stol:.1e} max_it {maxit}; "
            f"rounding floor |F(q0,0)| {stepper.rounding_floor:.1e}"
            + ("; chord steps near convergence" if stepper.spec.reuse_tangent else ""))


def linear_solver_detail(stepper, reason: int) -> str:
    """Why a DIVERGED_LINEAR_SOLVE happened and what works (empty for other reasons)."""
    if reason != PETSc.SNES.ConvergedReason.DIVERGED_LINEAR_SOLVE:
        return ""
    kreason = {getattr(PETSc.KSP.ConvergedReason, k): k for k in dir(PETSc.KSP.ConvergedReason)
               if not k.startswith("_")}.get(stepper.ksp_reason, str(stepper.ksp_reason))
    infog1 = mumps_error(stepper.snes.getKSP())
    if stepper.linear == "fieldsplit":
        hint = "solver.linear: direct factors the whole Jacobian instead"
    elif infog1 is not None:
        hint = mumps_hint(infog1)
    else:
        pc, factor = factor_package(stepper.petsc_options, stepper.prefix)
        hint = solver_hint(pc, factor, stepper.problem.comm.size, PETSc.Sys.hasExternalPackage)
    return f" (the linear solver {solver_text(stepper)} stopped with {kreason}; {hint})"


def solver_text(stepper) -> str:
    """The linear solver in effect, for messages."""
    if stepper.linear == "fieldsplit":
        return "FGMRES with the fascicle Schur preconditioner, solver.linear: fieldsplit"
    return solver_options(stepper.petsc_options, stepper.prefix)
