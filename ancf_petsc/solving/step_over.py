"""A level inside a band of load factors where the discrete model has no equilibrium, reported at
the first converged state just past it (a last resort of the stepper: stepper.py ``last_resorts``).

Where the residual jumps (continuity.py: a contact point whose closest point passes a C⁰ edge of
B's surface, two closest places, a fade weight's jump), the load path can have a gap: no state
solves F = 0 for the load factors inside it.  Measured on the second subject's sliding 30°
soleus-biased column (4 elements): no equilibrium from 2499.64 N (loading) nor down to 2500.15 N
(unloading from 2500.5 N), so the level of 2500 N lies inside the gap, and the stepper crept up
to it in 28 halvings; a step from 2000 N to 2500.5 N, 2550 N or 2700 N converges and the column
reaches 3 kN.  Of the envelope's columns that stopped this way, those whose level lay in such a
gap (the 8-element 135° soleus-biased unilateral column at 1199.42 N, μ = 0.1 at 150° at
2999.32 N) complete with the level 1 N later, and with this step over.  A level whose sub-steps
failed ``CREEP_FAILURES`` times at the level itself is stepped over as soon as the failed attempt
shows the jump (``creeping``), not after every halving: that column 564 → 233 Newton iterations,
μ = 0.1 at 150° 2 985 → 427.  The cure of the kink is
a C¹ partner surface (not built); until then the level is reported where the path continues,
beyond the gap, with its own load factor, and the run says so (summary ``passed_over``, reason
code LEVELS_PASSED_OVER).  Docs: docs/running.md, "Levels in a gap of the load path".
"""
from __future__ import annotations

from dataclasses import replace

from petsc4py import PETSc

from .failure_cause import JUMP_CAUSES
from .records import StepRecord

#: the load factors tried past the level, as shares of the level's own increment, in turn (the
#: second subject's sliding 165° gastrocnemius-biased column, no equilibrium from 1597.57 N on,
#: needs the last: 1600 N is reported at 1640 N, 10 % of its 400 N increment past it)
STEP_OVER = (1e-3, 1e-2, 1e-1)

#: failed sub-steps at the level itself after which a jump of the residual is looked for and the
#: level stepped over at once (``creeping``): each failure halves the increment, and a level in a
#: gap took 28 of them, 494 Newton iterations, before its give-up (the second subject's sliding
#: 30° soleus-biased column; μ = 0.1 at 150°: 2 868)
CREEP_FAILURES = 8


def creeping(stepper, tally, at_level: bool) -> bool:
    """Count a failed sub-step (``at_level``: one that ended at the level itself); True from the
    level's ``CREEP_FAILURES``-th such failure on: its path is creeping into a gap at the level,
    and a jump of the residual in a failed attempt steps over at once (stepper.py ``_cut_back``)
    rather than after every halving down to the give-up.  The same on every rank."""
    tally.at_level_failures += at_level
    return bool(stepper.spec.step_over_jumps) and tally.at_level_failures >= CREEP_FAILURES


def reported_level(target: float, reason: int, fnorm: float, tally, snes, lam: float) -> tuple[float, int, float]:
    """The level's load factor, SNES reason and |F| as reported: the level's own (its state's
    polished for the stability verdict: ``tally.polished``, critical_point.verdict_count), or
    where it was stepped over (``tally.passed_over``), that solve's.  A level that ends on a
    branch switch's state (at ``lam``) has the switch's settling solve's, the last of ``snes``
    (branch_switch.py ``_keep``), not the failed attempt's before it."""
    if tally.switches and tally.switches[-1]["load_factor"] == lam:
        reason, fnorm = snes.getConvergedReason(), snes.getFunctionNorm()
    over = tally.passed_over
    own = fnorm if tally.polished is None else tally.polished
    return (target, reason, own) if not over else tuple(over[1:])


def applies(stepper, failure) -> bool:
    """Whether a give-up ``failure`` (records.LoadStepFailure) is stepped over: on in the config
    (``solver.step_over_jumps``) and the failure a jump of the residual (the same on every rank)."""
    return bool(stepper.spec.step_over_jumps) and failure.cause in JUMP_CAUSES


def step_over(stepper, path, X_prev: PETSc.Vec, target: float, tally, failure) -> bool:
    """From the last converged state (``path``, also in ``X_prev``), solve at load factors just
    past ``target`` (``STEP_OVER``); accept the first that converges to a state no less stable
    than the last, recording (last converged, reported load factor, its reason, its |F|) in
    ``tally.passed_over``.  False (the last converged state and load factor restored) when none
    does or the failure is no jump.  Collective."""
    P = stepper.problem
    if not applies(stepper, failure):
        P.load_factor = path.lam
        return False
    span = target - tally.start
    for share in STEP_OVER:
        lam = target + share * span
        if P.loads.unchanged(target, lam):           # past a history's last frame: the level itself
            continue
        X_prev.copy(P.X)
        P.restore()
        reason, its, fnorm = stepper.solve_at(lam, P.X, lam, path.lam)
        tally.its += its
        reason, neg = stepper.judge(path, reason, fnorm, lam - path.lam, tally)
        if reason > 0:
            tally.passed_over = (path.lam, lam, reason, fnorm)
            stepper.log(f"  load factor {target:g}: not reached from {path.lam:.6g} ({failure.cause}: "
                        f"the residual jumps); past it at {lam:.6g}, {its} Newton iterations: the level is "
                        "reported there (solver.step_over_jumps)")
            stepper.accept(path, X_prev, lam - path.lam, its, neg, tally)
            path.dlam = max(path.dlam, tally.increment)
            return True
    X_prev.copy(P.X)
    P.restore()
    P.load_factor = path.lam
    return False


def behind(stepper, path, target: float, last) -> StepRecord | None:
    """A level the last one's step over has passed already (its reported load factor, up to
    ``STEP_OVER[-1]`` of its own increment late, lies beyond this level too): reported at the
    same state, passed over from the same last converged state, with no work of its own (the
    while loop of stepper.py ``_reach`` had nothing to solve and no reason to report).  None for
    a level ahead of the path."""
    if path.lam < target * (1.0 - 1e-14) or last is None or not last.passed_over:
        return None
    stepper.log(f"  load factor {target:g}: passed over too by the step over of {last.passed_over[0]:g}, "
                f"reported at {path.lam:.6g} with it (solver.step_over_jumps)")
    return replace(last, iterations=0, substeps=0, cutbacks=0, tresca_solves=0, wall_time=0.0,
                   iteration_history=[], branch_switches=[], increment=path.dlam, last_increment=path.dlam_last,
                   passed_over=(target, last.passed_over[1], last.load_factor))


def sentence(passed: list) -> str:
    """The final message's part for the levels reported past a gap: [(level, last converged,
    reported)]; empty without any."""
    if not passed:
        return ""
    parts = ", ".join(f"{lv:g} at {at:.6g} (not reached from {fr:.6g})" for lv, fr, at in passed)
    return (f"{len(passed)} level(s) not reached where the residual jumps (a gap of the load path "
            "without equilibrium, e.g. at a C0 edge of B's surface: docs/running.md, "
            f"\"Levels in a gap of the load path\") and reported just past it: {parts}")
