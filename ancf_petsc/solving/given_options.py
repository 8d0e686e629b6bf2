"""PETSc options given in a run's options (its command line under the solver's prefix, else its
config's ``petsc:``) that explain a failed solve: a -snes_stol above the run's own, a -snes_type
other than Newton, a -snes_linesearch_damping below 1 (solver_messages.failure_detail)."""
from __future__ import annotations

from petsc4py import PETSc

from ..linalg.database import option
from ..linalg.option_syntax import parse_bool
from ..linalg.options import DEFAULT_OPTIONS, SolverOptionError
from .failure_cause import Detail
from .records import STALLED_STEP


def given_option(solver, name: str):
    """The value of the PETSc option ``name`` the run was given (the command line under the
    solver's prefix, else the config's ``petsc:``), or None where the run's own default holds."""
    given = option(name, getattr(solver, "prefix", ""))
    return getattr(solver, "petsc_options", {}).get(name) if given is None else given


def given_stol(solver) -> str:
    """For a solve stopped on its step length: a -snes_stol given (command line or ``petsc:``)
    above the run's own, which ends solves before |F| is small (-snes_stol 1e-3 on
    configs/bending_neohookean.yaml: 3 497 Newton iterations in 399 sub-steps instead of 36, and
    no word of it); empty otherwise."""
    given = given_option(solver, "snes_stol")
    own = float(DEFAULT_OPTIONS.get("snes_stol", 1e-12))
    try:
        given = float(given)
    except (TypeError, ValueError):
        return ""
    if given <= own:
        return ""
    return (f"; -snes_stol {given:g}, given in the run's options, ends a solve when a step is that "
            f"small beside the state: leave it out or give at most {own:g}")


def stalled_text(solver) -> str:
    """Why a solve that stopped on its step length failed: |F| above the tolerance, and a
    -snes_stol given above the run's own (the final message too: -snes_stol 1e-2 on
    configs/uniaxial_neohookean.yaml ended 'with STALLED_ABOVE_TOLERANCE' and no word of it)."""
    tol, method = solver.snes.getTolerances()[1], given_method(solver)
    if method:                                  # ksponly stops after its linear step
        return f" (|F| {solver.stalled_at:.2e} above the tolerance {tol:.1e}: {method})"
    return f" (stopped on the step length with |F| {solver.stalled_at:.2e} above the tolerance {tol:.1e}{given_stol(solver)})"


#: the failed solves whose cause a method given in the run's options is (``given_method``)
NEWTON_STOPS = (PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT, PETSc.SNES.ConvergedReason.DIVERGED_LINE_SEARCH,
                PETSc.SNES.ConvergedReason.DIVERGED_DTOL)
#: the nonlinear methods that take the tangent's Newton step
NEWTON_TYPES = ("newtonls", "newtontr", "vinewtonrsls", "vinewtonssls")


def given_method(solver) -> str:
    """A -snes_type other than Newton, a lagged Jacobian or preconditioner, or a
    -snes_linesearch_damping below 1, given in the run's options: the cause of its failed solves
    (on configs/uniaxial_neohookean.yaml ksponly ended 'with STALLED_ABOVE_TOLERANCE', damping 0.5
    was called 'a nearly singular tangent', ngmres 'the tangent does not predict the residual');
    empty otherwise."""
    kind = solver.snes.getType()
    if kind not in NEWTON_TYPES and given_option(solver, "snes_type") is not None:
        what = ("takes one linear step per solve and stops" if kind == "ksponly"
                else "is not Newton's method and did not converge here")
        return f"-snes_type {kind}, given in the run's options, {what}: leave it out (newtonls, the default)"
    lagged = [(name, lag) for name in ("snes_lag_jacobian", "snes_lag_preconditioner")
              if (lag := _integer(given_option(solver, name))) not in (None, 1)]
    if lagged:               # -2 on the elastica: 'a nearly singular tangent, as near a limit point'
        name, lag = lagged[0]
        return (f"-{name} {lag}, given in the run's options, keeps an old tangent over Newton's iterations, "
                "so its steps do not follow the residual: leave it out (solver.reuse_tangent takes chord "
                "steps only where they converge)")
    norms = given_option(solver, "snes_linesearch_norms")
    if norms is not None and parse_bool(norms) is False and solver.linesearch == "basic":
        # PETSc's basic line search then never measures |F| again: every solve 'stalled' at its
        # first |F| ('Newton stalls at |F| 4.55e-05 N ... more iterations do not help')
        return ("-snes_linesearch_norms false, given in the run's options, keeps the basic line search "
                "from measuring |F| after its steps, so the solve sees its first |F| for ever and cannot "
                "converge: leave it out")
    try:
        damping = float(given_option(solver, "snes_linesearch_damping"))
    except (TypeError, ValueError):
        return ""
    if damping >= 1.0 or solver.linesearch == "none":      # newtontr: no line search
        return ""
    return (f"-snes_linesearch_damping {damping:g}, given in the run's options, shortens every Newton step "
            f"to {damping:g} of itself, so |F| falls only linearly: leave it out (1, whole steps)")


def _integer(value) -> int | None:
    """An option's integer value, or None (not given, or not an integer)."""
    try:
        return int(value)
    except (TypeError, ValueError):
        return None


def given_cause(solver, reason: int) -> Detail | None:
    """The cause of a failed solve (SNES ``reason``) that an option given in the run's options
    is, as a failure message's part (failure_cause codes step_tolerance, nonlinear_method)."""
    if reason == STALLED_STEP and given_stol(solver):
        return Detail(stalled_text(solver), "step_tolerance")
    method = given_method(solver) if reason in (STALLED_STEP, *NEWTON_STOPS) else ""
    return Detail(f" ({method})", "nonlinear_method") if method else None


def first_load(loads, levels: list[float]) -> tuple[float, float]:
    """(λ, Σ_g |m_g(λ)| ‖f_g‖) of the first of ``levels`` with a load (petsc/loading.AppliedLoads),
    an upper bound of |F| at rest there; (0, 0) where a prescribed displacement moves first or
    nothing loads (collective: the vectors' norms)."""
    norms, moving = [f.norm() for f in loads.forces], [u.norm() > 0.0 for u in loads.moves]
    for lam in levels:
        m = loads.multipliers(lam)
        if any(mk != 0.0 and mv for mk, mv in zip(m, moving)):
            return 0.0, 0.0
        size = float(sum(abs(mk) * n for mk, n in zip(m, norms)))
        if size > 0.0:
            return lam, size
    return 0.0, 0.0


def check_given_atol(solver, levels: list[float]) -> None:
    """A -snes_atol given at or above |F| at rest at the first loaded level: the unloaded state
    meets it there, and the level is accepted without a Newton step (the paper's tendon at 2
    elements: -snes_atol 150 reported 100 N at zero displacement, 'completed'; -snes_atol 1000
    100 N at rest and 400 N 'passed over' at rest).  Refused (exit 2) with the run's own.  A
    restart (no ``levels``) goes on from a loaded state: not checked."""
    try:
        given = float(given_option(solver, "snes_atol"))
    except (TypeError, ValueError):
        return
    lam, size = first_load(solver.problem.loads, levels)
    if 0.0 < size <= given:
        raise SolverOptionError("", f"PETSc option -snes_atol {given:g}: at or above the loads of the first "
                                    f"level (load factor {lam:g}, {size:.4g} N): the unloaded state meets it, so "
                                    "the level would be accepted without a Newton step; give a tolerance well "
                                    f"below the loads, or leave it out (the run's own is {solver.own_atol:.1e})")


def rest_level_warning(solver, levels: list[float]) -> list[str]:
    """A warning when the loads of the first loaded level are within the residual's rounding at
    rest (at most 20 x |F(q0, 0)|, the floor of the run's own -snes_atol): the unloaded state
    meets the tolerance, and the level is reported at rest, zero displacements and 'completed'
    (configs/uniaxial_neohookean.yaml at 4.5e-11 N: every level; the paper's tendon at 4e-10 N
    first).  Not with a -snes_atol given (check_given_atol) or on a restart (no ``levels``)."""
    if given_option(solver, "snes_atol") is not None:
        return []
    lam, size = first_load(solver.problem.loads, levels)
    floor = 20.0 * solver.rounding_floor
    if not 0.0 < size <= floor:
        return []
    return [f"warning: the loads of the first level (load factor {lam:g}, {size:.3g} N) are within the "
            f"rounding of the elastic forces at rest (20 x |F(q0,0)| = {floor:.2g} N, the run's tolerance): "
            "the unloaded state meets them and the level is reported at rest; loads this small beside the "
            "model's stiffness are not resolved: check the units (N in loads, Pa in materials)"]

