"""The load solver's messages: its solver in one line, and why a level failed with what to try
instead (the linear solver's part: linear_messages.py)."""
from __future__ import annotations

from petsc4py import PETSc

from ..config.specs import SolverSpec
from ..linalg.options import DEFAULT_OPTIONS
from .failure_cause import Detail
from .given_options import given_cause, given_option, stalled_text
from .linear_messages import (MF_NO_MATRIX, MF_OPERATOR, SADDLE_POINT_HINT, applied_once,  # noqa: F401
                              linear_solver_detail, matrix_free, solver_text)
from .records import STALLED_STEP, UNSTABLE_STEP, VIOLATED_STATE


def describe(solver) -> str:
    """The solver in one line (the run's header)."""
    ksp = solver.snes.getKSP()
    pc = ksp.getPC()
    ls = solver.linesearch + (" (the whole step first)" if solver.full_step_first is not None else "")
    name, extra = pc.getType(), ""
    if name in ("lu", "cholesky"):
        extra = f" ({pc.getFactorSolverType()})"
    if solver.linear == "fieldsplit":
        extra = " (fascicle Schur: dense fascicle factors, MUMPS LDLT on the multipliers)"
    elif name == "python":                      # linalg/compact_factor.py
        name = "cholesky" if pc.getPythonContext().symmetric else "lu"
        extra = " (mumps, of the Jacobian's structural nonzeros)"
    rtol, atol, stol, maxit = solver.snes.getTolerances()
    return (f"SNES {solver.snes.getType()} line search {ls}; KSP {ksp.getType()} PC "
            f"{name}{extra} on {solver.problem.matrix_type.upper()}; rtol {rtol:.1e} atol {atol:.1e} "
            f"stol {stol:.1e} max_it {maxit}; "
            f"rounding floor |F(q0,0)| {solver.rounding_floor:.1e}"
            + ("; chord steps near convergence" if solver.spec.reuse_tangent else "")
            + (_turns_text(solver) if solver.spec.section_update == "rotation" else "")
            + (_band_text(solver) if solver.spec.band_step > 0.0 else "")
            + ("; tangent: mixed (initial stress of the linearised strain)" if solver.problem.mixed else ""))


def _turns_text(solver) -> str:
    """What ``solver.section_update: rotation`` does in this run (step_limits.StepLimits.configure)."""
    if solver.problem.limits.turns is not None:
        return "; Newton steps turn the sections"
    return ("; Newton steps not turned (solver.section_update: rotation needs full steps, "
            f"line search {solver.linesearch})")


def _band_text(solver) -> str:
    """What ``solver.band_step`` does in this run (step_limits.StepLimits.configure): nothing
    without contact or where a line search scales the steps (friction's l2)."""
    if solver.problem.limits.band_step > 0.0:
        return f"; Newton steps held to {solver.spec.band_step:g} fade-band widths"
    why = "no contact" if solver.problem.contact is None else f"line search {solver.linesearch}"
    return f"; Newton steps not held to the fade bands (solver.band_step needs full steps with contact, {why})"


def floor_detail(step: float, lam: float, floor: float) -> Detail:
    """The cause of a level given up at its first failure: half the failed step is below
    ``solver.min_increment`` (``floor``), so no smaller step was tried (load_control.floored)."""
    return Detail(f" (no cut-back was tried: half the failed step from load factor {lam:.6g} to {lam + step:.6g} "
                  f"is {0.5 * step:.4g}, below solver.min_increment = {floor:g}; lower solver.min_increment "
                  f"to at most {0.5 * step:.4g} (the default is {SolverSpec.min_increment:g}, times the largest load "
                  "factor where that is below 1) so that the step "
                  "can be cut back)", "min_increment")


def stability_detail(unstable_at: tuple[float, int, int] | None) -> str:
    """The cause of a failure after a stability retry in the same level: a sub-step on the way
    converged to a state whose tangent had more negative eigenvalues than the last accepted one,
    so the path nears a limit or bifurcation point that load control cannot pass."""
    if unstable_at is None:
        return ""
    lam, neg, before = unstable_at
    return (f"; on the way, a converged state at load factor {lam:.6g} had {neg} negative tangent "
            f"eigenvalue(s) against {before} at the last accepted one: the path nears a limit or "
            f"bifurcation point, which load control cannot pass (smaller increments, -snes_max_it "
            f"or another predictor may find another branch)")


def switch_line(report: dict) -> str:
    """The log line of a branch switch or a snap (branch_switch.py's report)."""
    how = (f"total potential {report['potential_drop']:.3g} J below the {_left(report)}'s, the lower of "
           f"{report['sides']} side(s)" if "potential_drop" in report
           else f"the smaller jump of {report['sides']} side(s)")
    move = (f"perturbed by {report['sign'] * report['amplitude'] * 1e3:+.3g} mm, Newton reached a state with "
            f"{report['negative_after']}, {report['jump'] * 1e3:.3g} mm away ({how}; {report['iterations']} "
            "Newton iterations)")
    if "critical_load_factor" in report:
        return (f"  snap past a critical point at load factor {report['critical_load_factor']:.6g} (its "
                f"tangent's smallest scaled eigenvalue {report['critical_share']:.1e} of the next; load control "
                f"found no equilibrium beyond it): along that mode at load factor {report['load_factor']:.6g}, "
                f"{move}")
    return (f"  branch switch at load factor {report['load_factor']:.6g}: the state there had "
            f"{report['negative_before']} negative tangent eigenvalue(s); along its critical mode "
            f"(eigenvalue {report['eigenvalue']:.3g}), {move}")


def _left(report: dict) -> str:
    return "critical state" if "critical_load_factor" in report else "unstable state"


def switched_message(reports: list[dict]) -> str:
    """The final message of a run that switched branch or snapped (branch_switch.py's reports)."""
    snaps = [r["critical_load_factor"] for r in reports if "critical_load_factor" in r]
    switches = [r["load_factor"] for r in reports if "critical_load_factor" not in r]
    parts = []
    if switches:
        parts.append(f"switching branch {len(switches)} time(s) at a bifurcation (load factor "
                     f"{', '.join(f'{x:g}' for x in switches)}): load control met an unstable state and "
                     "could not pass it; the path went on from a stable state along its critical mode")
    if snaps:
        parts.append(f"snapping {len(snaps)} time(s) past a critical point (load factor "
                     f"{', '.join(f'{x:g}' for x in snaps)}): load control found no equilibrium just beyond "
                     "it; the path went on from a stable state reached along its critical mode (a jump)")
    return ("completed, " + "; ".join(parts) + " (summary.json steps[].branch_switches; "
            "solver.branch_switch: false stops there instead)")


def reachable_tolerance(solver) -> float:
    """The smallest |F| Newton can be held to: 20 x the residual's rounding floor, as the run's
    own absolute tolerance (below it a change of F is rounding, not a jump of the residual)."""
    return 20.0 * getattr(solver, "rounding_floor", 0.0)


def unreachable_atol(solver) -> Detail | None:
    """A -snes_atol (command line or ``petsc:``) below ``reachable_tolerance``: the cause of a
    solve stalled above it (-snes_atol 1e-14 on configs/bending_neohookean.yaml, floor 4.9e-11:
    12 cut-backs, then blamed on a 2.4e-11 N 'discontinuity of the discrete model')."""
    atol, least = solver.snes.getTolerances()[1], reachable_tolerance(solver)
    given = given_option(solver, "snes_atol")
    # the run's own atol is at least ``least`` up to its rounding (max(1e-10 load, 20 floor)):
    # a shear-lag run at k_t = 1e12 Pa/m was told its own 3.1e-12 was "given in the run's options"
    if given is None or atol >= least * (1.0 - 1e-9):
        return None
    return Detail(f" (-snes_atol {atol:.1e}, given in the run's options, is below 20 x the residual's rounding "
                  f"floor |F(q0,0)| {solver.rounding_floor:.1e}: Newton's |F| cannot get that small; leave "
                  f"-snes_atol out or give at least {least:.1e})", "unreachable_tolerance")


def failure_detail(solver, reason: int) -> Detail:
    """What to try after a failed level: the linear solver's reason and what works, a
    preconditioner that solves nothing, a -snes_atol below rounding, or a Newton budget too
    small for an active set; its ``kind`` the cause's code (failure_cause.py)."""
    linear = PETSc.SNES.ConvergedReason.DIVERGED_LINEAR_SOLVE    # or failed linear solves let through
    if reason == linear or (getattr(solver, "ksp_reason", 0) < 0 and reason in (STALLED_STEP, PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT)):
        return Detail(linear_solver_detail(solver, linear), "linear_solver")
    unreachable = (unreachable_atol(solver)
                   if reason in (STALLED_STEP, PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT) else None)
    unreachable = unreachable or given_cause(solver, reason) or applied_once(solver)
    if unreachable is not None:
        return unreachable
    if reason == VIOLATED_STATE:
        return Detail(" (the solves converged on active sets with a multiplier pulling or a gap penetrating "
                      "at their states, which are no answers of unilateral contact)", "violated_state")
    if reason != PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT:
        return Detail("")
    ksp = solver.snes.getKSP()
    if ksp.getType() == "preonly" and ksp.getPC().getType() == "none":
        if matrix_free(solver.snes):
            return Detail(f" ({MF_NO_MATRIX}, and with -ksp_type preonly every Newton step is the residual "
                          f"itself; for matrix-free products use {MF_OPERATOR}, or add -ksp_type gmres "
                          "(unpreconditioned: slow, and on a contact model's saddle-point Jacobian unlikely "
                          "to converge))", "linear_solver")
        return Detail(" (-pc_type none with -ksp_type preonly solves nothing: every Newton step is the residual "
                      "itself; drop -pc_type none" + ("" if solver.problem.contact is None else
                                                     f"; {SADDLE_POINT_HINT}") + ")", "linear_solver")
    contact = solver.problem.contact
    friction = friction_why(contact)
    cycle = newton_cycle(solver.last_solve_history)
    if cycle is not None:
        period, low, high = cycle
        if period == 1:
            return Detail(f" (Newton stalls at |F| {high:.2e} N, above the tolerance "
                          f"{solver.snes.getTolerances()[1]:.1e}: more iterations do not help{friction})",
                          "newton_stall")
        return Detail(f" (Newton cycles: |F| repeats every {period} iterations, between {low:.1e} and "
                      f"{high:.1e} N, so more iterations do not help{friction})", "newton_cycle")
    budget = small_newton_budget(solver)
    if budget is not None:
        return budget
    if friction:
        return Detail(f" ({friction.removeprefix('; ')})", "friction_statuses")
    if contact is not None and contact.law.decides_activity:
        maxit, stop = solver.snes.getTolerances()[3], solver.cycle_stop
        if stop is not None and stop.wandered:
            h = solver.last_solve_history
            # with auto the run switched to them where it could (solving/fade_switch.py)
            hint = ("; at large twist, contact.fade_forces: auto or pointwise may converge where the fade "
                    "bands' forces stall Newton (docs/contact.md)"
                    if contact.spec.fade_forces == "variational" and contact.weights.rule == "newton" else "")
            return Detail(f" (unilateral contact: Newton found no |F| below {min(h):.2e} N in its last "
                          f"{stop.window} iterations, so the solve ended: more iterations are unlikely to "
                          f"help{hint})", "newton_wander")
        return Detail(f" (unilateral contact changes its active set within a level and may need more than "
                      f"-snes_max_it {maxit} Newton iterations: try -snes_max_it {4 * maxit})",
                      "active_set_iterations")
    return newton_course(solver.last_solve_history, solver.snes.getTolerances()[3])


def small_newton_budget(solver) -> Detail | None:
    """A solve out of iterations under a -snes_max_it (command line or config ``petsc:``) below
    the run's own budget (15, unilateral contact 60, friction 200): the budget given is the
    cause, whatever the model does (with -snes_max_it 3 a friction column blamed μ)."""
    given = given_option(solver, "snes_max_it")
    laws = getattr(solver.problem, "solver_defaults", None) or {}
    own = int(laws.get("snes_max_it", DEFAULT_OPTIONS["snes_max_it"]))
    try:
        given = int(given)
    except (TypeError, ValueError):
        return None
    if given >= own:
        return None
    return Detail(f" (-snes_max_it {given}, given in the run's options, is below the run's own {own}: the "
                  f"solve ran out of the iterations given; leave it out or raise it)", "newton_budget")


#: iterations at the end of a solve whose course ``newton_course`` describes
COURSE_WINDOW = 6


def newton_course(history: list[float], maxit: int) -> Detail:
    """How a solve that ran out of iterations moved, when it neither cycled nor stalled: |F|
    falling in every one of the last ``COURSE_WINDOW`` iterations (Newton converging only
    linearly: a nearly singular tangent) or not (wandering).  Measured on a traced subject's
    sliding column (twist 120°, 2.57 kN, docs/gait.md): |F| × 0.13–0.28 per iteration on
    small increments, wandering at 0.03–8 N on larger ones, and with -snes_max_it 30 the state
    beyond had a negative tangent eigenvalue: a limit or bifurcation point."""
    if len(history) < COURSE_WINDOW + 1:
        return Detail("")
    tail = history[-(COURSE_WINDOW + 1):]
    ratios = [b / a for a, b in zip(tail, tail[1:]) if a > 0.0]
    advice = (f"a smaller solver.max_increment or -snes_max_it {3 * maxit} may reach a state "
              "whose stability check then says whether a limit or bifurcation point is ahead")
    if len(ratios) == COURSE_WINDOW and max(ratios) < 1.0:
        return Detail(f" (Newton converges only linearly here, |F| x {min(ratios):.2f}-{max(ratios):.2f} per "
                      f"iteration down to {tail[-1]:.1e} N: a nearly singular tangent, as near a limit or "
                      f"bifurcation point; {advice})", "newton_linear")
    return Detail(f" (Newton's iterates wander: |F| between {min(tail):.1e} and {max(tail):.1e} N over the "
                  f"last {COURSE_WINDOW + 1} iterations, neither converging nor repeating: the tangent does "
                  f"not predict the residual over these steps, as near a limit or bifurcation point or where "
                  f"the residual is not smooth; {advice})", "newton_wander")


#: why a friction increment fails (docs/interface.md, "Limits")
FRICTION_WHY = ("; friction: the stick-slip statuses of the tangential functions flip from iterate "
                "to iterate and do not settle, and the Tresca fixed point did not contract; with a "
                "large friction coefficient the quasi-static incremental problem need not have a "
                "unique solution near this path (docs/interface.md, Limits): another increment "
                "(solver.max_increment) or mu may pass")


def friction_why(contact) -> str:
    """FRICTION_WHY for a model with Coulomb friction (else ""), naming its augmentation c: the
    pressed strips at c = 1e3 or 1e6 cycle at the first reversal, where c = 0.1 passes."""
    bounded = [t for t in getattr(contact, "terms", ()) if t.bounded]
    if not bounded:
        return ""
    c = max(getattr(t, "augmentation", 0.0) for t in bounded)
    return (FRICTION_WHY[:-len(" may pass")] + ", or a smaller contact.tangential.augmentation "
            f"(c = {c:g} here; it steers Newton's iteration) may pass")
#: relative agreement of |F| one period apart that counts as a repeat (a Newton cycle): 1e-3 missed
#: the period-5 cycle of the soleus-biased unilateral stride at ψ = 90° (2.35 kN, frame 46.8 of
#: the gait envelope), whose norms drift by up to 1.8e-3 per period while raising -snes_max_it to
#: 30 does not help; a converging or slowly contracting Newton never matches p + 2 norms to 1 %
CYCLE_TOL = 1e-2
#: the longest cycle looked for
MAX_PERIOD = 8


def newton_cycle(history: list[float]) -> tuple[int, float, float] | None:
    """(period, min, max |F|) when the last p + 2 residual norms of a solve repeat those one period
    earlier to ``CYCLE_TOL`` (period 1: |F| stalled), else None (Newton still moving)."""
    h = history
    for p in range(1, MAX_PERIOD + 1):
        n = p + 2                               # one period and two more iterates compared
        if len(h) < n + p:
            break
        tail = h[-(n + p):]
        if all(abs(tail[k] - tail[k + p]) <= CYCLE_TOL * max(tail[k], tail[k + p]) for k in range(n)):
            return p, min(h[-p:]), max(h[-p:])
    return None


def unsettled_message(unsettled: list[float], levels: int) -> str:
    """The final message's part for levels accepted with their contact weights unsettled (their
    load factors; empty without any)."""
    if not unsettled:
        return ""
    return (f"contact weights not settled at {len(unsettled)} of {levels} levels (load factor "
            f"{', '.join(f'{x:g}' for x in unsettled)}; their residual_norm is |F| with the state's own "
            "weights): contact.fade: newton solves for them")


def attempt_why(solver, reason: int, neg, inverted: bool, lost: bool, accepted_negative) -> str:
    """What went wrong with a failed sub-step, for its cut-back line in the log."""
    if reason == STALLED_STEP:
        return stalled_text(solver)
    if reason == UNSTABLE_STEP:
        return f" ({neg} negative tangent eigenvalue(s), the last state had {accepted_negative})"
    if reason == VIOLATED_STATE:
        return " (converged with a multiplier pulling or a gap penetrating: the exact rule would change the status)"
    return " (inverted element)" if inverted else (" (contact projection lost)" if lost else "")


def tresca_line(lam: float, bound_updates: int, reason: int, its: int) -> str:
    """The log line of a solve that friction's semi-smooth iteration failed (newton.py's Tresca problems)."""
    return (f"  load factor {lam:.6g}: friction's semi-smooth iteration failed; solved again "
            f"through {bound_updates} Tresca problems (bounds held): "
            f"{'converged' if reason > 0 else 'failed'}, {its} Newton iterations in all")


def unsettled_line(lam: float, updates: int, fnorm: float) -> str:
    """The log line of a level accepted with its contact weights unsettled (contact/weights.py)."""
    return (f"  contact weights not settled at load factor {lam:.6g} after {updates} updates: "
            f"|F| with the state's own weights {fnorm:.2e} (contact.fade: newton solves for them)")
