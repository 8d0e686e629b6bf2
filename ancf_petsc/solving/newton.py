"""The Newton solves of one load increment: the contact law's phases around SNES.

Without contact, or with sliding contact, an increment is one SNES solve.  A law that decides
which constraints are active (unilateral) solves an increment by a Josephy–Newton iteration
when the complementarity predictor applies (petsc/complementarity.py, up to its size):

1. the linearised complementarity problem is solved exactly at the increment's start (the secant
   predictor's state): its solution sets the status and the first step;
2. one SNES solve keeps that status (one active set's smooth problem: quadratic convergence);
3. at the converged state the exact rule checks the status (``Contact`` evaluates it; no change:
   the state satisfies the exact conditions, done); otherwise the predictor is solved again
   there, and so on, at most ``MAX_PREDICTIONS`` times.

**A settled active set.**  Where the last ``SETTLED_INCREMENTS`` increments' predictions and checks
changed no status (a stride's loading frames: 57 of the 60 predictions of the 45° uniform
unilateral stride changed none), the increment is solved with the status kept first, from the
load predictor's state, and predicted only where the check then changes it or that solve fails
(without a prediction then, the phases).  With the status unchanged the Josephy–Newton step is
the saddle-point Newton step of that active set, which the SNES's first iteration takes for the
price of one iteration instead of the predictor's linearisation (the held Jacobian, a
factorisation of K, a solve per multiplier): the same residuals, one iteration later
(docs/gait.md, "Frames per second").  The check itself reads the status from the converged
solve's last evaluation at that state (``contact.decide_kept``), evaluating again only where the
rule changes it.  Where that solve fails and the prediction made then changes no status, the
prediction's step is the failed solve's first, and its solve is not made again (``_repeats``).

Measured over the unilateral grid (scripts/bench_contact_grid.py, docs/contact.md) this finds
the contact state of an increment in one prediction in most increments and two in the others,
where the status rule inside Newton's iteration took several phases of several iterations each.

**The weights from rest.**  The first solve from rest keeps the fade weights (contact/weights.py);
after it they are brought up to date, and when one changed the next prediction linearises them with
the status (one Josephy–Newton step for both), instead of a further solve for the weights once the
status has settled (gait envelope, twist 60-90 deg: the first level 17-20 → 10-13 iterations).

**From the converged state.**  The load predictor (secant, tangent) moves X off an equilibrium,
and the complementarity problem is linearised there.  Where that path loses its predictions (S
too far from semidefinite at a state it reaches after a first prediction, or a failed solve after
one), the increment starts again from the converged state, whose linearisation is that of an
equilibrium, before the phases: on the gait envelope at twist 90 deg the secant's path met an
indefinite S (one eigenvalue −5.6e9 against 7.5e9) after a prediction that changed 4 constraints
and 3 more at its check, and the phases then took 16 Newton iterations (32 for the level, 600 N,
gastrocnemius-biased); from the converged state the level takes 19, the lost path's 10 included.
Without a prediction already at the load predictor's state the kept-status solve and the phases
run as before (restarting took the 135 deg gastrocnemius-biased column to a failure, 1072 N).
Where the check sets a status it set before in the increment, the predictions cycle (an indefinite
S has several complementary solutions: period 3 at 1000 N on the 120 deg gastrocnemius-biased
column) and the phases take over from that state.

Where there is no prediction (S too far from positive definite, a failed factorisation) and the
kept status does not pass the check, where a solve fails (restarted from the predicted state)
and past ``MAX_PREDICTIONS``, the increment is solved in the law's phases (``contact.laws``):
bands of tolerated violations, then the exact rule, each phase one SNES solve of up to the law's
``snes_max_it`` (60) iterations while |F| still finds new lows (solving/cycle_stop.py).  Two ways
to change the status there:

* with the full Newton step (``-snes_linesearch_type basic``, the default), at every iterate
  (a primal–dual active set inside Newton's iteration);
* with a line search (bt, l2, cp), only between SNES solves: each solve keeps its active set,
  so that the line search compares one smooth residual, and the status is updated at the
  converged state and solved again until it no longer changes (at most ``MAX_STATUS_UPDATES``).

Above the predictor's size the first increment from rest is first solved with every constraint
held (the sliding problem), whose multipliers' signs start the phases.  After the solves, contact
points whose partners slid past B's ends get their new weights (Contact.refresh_weights) and the
state is solved again until the weights settle.  An increment that changes no load (a stride's
swing frames) starts with the check of the converged state it starts from, no prediction.

**Friction's bounds** (issue 27): where the semi-smooth iteration for Coulomb's law fails, the
increment is solved again from its start as a fixed point of Tresca problems (Nečas, Jarušek &
Haslinger 1980; Haslinger, Hlaváček & Nečas 1996, the existence proof for small μ): each solve
holds the bounds μ ẑ_k at the last state's (``contact.hold_bounds``: a given slip resistance,
no coupling of the bounds to the pressures), the next holds them at that solution's, until
they change by less than ``BOUND_TOL``; then Coulomb's own iteration runs from there, so an
accepted state satisfies Coulomb's law exactly as a plainly converged one does.  Why: at a
function on the stick–slip boundary whose sliding branch is softened by its bound's coupling to
the pressures, the two branches of the generalised Jacobian have determinants of opposite sign
(measured: the paper's tendon, equal loading, μ = 0.3, the fold, 92.5 N); the piecewise
smooth residual has no zero near the boundary and the full-step iteration cycles between the two
branches' zeros, each outside its own branch, while the increment's solution lies elsewhere.
Tresca's problem has no such coupling (its branches agree in sign there).
"""
from __future__ import annotations

import os
from typing import Callable

from petsc4py import PETSc

from ..contact import forget_evaluation, hold_bounds
from ..contact.laws import HELD, Phase
from .contact_steps import ContactSteps

#: Newton solves after the first at most, to bring contact points' weights up to date
MAX_WEIGHT_UPDATES = 5
#: status updates between converged solves at most (line-search mode)
MAX_STATUS_UPDATES = 40
#: predictions (Josephy–Newton steps) of one increment at most before the phases take over
MAX_PREDICTIONS = 8
TRACE = bool(os.environ.get("ANCF_TRACE_PHASES"))
#: Tresca solves of a failed friction increment at most; the bounds' relative change below which
#: Coulomb's own iteration takes over (module docstring)
MAX_BOUND_UPDATES = 60
BOUND_TOL = 1e-9
#: ... and gives up when ``STALL_WINDOW`` updates did not halve the smallest change (measured: about
#: 0.55 per update where it helps, plateaus of 3–4; 0.2–0.3, not shrinking, at μ = 3 from rest)
STALL_WINDOW, STALL_FACTOR = 6, 0.5
#: increments in a row whose prediction and check changed no status, after which the next one
#: is solved with its status kept before it is predicted (module docstring, "A settled active set")
SETTLED_INCREMENTS = 2
#: the rule that checks a predicted state (the exact one, block principal pivoting)
CHECK = Phase("exact", pivoting=True)


def contracting(changes: list[float]) -> bool:
    """Whether the fixed point's relative bound changes (inf first) still shrink: the smallest
    of the last ``STALL_WINDOW`` below ``STALL_FACTOR`` times the smallest before them."""
    return (len(changes) <= STALL_WINDOW
            or min(changes[-STALL_WINDOW:]) <= STALL_FACTOR * min(changes[:-STALL_WINDOW]))


class PhasedNewton:
    """Runs the SNES solves of one increment (module docstring).  ``snes_solve(X)`` is one SNES
    solve returning (reason, iterations); ``predictor`` the complementarity predictor or None."""

    def __init__(self, steps: ContactSteps, snes_solve: Callable, predictor=None,
                 line_search: str = "basic"):
        self.steps = steps
        self.snes_solve = snes_solve
        self.predictor = predictor
        self.between_solves = line_search != "basic"
        #: |F| with the state's own contact weights when their updates did not settle, else None
        self.unsettled: float | None = None
        #: Tresca solves of the increment (friction's bounds held; 0: none were needed)
        self.bound_updates = 0

    def solve(self, X: PETSc.Vec, lam: float, from_rest: bool,
              converged: PETSc.Vec | None = None, unchanged: bool = False) -> tuple[int, int]:
        """(reason of the last solve, Newton iterations of all of them).  ``converged``: the
        converged state a load predictor moved X from (module docstring, "From the converged
        state"); ``unchanged``: X is the last increment's converged state and this one changes
        no load (``_predicted``)."""
        P = self.steps
        P.frozen = self.between_solves
        P.begin_increment(from_rest)
        its, solved = 0, None
        start = X.copy() if P.bounded else None
        if self.predictor is not None and P.decides_activity:
            solved, its, lost = self._predicted(X, lam, converged is not None, unchanged)
            if lost:
                # the load predictor's path lost the predictions: the Josephy–Newton iteration
                # again from the converged state, linearised at an equilibrium
                self._trace(lam, "from the converged state", 0, 0)
                converged.copy(X)
                P.contact.restore()
                solved, n, _ = self._predicted(X, lam)
                its += n
        if solved is not None:
            reason = solved
        else:
            phases = P.phases(from_rest)
            if from_rest and self.predictor is None and P.decides_activity:
                # too many multipliers for the predictor: solve the increment with every
                # constraint held first (the sliding problem); the phases then release the
                # ones that pull
                phases = [HELD] + phases
            reason, n = self._phases(X, lam, phases)
            its += n
            if reason <= 0 and start is not None:
                start.copy(X)
                reason, n = self._bounds_fixed_point(X, lam, phases)
                its += n
        if start is not None:
            start.destroy()
        P.frozen = self.between_solves
        for _ in range(MAX_WEIGHT_UPDATES):
            # contact points whose partners moved past B's ends changed weight: solve again
            if reason <= 0 or not P.refresh_weights():
                return reason, its
            reason, n = self.snes_solve(X)
            its += n
            self._trace(lam, "weights changed", n, reason)
        if reason > 0 and P.refresh_weights():
            # the weights' fixed point did not settle: the last solve's weights are not those of
            # its state; the residual with the state's own weights is what the level reports
            self.unsettled = P.residual_norm(X)
        return reason, its

    def _predicted(self, X: PETSc.Vec, lam: float, moved: bool = False,
                   unchanged: bool = False) -> tuple[int | None, int, bool]:
        """Josephy–Newton (module docstring): (reason, iterations, lost), reason None when the
        increment is left to the phases (from X as it is then).  A prediction is one Newton
        iteration; without one the status is kept, and the phases take over when the check then
        changes it.  ``moved``: X is a load predictor's state; ``lost``: this path predicted and
        lost the next prediction or its solve (the caller starts again from the converged state).
        A settled active set is solved as it is first (module docstring)."""
        P, c, its, predicted_once, weighed, seen = self.steps, self.steps.contact, 0, False, None, set()
        (streak, self.predictor.settled), retry = (self.predictor.settled, 0), False
        for k in range(MAX_PREDICTIONS):
            before, skipped = c.status.copy(), k == 0 and streak >= SETTLED_INCREMENTS and not unchanged
            ok = not (unchanged and k == 0) and not skipped and self.predictor.predict(X)
            predicted = int((before != c.status).sum())          # this rank's, for the trace
            its += int(ok)
            if not ok and (retry or moved and predicted_once):   # retry: the settled solve failed
                self._trace(lam, f"no prediction {k}" + ("" if retry else " on the load predictor's path"), 0, 0)
                return None, its, not retry
            predicted_once |= ok
            if ok and retry and self._repeats(before):
                self._trace(lam, f"prediction {k} (0 changes) repeats the failed solve", 0, 0)
                return None, its, moved
            start, status = X.copy(), c.status.copy()
            P.keep_status(CHECK)
            reason, n = self.snes_solve(X)
            its += n
            what = f"prediction {k} ({predicted} changes{self._held})" if ok else f"no prediction {k}"
            if reason <= 0:
                self._trace(lam, what, n, reason)
                self._undo(X, start, status, weighed)
                if weighed is not None:
                    return self._reweigh(X, lam, its, weighed)
                if skipped:
                    retry = True        # the settled set's solve failed: predicted after all
                    continue
                # the predicted state's solve failed: the phases from the prediction (they
                # rescue increments that may not be cut back: fixed increments)
                return None, its, moved and predicted_once
            start.destroy()
            changes = P.update_status(X)
            self._trace(lam, what, n, reason, changes)
            if changes and self._cycles(seen, lam, reason):
                return None, its, False
            weighed = self._weights_followed(X, lam, reason, weighed)
            reweighted = weighed is not None
            if changes == 0 and not reweighted:
                self.predictor.settled = streak + 1 if k == 0 and (skipped or self._unchanged(before)) else 0
                return reason, its, False
            if skipped:
                continue                                     # the check changed it: predict
            if not ok:
                if changes:
                    return None, its, False
                return self._reweigh(X, lam, its, weighed)   # no prediction: the weights alone
        return None, its, False

    def _weights_followed(self, X: PETSc.Vec, lam: float, reason: int, weighed):
        """The first solve from rest kept the weights: they now follow the state, and the next
        prediction linearises them with it (one Josephy–Newton step for the status and the
        weights together, instead of a re-solve for the weights after the status settled).
        The state and status they were updated at, or None when none changed (collective)."""
        if weighed is not None:
            weighed[0].destroy()
        if not self.steps.differentiate_weights():
            return None
        self._trace(lam, "weights differentiated", 0, reason)
        return X.copy(), self.steps.contact.status.copy()

    def _undo(self, X: PETSc.Vec, start: PETSc.Vec, status, weighed) -> None:
        """After a prediction's failed solve: X and the status it started from (``start`` is
        destroyed), or, where the step that linearised the weights with the status failed
        (``weighed``), the state the weights were updated at with its status kept."""
        c = self.steps.contact
        c.projector.restore()
        (start if weighed is None else weighed[0]).copy(X)
        c.status[:] = status if weighed is None else weighed[1]
        start.destroy()

    def _repeats(self, status) -> bool:
        """Whether a prediction after the settled solve failed kept every rank's status: it then
        steps as that solve's first Newton iteration did from the same state, and its solve would
        repeat the failure (the second subject's 90° gastrocnemius-biased unilateral column at
        600 N: 15 Newton iterations to the same cycle of period 5).  The caller goes on as after
        that solve's failure, without it.  Collective."""
        return self._unchanged(status)

    def _unchanged(self, status) -> bool:
        """Whether the prediction kept every rank's status (collective)."""
        g = self.predictor.global_status
        return bool((g(status) == g(self.steps.contact.status)).all())

    @property
    def _held(self) -> str:
        return ", held" if self.predictor.last_held else ""

    def _cycles(self, seen: set, lam: float, reason: int) -> bool:
        """Whether the check set a status it set before in this increment (``seen``, which
        gets this one): the predictions cycle (module docstring; from the converged state they
        cycle again).  Collective."""
        key = self.predictor.global_status(self.steps.contact.status).tobytes()
        if key in seen:
            self._trace(lam, "the predictions cycle", 0, reason)
            return True
        seen.add(key)
        return False

    def _reweigh(self, X: PETSc.Vec, lam: float, its: int, weighed) -> tuple[int, int, bool]:
        """One solve for the weights just updated, the status kept (``_predicted``), checked by
        the exact rule: a changed status leaves the increment to the phases (reason None; unchecked,
        the 135° uniform unilateral stride's frame 1 had multipliers pulling, −28 N)."""
        if weighed is not None:
            weighed[0].destroy()
        forget_evaluation(self.steps.contact)
        reason, n = self.snes_solve(X)
        changes = self.steps.update_status(X) if reason > 0 else 0
        self._trace(lam, "weights changed", n, reason, changes)
        return (None if changes else reason), its + n, False

    def _bounds_fixed_point(self, X, lam: float, phases: list) -> tuple[int, int]:
        """Friction's bounds (module docstring): Tresca solves from X (the increment's start),
        then Coulomb's; (reason, iterations).  Gives up (a failure: the stepper cuts back) when
        a Tresca solve fails or the bounds stop contracting.  Collective."""
        P, c, its, changes = self.steps, self.steps.contact, 0, []
        reason = PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT
        c.restore()                                  # statuses and projections of the start
        try:
            for k in range(MAX_BOUND_UPDATES):
                P.residual_norm(X)                   # the bounds at X
                changes.append(hold_bounds(c))
                self._trace(lam, f"bounds held ({changes[-1]:.1e} relative change)", 0, 0)
                if changes[-1] <= BOUND_TOL or not contracting(changes):
                    break
                self.bound_updates += 1
                reason, n = self._phases(X, lam, phases)
                its += n
                self._trace(lam, f"Tresca solve {k}", n, reason)
                if reason <= 0:
                    return reason, its
        finally:
            hold_bounds(c, False)
        if not contracting(changes):
            return PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT, its
        reason, n = self._phases(X, lam, phases)
        self._trace(lam, "Coulomb after the fixed point", n, reason)
        return reason, its + n

    def _phases(self, X, lam: float, phases: list) -> tuple[int, int]:
        P, its, previous, reason = self.steps, 0, None, 0
        P.frozen = self.between_solves
        for phase in phases:
            P.begin(phase, previous)
            reason, n = self._phase(X, lam, phase)
            its += n
            if reason <= 0:
                break
            previous = phase
        return reason, its

    def _phase(self, X, lam: float, phase) -> tuple[int, int]:
        P, its = self.steps, 0
        if self.between_solves and P.decides_activity:
            for update in range(MAX_STATUS_UPDATES):
                reason, n = self.snes_solve(X)
                its += n
                # a solve that stalls (line search, iterations) may stall on a wrong active
                # set: the status at its last iterate decides whether to go on
                stalled = reason in (PETSc.SNES.ConvergedReason.DIVERGED_LINE_SEARCH,
                                     PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT)
                changes = P.update_status(X) if reason > 0 or stalled else 0
                self._trace(lam, f"{phase.name} update {update}", n, reason, changes)
                if changes == 0:
                    return reason, its
            return PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT, its
        changes = P.status_changes()
        reason, n = self.snes_solve(X)
        self._trace(lam, phase.name, n, reason, P.status_changes() - changes)
        return reason, n

    @staticmethod
    def _trace(lam, what, n, reason, changes=None) -> None:
        if TRACE:
            extra = "" if changes is None else f", {changes} status changes"
            print(f"   load factor {lam:.6g} {what}: {n} Newton its, reason {reason}{extra}", flush=True)
