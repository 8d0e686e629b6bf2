"""What the load stepper reports: SNES reason names, the failure of a load level, the record of
a converged level and the state of the load path (everything a restart needs)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from petsc4py import PETSc

REASONS = {getattr(PETSc.SNES.ConvergedReason, k): k
           for k in dir(PETSc.SNES.ConvergedReason) if not k.startswith("_")}
#: a converged step whose state is less stable than the last accepted one (more negative
#: tangent eigenvalues) is cut back, at most ``solver.stability_cutbacks`` times per load level;
#: then the less stable state is accepted (a genuine loss of stability)
UNSTABLE_STEP = -1000
REASONS[UNSTABLE_STEP] = "UNSTABLE_STATE"
#: SNES converged, but a contact projection of the final state did not (or the residual was NaN)
UNCLEAN_STATE = -1001
REASONS[UNCLEAN_STATE] = "PROJECTION_NOT_CONVERGED"
#: SNES stopped on the step length (CONVERGED_SNORM_RELATIVE) with the residual above the
#: absolute tolerance: not converged (a line search that no longer moves)
STALLED_STEP = -1002
REASONS[STALLED_STEP] = "STALLED_ABOVE_TOLERANCE"
#: SNES converged on a unilateral active set that the exact rule would change at the final state
#: (a multiplier pulls or a constraint penetrates beyond the tie tolerance): not an answer
VIOLATED_STATE = -1003
REASONS[VIOLATED_STATE] = "UNILATERAL_CONDITIONS_VIOLATED"


def reason_name(reason: int) -> str:
    return REASONS.get(reason, str(reason))


class LoadStepFailure(Exception):
    """A requested load level could not be reached; raised identically on every rank.
    ``code`` is the machine-readable reason (the SNES reason name, NEWTON_BUDGET_EXCEEDED, ...);
    ``cause`` what stopped the path, one of ``failure_cause.CAUSES`` (summary.json
    ``failure_cause``; by default the code in lower case)."""

    args: tuple             # (the message,): ``amend`` adds to it

    def __init__(self, target: float, attempted: float, reached: float, reason: str, inverted: bool,
                 detail: str = "", cause: str = ""):
        msg = (f"could not reach load factor {target:g}: SNES failed at load factor {attempted:.6g} "
               f"(last converged {reached:.6g}) with {reason}{detail}")
        if inverted:
            msg += " (an element was inverted, J <= 0)"
        super().__init__(msg)
        self.target, self.attempted, self.reached, self.reason = target, attempted, reached, reason
        self.code = reason.split()[0] if reason else "FAILED"
        self.inverted = inverted
        self.detail = detail      # the cause after the reason (``stepper._first_give_up`` repeats it)
        self.cause = cause or self.code.lower()

    def amend(self, detail: str) -> "LoadStepFailure":
        """The same failure with ``detail`` added to its message (what the stepper found after
        giving up: solving/critical_point.py)."""
        if detail:
            self.args = (self.args[0] + detail,)
        return self


@dataclass
class StepRecord:
    load_factor: float
    iterations: int           # Newton iterations summed over the sub-steps of this level
    substeps: int
    cutbacks: int
    reason: str               # reason of the final sub-step
    residual_norm: float
    wall_time: float
    iteration_history: list = field(default_factory=list)
    # negative eigenvalues of the last factored tangent on the constraint surface (inertia of
    # its LDLᵀ factor less one per contact constraint): 0 = a stable equilibrium, > 0 = a saddle;
    # None when the PC is not MUMPS LDLᵀ.  The tangent is that of the last Newton iterate, or of
    # the one before after a chord step (solver.reuse_tangent), a step of ~‖F‖ / k away
    negative_eigenvalues: int | None = None
    #: Tresca solves of friction's fixed point in its sub-steps (solving/newton.py: increments
    #: whose semi-smooth iteration failed, solved again with the bounds held); 0 normally
    tresca_solves: int = 0
    increment: float = 0.0          # the load increment the next level starts with
    last_increment: float = 0.0     # the last accepted one (secant predictor)
    #: a sub-step was accepted with its contact weights unsettled (residual_norm: with its own)
    weights_unsettled: bool = False
    #: switches to a stable branch at a bifurcation within this level (branch_switch.py reports)
    branch_switches: list = field(default_factory=list)
    #: (requested level, last converged, reported load factor) where the level lay in a gap of the
    #: load path without equilibrium and is reported past it (step_over.py); None normally
    passed_over: tuple | None = None


@dataclass
class PathState:
    """Where the load path is: the state, the last accepted increment of it and of the load,
    the next increment, and the stability of the last accepted state.  Everything a restart
    needs to continue exactly as an uninterrupted run would."""
    X: PETSc.Vec
    dX_last: PETSc.Vec
    lam: float
    dlam: float
    dlam_last: float
    accepted_negative: int = 0
    #: Newton iterations spent before it: a restart's levels on disk (the budget is the run's)
    spent: int = 0


def restored_records(point) -> list[StepRecord]:
    """The levels a restarted run continues after (``io.restart.RestartPoint``'s summary entries)
    as StepRecords: the run's status and counts cover every level on disk, not the restarted
    process's alone (an unstable run restarted read ``completed``)."""
    if point is None:
        return []
    out = []
    for e in point.summary.get("steps") or []:
        passed = e.get("passed_over")
        out.append(StepRecord(
            e["load_factor"], e.get("iterations", 0), e.get("substeps", 0), e.get("cutbacks", 0),
            e.get("reason", ""), e.get("residual_norm", 0.0), e.get("wall_time", 0.0),
            negative_eigenvalues=e.get("negative_eigenvalues"),
            weights_unsettled=bool(e.get("weights_unsettled")),
            branch_switches=list(e.get("branch_switches") or []),
            passed_over=None if not passed else (passed["level"], passed["last_converged"], passed["reported_at"])))
    return out


def spent_before(point) -> int:
    """The Newton iterations of the levels a restarted run continues after (each level's count
    includes its cut-back attempts): what an uninterrupted run had spent there."""
    return sum(r.iterations for r in restored_records(point))


def restart_increment(point, levels: list[float], say=lambda *_: None) -> float:
    """A restart's next load increment: the stored one, unless it is not > 0 (a results.h5
    written before f0a0e19 for a level passed over with the one before it, or edited), which
    stepped by 0 forever at the last converged level; then the last accepted increment, else
    the way to the next level (said in the log)."""
    dlam = point.increment
    if math.isfinite(dlam) and dlam > 0.0:
        return dlam
    last = point.last_increment
    ok = math.isfinite(last) and last > 0.0
    ahead = [lv - point.load_factor for lv in levels if lv > point.load_factor]   # not one passed over
    new = last if ok else (ahead[0] if ahead else 1.0)
    say(f"[ancf] restart: results.h5 steps/step_{point.step:04d}/restart gives the next load increment "
        f"{dlam:g} (not > 0); going on with {new:g}, the {'last accepted increment' if ok else 'way to the next level'}")
    return new
