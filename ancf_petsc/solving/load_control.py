"""Load-step control: how the load factor λ advances from one converged state to the next.

Pure Python (no PETSc, no MPI): the first increment, the next sub-step (capped by
``solver.max_increment``, landing exactly on every requested level, the rest of the way in one
step when it is at most ``STRETCH`` increments), growth after easy steps,
halving after a failed one (at most ``solver.max_cutbacks`` in a row, not below
``solver.min_increment``), retries with smaller steps when a step lands on a less stable state
(at most ``solver.stability_cutbacks`` per level) and the Newton budget of the whole run.  The
SNES side (stepper.py) asks it at every sub-step."""
from __future__ import annotations

from dataclasses import dataclass, field


#: the rest of the way to a requested level is taken in one step when it is at most this many
#: increments (instead of an increment and a sliver: 100 → 140 → 150 N); measured over the
#: unilateral grid and the sliding columns (docs/contact.md)
STRETCH = 1.5


@dataclass
class LevelTally:
    """What reaching one requested level took."""
    its: int = 0            # Newton iterations of its sub-steps
    substeps: int = 0       # accepted sub-steps
    cutbacks: int = 0       # halvings (failures and stability retries)
    consecutive: int = 0    # failures since the last accepted sub-step
    first_failed: float = 0.0   # the increment of the first of them
    stability: int = 0      # retries because a step landed on a less stable state
    unsettled: bool = False  # a sub-step accepted with its contact weights unsettled
    start: float = 0.0      # the load factor the level starts from (the last level's)
    increment: float = 0.0  # the increment it starts with
    passed_over: tuple | None = None   # (last converged, reported, reason, |F|): step_over.py
    at_level_failures: int = 0  # failed sub-steps whose end was the level itself (step_over.py)
    tresca_solves: int = 0  # friction's fixed point (solving/newton.py), all sub-steps
    polished: float | None = None  # |F| of the last sub-step's state polished for its verdict (critical_point.py)
    #: (load factor, negative eigenvalues, the last accepted state's) of the first sub-step
    #: that converged to a less stable state (a stability retry)
    unstable_at: tuple[float, int, int] | None = None
    after_unstable: int = 0  # failed sub-steps since then (early_switch.py)
    #: the branch switches of this level (solving/branch_switch.py reports)
    switches: list = field(default_factory=list)


class LoadControl:
    """The increments of one run, from ``solver`` (a config.specs.SolverSpec)."""

    def __init__(self, solver):
        self.spec = solver

    def first_increment(self, first_level: float, share: float | None, last_level: float | None = None,
                        predicted: bool = False) -> float:
        """The first load increment from rest: the first level, or for a law with a
        ``first_increment`` share (unilateral) that share of the first level without the
        complementarity predictor (the held start) and at most that share of the last level with it
        (one step from rest to a far level lands on another equilibrium of the unilateral problem:
        docs/contact.md, stability map); ``solver.initial_increment`` and ``max_increment`` bound it."""
        dlam = first_level
        if share is not None:
            dlam = (min(first_level, share * (last_level or first_level)) if predicted
                    else first_level * share)
        if self.spec.initial_increment is not None:
            dlam = min(first_level, self.spec.initial_increment)
        return dlam if self.spec.max_increment is None else min(dlam, self.spec.max_increment)

    def step(self, lam: float, dlam: float, target: float) -> float:
        """The next sub-step from λ with increment ``dlam``: the rest of the way to ``target``
        when that is at most ``STRETCH`` increments, else ``dlam``; never past the cap."""
        step = target - lam
        if step > STRETCH * dlam:
            step = dlam
        return step if self.spec.max_increment is None else min(step, self.spec.max_increment)

    def after_success(self, step: float, dlam: float, its: int) -> float:
        """The next increment after a converged sub-step of ``its`` Newton iterations: after an
        easy one, ``growth`` times the step it took, never less than the increment (until
        2026-11-28 a sub-step shortened to hit a level kept the increment, however easy: after a
        first level of 30 N in 10-13 iterations every level to 400 N took two sub-steps, 60 → 100,
        100 → 160 → 200, 200 → 320 → 400, on the unilateral gait columns)."""
        if its <= self.spec.easy_iterations:
            return max(step * self.spec.growth, dlam)
        return dlam

    def wants_stability_retry(self, negative: int | None, accepted: int, tally: LevelTally) -> bool:
        """Whether a converged sub-step with ``negative`` tangent eigenvalues (the last accepted
        state had ``accepted``) is retried with a smaller step: a stable path does not step onto a
        saddle, another branch may have been reached; counted in ``tally``."""
        if negative is not None and negative > accepted and tally.stability < self.spec.stability_cutbacks:
            tally.stability += 1
            return True
        return False

    def after_failure(self, step: float, stability: bool, tally: LevelTally) -> tuple[float, bool]:
        """The increment after a failed (or stability-retried) sub-step and whether to give up:
        more than ``max_cutbacks`` failures in a row, or below ``min_increment``."""
        tally.cutbacks += 1
        if not tally.consecutive:
            tally.first_failed = step
        tally.consecutive += not stability                 # retries are bounded on their own
        dlam = 0.5 * step
        return dlam, tally.consecutive > self.spec.max_cutbacks or dlam < self.spec.min_increment

    def stop_reason(self, dlam: float, tally: LevelTally) -> str:
        """Why ``after_failure`` gave up, for the log."""
        if tally.consecutive > self.spec.max_cutbacks:
            return f"{tally.consecutive} failures in a row (solver.max_cutbacks = {self.spec.max_cutbacks})"
        return f"the increment {dlam:.4g} would be below solver.min_increment = {self.spec.min_increment:g}"

    def floored(self, step: float, tally: LevelTally) -> bool:
        """Whether a level gave up at its first failure only because half the failed ``step`` is
        below ``min_increment``: no cut-back was tried.  A min_increment above half the spacing
        of the load levels (or of ``max_increment``) does that to every failure; the config is
        valid still (a run whose steps all converge never cuts back: the ψ = 45° config with
        min_increment 6 between its levels 40 and 45 completes), so this is said at the failure.
        Only at the level's first cut-back: a level that crept on by cut-backs to a step below
        the floor (the 180° soleus-biased stride, 14 of them from frame 41 to 41.8398) gave up on
        Newton's course, which its message names (until 2026-12-03 it said "no cut-back was tried")."""
        return (tally.cutbacks == 1 and tally.consecutive == 1 and tally.consecutive <= self.spec.max_cutbacks
                and 0.5 * step < self.spec.min_increment)

    def over_budget(self, newton_iterations: int) -> bool:
        """Whether the run has spent more Newton iterations than ``max_newton_iterations``."""
        budget = self.spec.max_newton_iterations
        return budget is not None and newton_iterations > budget

    def budget_spent(self, spent: int, before: int) -> str:
        """The failure's words for a spent budget (``before``: the iterations of the levels a
        restart continued after, which count)."""
        restart = f"; {before} of them before --restart" if before else ""
        return (f" after {spent} Newton iterations (solver.max_newton_iterations = "
                f"{self.spec.max_newton_iterations}{restart})")
