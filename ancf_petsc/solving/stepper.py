"""SNES Newton with line search inside an adaptive load-stepping loop (paper §3, static case).

The SNES's options are set up by ``options.py``.  Load stepping: from the last converged load
factor λ the stepper tries an increment Δλ (the whole rest of the way to the next requested level
when that is at most ``STRETCH`` Δλ); on a converged SNES it accepts it (growing Δλ after
easy steps), on divergence (including NaN residuals from inverted elements, J ≤ 0) it restores
the last converged state and halves Δλ, at most ``max_cutbacks`` times in a row.  Requested levels are always hit exactly.  All
decisions use the SNES converged reason, which is the same on every rank.
Near convergence a Newton step may reuse the last factored tangent (``chord.py``).
"""
from __future__ import annotations

import time
from typing import Callable

import numpy as np
from petsc4py import PETSc

from ..config.specs import SolverSpec
from ..petsc import logging
from ..petsc.complementarity import ComplementarityPredictor
from ..petsc.inertia import mumps_error, pivot_counts
from ..petsc.options import petsc_message, used_anywhere
from ..petsc.problem import MAX_STEP_SECTIONS_CONTACT, Problem
from . import solver_messages
from .chord import TangentReuse
from .interrupt import RunInterrupted, stop_requested
from .newton import ContactSteps, PhasedNewton
from .options import SolverOptionError, configure_options, refused, run_defaults
from .records import (STALLED_STEP, UNCLEAN_STATE, UNSTABLE_STEP, LoadStepFailure, PathState, StepRecord,
                      reason_name)

#: the rest of the way to a requested level is taken in one step when it is at most this many
#: increments (instead of an increment and a sliver: 100 → 140 → 150 N); measured over the
#: unilateral grid and the sliding columns (docs/contact.md)
STRETCH = 1.5


def first_increment(spec: SolverSpec, share: float | None, first_level: float, last_level: float,
                    predicted: bool) -> float:
    """The first load increment from rest: the first level, or for a law with a
    ``first_increment`` share (unilateral) that share of the first level without the
    complementarity predictor (the held start) and at most that share of the last level with it
    (one step from rest to a far level lands on another equilibrium of the unilateral problem:
    docs/contact.md, stability map); ``solver.initial_increment`` and ``max_increment`` bound it."""
    dlam = first_level
    if share is not None:
        dlam = min(first_level, share * last_level) if predicted else first_level * share
    if spec.initial_increment is not None:
        dlam = min(first_level, spec.initial_increment)
    if spec.max_increment is not None:
        dlam = min(dlam, spec.max_increment)
    return dlam


class LoadStepper:
    """Drives ``problem`` through the requested load factors with one SNES."""

    def __init__(self, problem: Problem, spec: SolverSpec, petsc_options: dict,
                 log: Callable[[str], None] = print, max_level: float = 1.0, linear: str = "direct"):
        self.problem, self.spec, self.log = problem, spec, log
        self.prefix = spec.options_prefix
        self.linear = linear                    # 'direct' | 'fieldsplit' (solving.linear.choose)
        self.snes = PETSc.SNES().create(comm=problem.comm)
        if self.prefix:
            self.snes.setOptionsPrefix(self.prefix)
        self.snes.setFunction(problem.residual, problem.F)
        self.snes.setJacobian(self._jacobian, problem.J, problem.J)
        if spec.merit == "energy" and problem.has_potential:
            # with contact multipliers the residual is the gradient of a Lagrangian (a saddle):
            # line searches then decrease ‖F‖²
            self.snes.setObjective(problem.objective)
        if spec.min_det_f > 0.0:
            self.snes.setLineSearchPreCheck(problem.precheck, kargs={"j_min": spec.min_det_f})
        # absolute tolerance: 1e-10 of the largest requested load, but never below the rounding
        # floor of the residual, measured as ‖F(q0, 0)‖ (exactly zero in exact arithmetic)
        fnorm = problem.fext.norm() * max_level
        self.rounding_floor = problem.reference_residual_norm()
        atol = max(1e-10 * fnorm, 20.0 * self.rounding_floor, 1e-30)
        self.petsc_options = petsc_options
        self._kept_options: list[str] = []
        self.path: PathState | None = None      # where the load path is (``run``)
        self.linesearch, self._kept_options = configure_options(
            self.snes, petsc_options,
            run_defaults(petsc_options, problem.comm.size, atol, self.prefix, linear,
                         saddle_point=problem.n_constraints > 0), self.prefix)
        if problem.contact is not None and self.linesearch == "basic":
            # full Newton steps with contact: the pairing holds for steps small beside a section
            problem.step_sections = MAX_STEP_SECTIONS_CONTACT
        schur = None
        if linear == "fieldsplit":
            # imported here: scipy.linalg is start-up time the direct solver does not need
            from ..petsc.fascicles import fascicle_split
            from ..petsc.fieldsplit import FascicleSchur
            pc = self.snes.getKSP().getPC()
            pc.setType(PETSc.PC.Type.PYTHON)
            schur = FascicleSchur(fascicle_split(problem), problem.comm, self.prefix)
            pc.setPythonContext(schur)
        self._check_factorisation()
        self._history: list[float] = []        # residual norms of the current SNES solve
        self.history: list[float] = []         # ... of all solves of the current increment
        self.snes.setMonitor(self._monitor)
        self.newton_iterations = 0
        #: the fascicle Schur preconditioner (petsc/fieldsplit.py) with solver.linear: fieldsplit
        self.fascicle_schur = schur
        self.chord = TangentReuse(spec.reuse_tangent, schur)
        self.contact_steps = ContactSteps(problem)
        #: the complementarity predictor of a unilateral law's increments (up to
        #: complementarity.MAX_MULTIPLIERS multipliers; solving/newton.py)
        self.predictor = (ComplementarityPredictor(problem, self.snes)
                          if ComplementarityPredictor.applies(problem) else None)
        self.ksp_reason = 0
        self.stalled_at = 0.0                    # |F| of the last step-length stop (messages)
        #: config ``petsc:`` options PETSc never read (known at ``close``)
        self.unused_config_options: list[str] = []

    def _check_factorisation(self) -> None:
        """Create the factor matrix now (no numbers yet), so that a package that cannot factor
        this matrix type on this many ranks is refused before the first load level."""
        ksp = self.snes.getKSP()
        pc = ksp.getPC()
        if pc.getType() not in ("lu", "cholesky", "ilu", "icc"):
            return
        ksp.setOperators(self.problem.J, self.problem.J)
        try:
            pc.setFactorSetUpSolverType()
        except PETSc.Error as exc:
            self.close()
            raise SolverOptionError("", refused(exc, self.petsc_options, self.problem.comm.size,
                                                self.prefix)) from None

    def close(self, collective: bool = True) -> None:
        """Remove the options this stepper left in PETSc's database; config options PETSc never
        read go to ``unused_config_options`` (collective unless ``collective`` is False).  The
        fascicle Schur preconditioner's parallel objects are destroyed here, collectively."""
        opts = PETSc.Options()
        n = len(self.prefix)
        if collective and self.linear == "fieldsplit":
            self.snes.getKSP().getPC().setType(PETSc.PC.Type.NONE)
        if collective:
            mine = [k for k in self._kept_options if k[n:] in self.petsc_options]
            used = used_anywhere(mine, self.problem.comm)
            self.unused_config_options = [k[n:] for k, u in zip(mine, used) if not u]
        for key in self._kept_options:
            opts.delValue(key)
        self._kept_options = []

    def destroy(self) -> None:
        """Free the SNES (with its KSP, PC and factor) and the path's vectors; not collective."""
        if self.path is not None:
            for v in (self.path.X, self.path.dX_last):
                v.destroy()
            self.path = None
        self.snes.destroy()

    def negative_eigenvalues(self) -> int | None:
        """Eigenvalues ≤ 0 of the last factored tangent on the constraint surface: the LDLᵀ
        inertia less one per contact constraint (a saddle-point matrix with m independent
        constraints has m negative eigenvalues besides those of the constrained tangent), plus
        the null pivots (a singular tangent: a mechanism the supports leave free)."""
        counts = pivot_counts(self.snes.getKSP())
        if counts is None:
            return None
        negative, null = counts
        return negative - self.problem.n_constraints + null

    def _monitor(self, snes, its, fnorm):
        self._history.append(float(fnorm))

    def _jacobian(self, snes, X: PETSc.Vec, J: PETSc.Mat, P: PETSc.Mat) -> None:
        """SNES Jacobian callback: the problem's tangent, or none for a chord step (chord.py)."""
        self.chord.jacobian(snes, self._history, lambda: self.problem.jacobian(snes, X, J, P))
        self.contact_steps.next_iterate()

    def describe(self) -> str:
        """The solver in one line (the run's header)."""
        return solver_messages.describe(self)

    def _solve_at(self, lam: float, X: PETSc.Vec, target: float, reached: float,
                  from_rest: bool = False) -> tuple[int, int, float]:
        """Newton at load factor ``lam`` from ``X`` (``newton.PhasedNewton``: the contact law's
        phases).  Returns the last solve's reason, the iterations of all of them and the final
        residual norm; ``history`` the residuals."""
        self.problem.load_factor = lam
        self.history = []
        newton = PhasedNewton(self.contact_steps, lambda Y: self._snes_solve(Y, target, lam, reached),
                              self.predictor, self.linesearch)
        reason, its = newton.solve(X, lam, from_rest)
        self.newton_iterations += its
        return reason, its, self.snes.getFunctionNorm()

    def _snes_solve(self, X: PETSc.Vec, target: float, lam: float, reached: float) -> tuple[int, int]:
        """One SNES solve from ``X``: its reason and iterations."""
        self._history = []
        self.chord.start_solve()
        try:
            self.snes.solve(None, X)
        except PETSc.Error as exc:
            # an error inside PETSc or an external package (a factorisation MUMPS gave up on,
            # a package that cannot handle this matrix); the same on every rank for these
            self.problem.load_factor = reached
            why = petsc_message(exc)
            if mumps_error(self.snes.getKSP()) is not None:
                why += (" (MUMPS could not factor the tangent: it is singular, e.g. a model free to "
                        "move or an integration rule with zero-energy modes)")
            raise LoadStepFailure(target, lam, reached, "PETSC_ERROR", False,
                                  f" in the linear solver ({solver_messages.solver_text(self)}): "
                                  f"{why}") from None
        self.ksp_reason = self.snes.getKSP().getConvergedReason()
        self.history += self._history
        return self.snes.getConvergedReason(), self.snes.getIterationNumber()

    def _stop_if_requested(self, target: float, level: float) -> None:
        """Between Newton solves: stop on every rank if any rank got SIGTERM/SIGINT (collective)."""
        signum = stop_requested(self.problem.comm)
        if signum:
            raise RunInterrupted(signum, f"on the way to load factor {target:g} (last converged "
                                         f"level {level:g})")

    def _residual_small(self, reason: int, fnorm: float) -> bool:
        """A level is accepted at the stated tolerances only: the residual tests (FNORM_ABS,
        FNORM_RELATIVE) pass, and a solve that stopped on the step length (SNORM_RELATIVE: a
        line search that no longer moves) counts only with |F| at the absolute tolerance."""
        rtol, atol, stol, maxit = self.snes.getTolerances()
        if reason in (PETSc.SNES.ConvergedReason.CONVERGED_FNORM_ABS,
                      PETSc.SNES.ConvergedReason.CONVERGED_FNORM_RELATIVE):
            return True
        return fnorm <= atol

    def run(self, levels: list[float], on_level: Callable[[StepRecord], None],
            start: PathState | None = None) -> list[StepRecord]:
        """Reach every level in ``levels`` (increasing); call ``on_level`` after each one.
        ``start``: continue a path (a restart) instead of starting from the reference state."""
        P = self.problem
        self.path = path = start or self.initial_path(levels[0], levels[-1])
        path.X.copy(P.X)
        P.checkpoint()
        records = []
        logging.stage(logging.SOLVE).push()
        try:
            for target in levels:
                rec = self._reach(path, target, records[-1].load_factor if records else path.lam)
                records.append(rec)
                on_level(rec)
        finally:
            logging.stage(logging.SOLVE).pop()
        return records

    def initial_path(self, first_level: float, last_level: float | None = None) -> PathState:
        """The path at the reference state, with the first increment (``first_increment``)."""
        X = self.problem.q0.copy()
        c = self.problem.contact
        dlam = first_increment(self.spec, None if c is None else c.law.first_increment,
                               first_level, last_level or first_level, self.predictor is not None)
        dX = X.duplicate()
        dX.set(0.0)
        return PathState(X=X, dX_last=dX, lam=0.0, dlam=dlam, dlam_last=0.0)

    def _reach(self, path: PathState, target: float, level: float) -> StepRecord:
        """Sub-steps from ``path.lam`` to ``target``: accept converged ones (growing the
        increment after easy ones), cut back failed ones; raises LoadStepFailure."""
        X = self.problem.X
        t0 = time.perf_counter()
        tally = {"its": 0, "substeps": 0, "cutbacks": 0, "consecutive": 0, "stability": 0}
        history = []
        X_prev = X.duplicate()
        try:
            while path.lam < target * (1.0 - 1e-14):
                self._stop_if_requested(target, level)
                step = target - path.lam
                if step > STRETCH * path.dlam:          # else the rest of the way in one step
                    step = path.dlam
                if self.spec.max_increment is not None:
                    step = min(step, self.spec.max_increment)
                X.copy(X_prev)
                if self.spec.predictor == "secant" and path.dlam_last > 0.0:
                    X.axpy(step / path.dlam_last, path.dX_last)       # secant predictor
                reason, its, fnorm = self._solve_at(path.lam + step, X, target, path.lam,
                                                    from_rest=path.lam == 0.0)
                tally["its"] += its
                history.append(list(self.history))
                self._check_budget(path, X_prev, target, step)
                reason, neg = self._judge(path, reason, fnorm, step, tally)
                if reason > 0:
                    self._accept(path, X_prev, step, its, neg, tally)
                else:
                    self._cut_back(path, X_prev, target, step, reason, neg, tally)
        finally:
            X_prev.destroy()
        return StepRecord(load_factor=target, iterations=tally["its"], substeps=tally["substeps"],
                          cutbacks=tally["cutbacks"], reason=reason_name(reason),
                          residual_norm=float(fnorm), wall_time=time.perf_counter() - t0,
                          iteration_history=history, negative_eigenvalues=self.negative_eigenvalues(),
                          increment=path.dlam, last_increment=path.dlam_last)

    def _check_budget(self, path: PathState, X_prev: PETSc.Vec, target: float, step: float) -> None:
        budget = self.spec.max_newton_iterations
        if budget is not None and self.newton_iterations > budget:
            self.problem.load_factor = path.lam
            X_prev.copy(self.problem.X)
            self.problem.restore()
            raise LoadStepFailure(target, path.lam + step, path.lam, "NEWTON_BUDGET_EXCEEDED", False,
                                  f" after {self.newton_iterations} Newton iterations "
                                  f"(solver.max_newton_iterations = {budget})")

    def _judge(self, path: PathState, reason: int, fnorm: float, step: float, tally: dict):
        """The sub-step's verdict: SNES's reason, made a failure when the residual is not small
        (stalled), when a projection did not converge, or when the state is less stable than
        the last accepted one (``UNSTABLE_STEP``, at most ``stability_cutbacks`` per level: a
        stable path does not step onto a saddle, another branch may have been reached)."""
        P = self.problem
        if reason > 0 and not self._residual_small(reason, fnorm):
            reason = STALLED_STEP                       # a step-length stop above the tolerance
            self.stalled_at = fnorm
        converged = reason > 0 and np.isfinite(fnorm) and P.state_is_clean()
        if reason > 0 and not converged:
            reason = UNCLEAN_STATE
        neg = self.negative_eigenvalues() if converged else None
        if (neg is not None and neg > path.accepted_negative
                and tally["stability"] < self.spec.stability_cutbacks):
            tally["stability"] += 1
            reason = UNSTABLE_STEP
        return reason, neg

    def _accept(self, path: PathState, X_prev: PETSc.Vec, step: float, its: int, neg, tally: dict):
        if neg is not None:
            path.accepted_negative = neg
        self.problem.checkpoint()
        self.problem.X.copy(path.dX_last)
        path.dX_last.axpy(-1.0, X_prev)
        path.dlam_last = step
        path.lam += step
        tally["substeps"] += 1
        tally["consecutive"] = 0
        if its <= self.spec.easy_iterations and step >= path.dlam * (1 - 1e-12):
            path.dlam = step * self.spec.growth      # easy: grow (not past targets)

    def _cut_back(self, path: PathState, X_prev: PETSc.Vec, target: float, step: float,
                  reason: int, neg, tally: dict) -> None:
        """Back to the last converged state with half the increment (collective: the reason is
        global); raises LoadStepFailure after ``max_cutbacks`` in a row."""
        P = self.problem
        inverted = bool(P.comm.tompi4py().allreduce(int(P.inverted)))
        lost = bool(P.comm.tompi4py().allreduce(int(P.contact_failed)))
        X_prev.copy(P.X)
        P.restore()
        tally["cutbacks"] += 1
        tally["consecutive"] += reason != UNSTABLE_STEP      # bounded by stability_cutbacks
        path.dlam = 0.5 * step
        why = " (inverted element)" if inverted else (" (contact projection lost)" if lost else "")
        if reason == STALLED_STEP:
            why = (f" (stopped on the step length with |F| {self.stalled_at:.2e} above the "
                   f"tolerance {self.snes.getTolerances()[1]:.1e})")
        if reason == UNSTABLE_STEP:
            why = f" ({neg} negative tangent eigenvalue(s), the last state had {path.accepted_negative})"
        self.log(f"  cut back at load factor {path.lam + step:.6g}: {reason_name(reason)}{why}; "
                 f"retry with increment {path.dlam:.4g}")
        if tally["consecutive"] > self.spec.max_cutbacks or path.dlam < self.spec.min_increment:
            P.load_factor = path.lam
            raise LoadStepFailure(target, path.lam + step, path.lam, reason_name(reason), inverted,
                                  solver_messages.failure_detail(self, reason))
