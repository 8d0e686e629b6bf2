"""SNES Newton with line search inside an adaptive load-stepping loop (paper §3, static case).

From the last converged load factor λ the stepper tries an increment Δλ (load_control.py); on a
converged solve it accepts it (growing Δλ after easy steps), on divergence (including NaN
residuals from inverted elements, J ≤ 0) it restores the last converged state and halves Δλ, at
most ``max_cutbacks`` times in a row (the rest of the way to a level in one step when that is at
most ``load_control.STRETCH`` increments).  Requested levels are always hit exactly.  All decisions use
the SNES converged reason, the same on every rank.  SNES: snes_solver.py; Newton phases: newton.py.
"""
from __future__ import annotations

import time
from typing import Callable

import numpy as np
from petsc4py import PETSc

from ..config.specs import SolverSpec
from ..linalg import logging
from ..petsc.complementarity import ComplementarityPredictor
from ..petsc.problem import Problem, unclean
from . import solver_messages
from .branch_switch import BranchSwitch
from .fade_switch import FadeForcesSwitch
from .continuity import jump_detail, residual_jump
from .early_switch import switch_early
from .failure_cause import Detail, give_up_cause, with_critical_point
from .interrupt import RunInterrupted, stop_requested
from .load_control import LevelTally, LoadControl
from .newton import MAX_WEIGHT_UPDATES, PhasedNewton
from .predictor import TangentPredictor
from .critical_point import critical_point, verdict_count
from .rest_response import at_rest, increment_from_rest
from .records import (STALLED_STEP, UNCLEAN_STATE, UNSTABLE_STEP, VIOLATED_STATE, LoadStepFailure, PathState,
                      StepRecord, reason_name)
from .snes_solver import SNESSolver
from .step_over import behind, creeping, reported_level, step_over
from .window_widening import WindowWidening


#: failures whose last iterates are scanned for a jump of the residual (continuity.py): Newton
#: ran out of iterations (cycling, wandering, stalling), its line search found no descent or its
#: residual grew past the divergence tolerance
JUMP_REASONS = (PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT, PETSc.SNES.ConvergedReason.DIVERGED_LINE_SEARCH,
                PETSc.SNES.ConvergedReason.DIVERGED_DTOL, STALLED_STEP)


class LoadStepper:
    """Drives ``problem`` through the requested load factors with one SNES (``solver``)."""

    def __init__(self, problem: Problem, spec: SolverSpec, petsc_options: dict,
                 log: Callable[[str], None] = print, max_level: float = 1.0, linear: str = "direct"):
        self.problem, self.spec, self.log = problem, spec, log
        self.control = LoadControl(spec)          # increments, cut-backs, budget (pure Python)
        self.solver = SNESSolver(problem, spec, petsc_options, max_level, linear)
        self.path: PathState | None = None      # where the load path is (``run``)
        self.newton_iterations = 0
        #: a unilateral law's complementarity predictor (complementarity.MAX_MULTIPLIERS; newton.py)
        self.predictor = (ComplementarityPredictor(problem, self.solver.snes, spec.compact_factor)
                          if ComplementarityPredictor.applies(problem) else None)
        self.tangent = TangentPredictor(problem, self.solver.snes)     # solver.predictor: tangent
        self.history: list[float] = []         # residual norms of the solves of an increment
        self.unsettled = False                  # the last solve's contact weights did not settle
        self.tresca_solves = 0                  # friction's fixed point in the last solve_at
        self.branches = BranchSwitch(problem, spec.branch_switch and not spec.allow_unstable)  # saddles
        self.fade_switch = FadeForcesSwitch(self, petsc_options, max_level, linear)   # fade_switch.py
        self.windows = WindowWidening(problem)                                         # window_widening.py
        self.first_give_up: tuple[float, LoadStepFailure, str] | None = None    # last_resorts' (lam, failure, resorts)

    def describe(self) -> str:
        """The solver in one line (the run's header)."""
        return self.solver.describe()

    def close(self, collective: bool = True) -> None:
        """Remove the solver's options from PETSc's database (``SNESSolver.close``)."""
        self.solver.close(collective)

    def release_path(self) -> None:
        """Free the load path's vectors (before another ``run`` of this stepper starts a path)."""
        for v in (self.path.X, self.path.dX_last) if self.path is not None else ():
            v.destroy()
        self.path = None

    def destroy(self) -> None:
        """Free the SNES, the complementarity predictor's factor and the path's vectors, and take the
        options a raising run left out of PETSc's database (MUMPS's null-pivot ones); not collective."""
        self.close(collective=False)
        self.release_path()
        self.branches.destroy()
        for part in (self.solver, self.predictor) if self.predictor is not None else (self.solver,):
            part.destroy()

    def solve_at(self, lam: float, X: PETSc.Vec, target: float, reached: float, from_rest: bool = False,
                 converged: PETSc.Vec | None = None, unchanged: bool = False) -> tuple[int, int, float]:
        """Newton at load factor ``lam`` from ``X`` (newton.PhasedNewton; ``converged``: the state a
        load predictor moved X from; ``unchanged``: X is converged at these loads): the last
        solve's reason, all their iterations, the final |F|; ``history`` the residuals."""
        self.problem.load_factor = lam
        self.problem.impose(X)                  # prescribed displacements at this load factor
        S = self.solver
        S.history = []
        newton = PhasedNewton(S.contact_steps, lambda Y: S.solve(Y, target, lam, reached),
                              self.predictor, S.linesearch)
        spent = S.spent
        try:
            reason, its = newton.solve(X, lam, from_rest, converged, unchanged)
        except RunInterrupted:                  # a solve stopped by a signal: its iterations count
            self.newton_iterations += S.spent - spent
            raise
        self.tresca_solves = newton.bound_updates
        if newton.bound_updates:
            self.log(solver_messages.tresca_line(lam, newton.bound_updates, reason, its))
        self.history = S.history
        self.newton_iterations += its
        # a SNES type that keeps no norm (ksponly, ms report 0: their levels were accepted with
        # NaN or one linear step's answers) is judged on |F(X)| (collective)
        fnorm = S.snes.getFunctionNorm()
        fnorm = fnorm if fnorm > 0.0 else S.contact_steps.residual_norm(X)
        self.unsettled = newton.unsettled is not None
        if self.unsettled:
            # a level accepted with its weights' last update unsettled reports the residual
            # with the state's own weights (contact/weights.py), never the stale one
            fnorm = max(fnorm, newton.unsettled)
            self.log(solver_messages.unsettled_line(lam, MAX_WEIGHT_UPDATES, fnorm))
        return reason, its, fnorm

    def _stop_if_requested(self, target: float, level: float) -> None:
        """Between Newton solves: stop on every rank if any rank got SIGTERM/SIGINT (collective)."""
        signum = stop_requested(self.problem.comm)
        if signum:
            raise RunInterrupted(signum, f"on the way to load factor {target:g} (last converged "
                                         f"level {level:g})")

    def run(self, levels: list[float], on_level: Callable[[StepRecord], None],
            start: PathState | None = None, before: StepRecord | None = None) -> list[StepRecord]:
        """Reach every level in ``levels`` (increasing); call ``on_level`` after each one.  ``start``:
        continue a path (a restart, ``before`` its last level) instead of from the reference state."""
        P = self.problem
        self.path = path = start or self.initial_path(levels[0], levels[-1])
        self.solver.spent += path.spent         # solver.max_newton_iterations: the whole run's
        path.X.copy(P.X)
        P.checkpoint()
        records = []
        logging.stage(logging.SOLVE).push()
        try:
            for target in levels:           # one a gap's step over passed too: reported with it
                if path.lam > 0.0 and at_rest(P, path.lam):      # a frame of zero loads
                    path.dlam = increment_from_rest(self, path.lam, target, levels[-1])
                rec = (behind(self, path, target, records[-1] if records else before)
                       or self._reach(path, target, records[-1].load_factor if records else path.lam))
                records.append(rec)
                on_level(rec)
        finally:
            logging.stage(logging.SOLVE).pop()
        return records

    def initial_path(self, first_level: float, last_level: float | None = None) -> PathState:
        """The path at the reference state, with the first increment (rest_response.py)."""
        X, dX = self.problem.q0.copy(), self.problem.q0.duplicate()
        dX.set(0.0)
        return PathState(X=X, dX_last=dX, lam=0.0, dlam=increment_from_rest(self, 0.0, first_level, last_level),
                         dlam_last=0.0)

    def _reach(self, path: PathState, target: float, level: float) -> StepRecord:
        """Sub-steps from ``path.lam`` to ``target``: accept converged ones (growing the
        increment after easy ones), cut back failed ones; raises LoadStepFailure."""
        X = self.problem.X
        t0 = time.perf_counter()
        tally = LevelTally(start=level, increment=path.dlam)
        history, X_prev = [], X.duplicate()
        mixed = self.problem.mixed                     # solver.tangent: mixed (petsc/mixed_tangent.py)
        try:
            while path.lam < target * (1.0 - 1e-14):
                self._stop_if_requested(target, level)
                step = self.control.step(path.lam, path.dlam, target)
                X.copy(X_prev)
                # a converged state at loads the increment leaves unchanged: nothing to predict
                still = path.lam > 0.0 and self.problem.loads.unchanged(path.lam, path.lam + step)
                rest = at_rest(self.problem, path.lam)          # λ = 0, or a frame of zeros
                predictor = "none" if still or rest or self._contact_formed(path) else self.spec.predictor
                moved = False
                if predictor == "secant" and path.dlam_last > 0.0:
                    X.axpy(step / path.dlam_last, path.dX_last)       # secant predictor
                    self.problem.limits.limit_predictor(X_prev, X)    # fibre exponents (step_limits)
                    moved = True
                elif predictor == "tangent" and self.tangent.predict(X, path.lam + step):
                    self.problem.limits.limit_predictor(X_prev, X)
                    moved = True
                reason, its, fnorm = self.solve_at(path.lam + step, X, target, path.lam, rest,
                                                    X_prev if moved else None, still)
                tally.its += its
                tally.tresca_solves += self.tresca_solves
                history.append(self.history)          # a polish adds its own (critical_point._polish)
                self._check_budget(path, X_prev, target, step)
                reason, neg = self.judge(path, reason, fnorm, step, tally)
                if reason > 0 and self.branches.applies(path, neg):       # branch_switch.py
                    if self.branches.take(self, path, X_prev, target, tally, resume=True):
                        continue
                    reason, neg = self.branches.resumed
                if reason > 0:
                    tally.unsettled |= self.unsettled
                    self.accept(path, X_prev, step, its, neg, tally)
                else:
                    self._cut_back(path, X_prev, target, step, reason, neg, tally)
        finally:
            X_prev.destroy()
            if mixed is not None:
                mixed.paused = False
        reported, reason, fnorm = reported_level(target, reason, fnorm, tally, self.solver.snes, path.lam)
        return StepRecord(load_factor=reported, iterations=tally.its, substeps=tally.substeps,
                          cutbacks=tally.cutbacks, reason=reason_name(reason),
                          tresca_solves=tally.tresca_solves,
                          residual_norm=float(fnorm), wall_time=time.perf_counter() - t0,
                          iteration_history=history, negative_eigenvalues=self.solver.negative_eigenvalues(),
                          increment=path.dlam, last_increment=path.dlam_last,
                          weights_unsettled=tally.unsettled, branch_switches=tally.switches,
                          passed_over=tally.passed_over and (target, *tally.passed_over[:2]))

    def _contact_formed(self, path: PathState) -> bool:
        """Whether the last increment was the first from rest and formed the contact state: no
        step along the load path for a load predictor to extrapolate (the secant took the soleus'
        lift-off of 30 N to 60 N at twist 60-90 deg: cut-backs in 4 of 10 columns); the next one
        starts at the converged state.  From the path and status alone, as a restart (collective)."""
        if self.predictor is None or path.dlam_last <= 0.0 or path.lam != path.dlam_last:
            return False
        return bool(self.predictor.global_status(self.problem.contact.status).any())

    def _check_budget(self, path: PathState, X_prev: PETSc.Vec, target: float, step: float) -> None:
        spent = max(self.newton_iterations + path.spent, self.solver.spent)   # the SNES's count caps its solves
        if self.control.over_budget(spent):
            self.problem.load_factor = path.lam
            X_prev.copy(self.problem.X)
            self.problem.restore()
            raise LoadStepFailure(target, path.lam + step, path.lam, "NEWTON_BUDGET_EXCEEDED", False,
                                  self.control.budget_spent(spent, path.spent))

    def judge(self, path: PathState, reason: int, fnorm: float, step: float, tally: LevelTally):
        """The sub-step's verdict: SNES's reason, made a failure when the residual is not small
        (stalled), the state no answer (problem.unclean) or less stable than the last accepted."""
        P = self.problem
        if reason > 0 and not self.solver.residual_small(reason, fnorm):
            reason = STALLED_STEP                       # a step-length stop above the tolerance
            self.solver.stalled_at = fnorm
        cause = unclean(P) if reason > 0 and np.isfinite(fnorm) else "residual"
        converged = reason > 0 and cause is None
        if reason > 0 and not converged:
            reason = VIOLATED_STATE if cause == "conditions" else UNCLEAN_STATE
        neg = verdict_count(self, path, step, tally, converged)    # polished where tolerances are loose
        if neg:                                         # a saddle: a branch point to switch from
            self.branches.remember(path.lam + step, P.X, self.solver.snes.getJacobian()[0], neg, path.lam)
        if self.control.wants_stability_retry(neg, path.accepted_negative, tally):
            reason = UNSTABLE_STEP
        return reason, neg

    def accept(self, path: PathState, X_prev: PETSc.Vec, step: float, its: int, neg, tally: LevelTally):
        if neg is not None:
            path.accepted_negative = neg
        self.tangent.valid = True                      # the SNES's factor: a converged state's
        self.solver.accepted()
        self.problem.checkpoint()
        self.problem.X.copy(path.dX_last)
        path.dX_last.axpy(-1.0, X_prev)
        path.dlam_last = step
        path.lam += step
        tally.substeps += 1
        tally.consecutive = 0
        path.dlam = self.control.after_success(step, path.dlam, its)

    def _cut_back(self, path: PathState, X_prev: PETSc.Vec, target: float, step: float,
                  reason: int, neg, tally: LevelTally) -> None:
        """Back to the last converged state with half the increment (collective); raises
        LoadStepFailure after ``max_cutbacks`` in a row (a creep into a gap: step_over.creeping)."""
        P = self.problem
        inverted = bool(P.comm.tompi4py().allreduce(int(P.inverted)))
        lost = bool(P.comm.tompi4py().allreduce(int(P.contact_failed)))
        self.tangent.valid = False                     # the factor is the failed attempt's
        if P.mixed is not None:                        # the retries: the plain tangent's course
            P.mixed.paused = True
        X_prev.copy(P.X)
        P.restore()
        path.dlam, give_up = self.control.after_failure(step, reason == UNSTABLE_STEP, tally)
        if reason == UNSTABLE_STEP and tally.unstable_at is None:
            tally.unstable_at = (path.lam + step, neg, path.accepted_negative)
        then = (f"no retry: {self.control.stop_reason(path.dlam, tally)}" if give_up
                else f"retry with increment {path.dlam:.4g}")
        self.log(f"  cut back at load factor {path.lam + step:.6g}: {reason_name(reason)}"
                 f"{solver_messages.attempt_why(self.solver, reason, neg, inverted, lost, path.accepted_negative)}; {then}")
        if not give_up and switch_early(self, path, X_prev, target, tally):   # creeping to a bifurcation
            return
        if give_up or creeping(self, tally, path.lam + step == target):
            failure = _given_up(self, path, X_prev, step, target, reason, tally, inverted, lost)
            if give_up:
                last_resorts(self, path, X_prev, target, tally, failure, lost and not inverted)
            else:                                      # a creep into a gap at the level
                step_over(self, path, X_prev, target, tally, failure)


def _given_up(stepper: LoadStepper, path: PathState, X_prev: PETSc.Vec, step: float, target: float, reason: int,
              tally: LevelTally, inverted: bool, lost: bool) -> LoadStepFailure:
    """The failure of a level whose cut-backs gave out at the step from ``path.lam``: its message
    (what Newton did, a less stable state on the way, a jump of the residual, looked for in the
    failed attempt's iterates, the state restored to ``X_prev`` after) and its cause's code
    (failure_cause.py).  Collective."""
    lam, jump, P = path.lam, None, stepper.problem
    if not (inverted or lost) and reason in JUMP_REASONS:
        tol = max(stepper.solver.snes.getTolerances()[1], solver_messages.reachable_tolerance(stepper.solver))
        jump = residual_jump(P, stepper.solver.trail, lam + step, tol)
        X_prev.copy(P.X)
        P.restore()
    # a min_increment that forbade every cut-back is the cause, not Newton's course (nor at rounding)
    rounding = jump is not None and jump.kind == "rounding_noise"
    newton = (solver_messages.floor_detail(step, lam, stepper.spec.min_increment) if stepper.control.floored(
        step, tally) else Detail("") if rounding else solver_messages.failure_detail(stepper.solver, reason))
    return LoadStepFailure(target, lam + step, lam, reason_name(reason), inverted,
                           newton + solver_messages.stability_detail(tally.unstable_at) + jump_detail(jump),
                           give_up_cause(inverted, lost, jump, tally.unstable_at, newton))


def last_resorts(stepper: LoadStepper, path: PathState, X_prev: PETSc.Vec, target: float, tally: LevelTally,
                 failure: LoadStepFailure, lost: bool) -> None:
    """What the stepper tries where every cut-back failed, in turn: the switch from a pending
    branch point (branch_switch.py), the whole partner beam as every contact point's search
    window where the last attempt lost a point from its window (``lost``; window_widening.py), a
    snap past a critical point (critical_point.py: the same model's answer, so before the other), a
    step past a gap of the load path at a jump of the residual (step_over.py), the pointwise fade
    forces (fade_switch.py: on with another form of the contact forces).  Returns when the path
    goes on from a state one of them reached; else raises ``failure``, naming the critical point
    if the path is at one.  Collective."""
    if stepper.branches.take(stepper, path, X_prev, target, tally, resume=False):
        return
    if stepper.windows.take(stepper, path, tally, lost):
        _went_on(stepper, path.lam, failure, "the whole partner beam as every contact point's search window")
        return
    critical = None if failure.cause == "rounding_noise" else critical_point(stepper, path.lam)
    tried, sentence = False, ""
    try:
        tried = critical is not None and stepper.branches.snaps(path)
        if tried and stepper.branches.snap(stepper, path, X_prev, target, tally, critical):
            return
        sentence = critical.sentence(tried) if critical is not None else ""
    finally:
        if critical is not None:
            critical.destroy()
    if critical is not None:
        failure.cause = with_critical_point(failure.cause)
        failure.detail += sentence           # _first_give_up repeats it if a resort goes on
    if step_over(stepper, path, X_prev, target, tally, failure):
        return
    if stepper.fade_switch.take(stepper, path, tally):
        _went_on(stepper, path.lam, failure, "the pointwise fade forces")
        return
    stepper.problem.load_factor = path.lam
    first = _first(stepper, failure)
    if critical is None and first is not None and first.cause == "critical_point":
        # the resort ended elsewhere, off the critical point that stopped the path first
        failure.cause = with_critical_point(failure.cause)
    raise failure.amend(sentence).amend(_first_give_up(stepper, failure))


def _went_on(stepper: LoadStepper, lam: float, failure: LoadStepFailure, resort: str) -> None:
    """Keep the give-up a last resort went on from: the level's first (a resort that fails too
    ends the level elsewhere, often farther from equilibrium, where what Newton meets is not what
    stopped the path first)."""
    first = stepper.first_give_up
    if first is None or first[1].target != failure.target:
        stepper.first_give_up = (lam, failure, resort)
    else:
        stepper.first_give_up = (first[0], first[1], f"{first[2]}, then {resort}")


def _first(stepper: LoadStepper, failure: LoadStepFailure) -> LoadStepFailure | None:
    """The level's first give-up where last resorts went on from it, else None."""
    first = stepper.first_give_up
    return None if first is None or first[1].target != failure.target else first[1]


def _first_give_up(stepper: LoadStepper, failure: LoadStepFailure) -> str:
    """The final message's part for the level's first give-up where last resorts went on from it
    (empty otherwise): where it was, its reason and cause (a critical point found there too)."""
    f = _first(stepper, failure)
    if f is None:
        return ""
    first = stepper.first_give_up
    return (f"; before going on with {first[2]}, the level's first give-up was from load factor "
            f"{first[0]:.6g}, at {f.attempted:.6g} with {f.reason}{f.detail}")
