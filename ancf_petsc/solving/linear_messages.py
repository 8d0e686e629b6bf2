"""What a failed level says about its linear solver: why a linear solve failed and what works
instead, a preconditioner applied once where a solve was meant, the linear solver in effect."""
from __future__ import annotations

import math

from petsc4py import PETSc

from ..linalg.diagnostics import mumps_hint, solver_hint
from ..linalg.inertia import mumps_error
from ..linalg.options import FIELDSPLIT_OPTIONS, factor_package, solver_options
from .failure_cause import Detail
from .given_options import given_option


#: what works on the saddle-point Jacobian of a model with contact multipliers (measured on
#: configs/achilles_type3_psi45.yaml, docs/running.md)
SADDLE_POINT_HINT = ("a contact model's Jacobian is a saddle-point matrix (a zero block for the "
                     "multipliers): only a pivoting direct solver factors it, the default (-pc_type cholesky, "
                     "MUMPS LDLᵀ) or -pc_type lu (MUMPS); Krylov methods with gamg, hypre, bjacobi, asm, ilu or "
                     "jacobi and the factorisations of PETSc and SuperLU_DIST fail on it")


#: what works instead of ``-snes_mf`` (measured on the two-element bar of tests/apps/test_edges.py
#: and configs/achilles_type3_psi45.yaml: -snes_mf_operator -ksp_type gmres converges like the
#: default; -snes_mf -ksp_type gmres solves the bar but did not reach the contact model's first
#: level in 5 minutes)
MF_OPERATOR = ("-snes_mf_operator -ksp_type gmres (GMRES on matrix-free products, preconditioned by "
               "the factored assembled Jacobian)")
MF_NO_MATRIX = "-snes_mf leaves no matrix to precondition with, so PETSc sets -pc_type none"


def matrix_free(snes: PETSc.SNES) -> bool:
    """Whether the SNES runs matrix-free without a preconditioning matrix (``-snes_mf``; not
    ``-snes_mf_operator``, which keeps the assembled Jacobian for the preconditioner)."""
    P = snes.getJacobian()[1]
    return P is not None and P.getType() == PETSc.Mat.Type.MFFD


#: share of the residual a Newton step may leave in its linear equations (an exact solve: rounding)
INEXACT_STEP = 1e-6
#: preconditioners that solve the Newton equations under -ksp_type preonly (none: its own message)
SOLVING_PCS = ("lu", "cholesky", "python", "none", "redundant")


def applied_once(solver) -> Detail | None:
    """Under -ksp_type preonly (the default) a preconditioner that is no factorisation (jacobi,
    gamg, bjacobi or asm on several ranks, ...) is applied once instead of solving, so the steps
    are no Newton steps: -pc_type jacobi on the 2-element cantilever failed as 'Newton's iterates
    wander ... as near a limit or bifurcation point', -pc_type gamg as 'a nearly singular
    tangent', and on the paper's tendon jacobi's steps inverted an element.  Measured: ‖J y − b‖ /
    ‖b‖ for y the preconditioner applied to b, the last residual (J·1 where that is not finite),
    once, at a failure only; None where that is rounding (ILU of a beam's banded tangent on one
    rank is its LU).  None without a solver (a failure named from its reason alone).  Collective."""
    if solver is None:
        return None
    ksp = solver.snes.getKSP()
    pc = ksp.getPC()
    if ksp.getType() != "preonly" or pc.getType() in SOLVING_PCS:
        return None
    J, F = ksp.getOperators()[0], solver.snes.getFunction()[0]
    b, y, r = F.copy(), F.duplicate(), F.duplicate()
    try:
        if not 0.0 < b.norm() < math.inf:           # an inverted element's NaN: J's own range
            y.set(1.0)
            J.mult(y, b)
        pc.apply(b, y)
        J.mult(y, r)
        r.axpy(-1.0, b)
        share = r.norm() / b.norm()
    except (PETSc.Error, ZeroDivisionError):
        return None
    finally:
        for v in (b, y, r):
            v.destroy()
    if not share > INEXACT_STEP:                # also NaN: nothing measured
        return None
    name = pc.getType()
    instead = (SADDLE_POINT_HINT if solver.problem.contact is not None else
               f"add -ksp_type gmres to solve them with -pc_type {name}, or use a factorisation, the "
               "default (-pc_type cholesky, MUMPS LDLᵀ) or -pc_type lu")
    return Detail(f" (-pc_type {name} with -ksp_type preonly is applied once instead of solving the Newton "
                  f"equations: its steps leave |J step - F| = {share:.2g} |F|, so Newton converges slowly or not "
                  f"at all; {instead})", "linear_solver")


def linear_solver_detail(solver, reason: int) -> str:
    """Why a DIVERGED_LINEAR_SOLVE happened and what works (empty for other reasons)."""
    if reason != PETSc.SNES.ConvergedReason.DIVERGED_LINEAR_SOLVE:
        return ""
    kreason = {getattr(PETSc.KSP.ConvergedReason, k): k for k in dir(PETSc.KSP.ConvergedReason)
               if not k.startswith("_")}.get(solver.ksp_reason, str(solver.ksp_reason))
    infog1 = mumps_error(solver.snes.getKSP())
    if solver.linear == "fieldsplit":
        hint = "solver.linear: direct factors the whole Jacobian instead"
    elif matrix_free(solver.snes):
        hint = f"{MF_NO_MATRIX}; use {MF_OPERATOR}, or leave out -snes_mf"
    elif infog1 is not None:
        hint = mumps_hint(infog1)
    elif solver.problem.contact is not None:
        hint = SADDLE_POINT_HINT
    else:
        pc, factor = factor_package(solver.petsc_options, solver.prefix, solver.problem.symmetric)
        hint = solver_hint(pc, factor, solver.problem.comm.size, PETSc.Sys.hasExternalPackage)
    return f" (the linear solver {solver_text(solver)} stopped with {kreason}; {krylov_budget(solver)}{hint})"


def solver_text(solver) -> str:
    """The linear solver in effect, for messages."""
    if solver.linear == "fieldsplit":
        return "FGMRES with the fascicle Schur preconditioner, solver.linear: fieldsplit"
    if matrix_free(solver.snes):
        return f"-snes_mf -ksp_type {solver.snes.getKSP().getType()} (no preconditioner)"
    return solver_options(solver.petsc_options, solver.prefix, solver.problem.symmetric)


def krylov_budget(solver) -> str:
    """A -ksp_max_it given below the Krylov method's own budget (PETSc's 10 000, the fascicle
    solver's 100) that the linear solve ran out of, as the start of a hint (empty otherwise):
    -ksp_max_it 2 on the 7-fascicle bundle was told only 'solver.linear: direct factors the whole
    Jacobian instead'."""
    if solver.ksp_reason != PETSc.KSP.ConvergedReason.DIVERGED_MAX_IT:
        return ""
    try:
        given = int(given_option(solver, "ksp_max_it"))
    except (TypeError, ValueError):
        return ""
    own = int(FIELDSPLIT_OPTIONS["ksp_max_it"]) if solver.linear == "fieldsplit" else 10000
    return (f"-ksp_max_it {given}, given in the run's options, is below the linear solver's own {own}: it ran "
            "out of the iterations given; leave it out or raise it, or " if given < own else "")
