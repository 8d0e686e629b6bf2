"""The SNES of a solve: one Newton solver for a Problem, its PETSc options and callbacks.

``SNESSolver`` creates the SNES with the residual and Jacobian of the Problem, puts the options in
(command line > config ``petsc:`` > the defaults of options.py and of the model's laws, e.g. a
line search for friction), sets the line-search pre-check, the energy merit where there is a
potential, the fascicle Schur preconditioner (``solver.linear: fieldsplit``) and chord steps near
convergence (chord.py), and counts the tangent's negative eigenvalues (its inertia).  ``solve``
is one SNES solve from a state; the load stepping around it is stepper.py.
"""
from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

from ..config.specs import SolverSpec
from ..linalg.compact_factor import install_for, release_python_pc
from ..linalg.database import remove
from ..linalg.diagnostics import petsc_message, used_anywhere
from ..linalg.full_step_first import install_full_step_first
from ..linalg.inertia import counts_inertia, exact_pivot_counts, mumps_error, solver_pivot_counts
from ..petsc.mixed_tangent import mixed_tangent
from ..petsc.potential import rounding_floor
from ..petsc.problem import Problem
from . import solver_messages
from .chord import TangentReuse
from .continuity import IterateTrail
from .cycle_stop import DEFAULT_DIVTOL, WANDER_WINDOW, CycleStop
from .interrupt import RunInterrupted, stop_requested
from .contact_steps import ContactSteps
from ..linalg.options import DEFAULT_OPTIONS, SolverOptionError, configure_options, refused, run_defaults
from .records import LoadStepFailure


def absolute_tolerance(load_norm: float, floor: float) -> float:
    """The absolute tolerance of a run: 1e-10 of the largest load, at least 20 x the residual's
    rounding floor."""
    return max(1e-10 * load_norm, 20.0 * floor, 1e-30)


def stop_window(contact) -> tuple[int, float] | None:
    """The wandering window and the divergence tolerance (unless an option sets one) of
    ``CycleStop`` for a contact, or None (PETSc's own test): friction's state-dependent bounds
    (PETSc's divtol 1e4, as since issue 39), else a law that decides the active set (its
    ``wander_window``; the run's default divtol, off)."""
    if contact is None:
        return None
    if any(t.bounded for t in contact.terms):
        return WANDER_WINDOW, DEFAULT_DIVTOL
    window = contact.law.wander_window
    return None if window is None else (window, float(DEFAULT_OPTIONS["snes_divergence_tolerance"]))


def budget_left(budget: int | None, spent: int, snes: PETSc.SNES) -> tuple[int, int]:
    """(-snes_max_it, the iterations the next solve may take): capped so that the run's SNES
    iterations pass ``solver.max_newton_iterations`` by one at most (the stepper's over_budget
    then stops it); checked between solves only, a friction history with a budget of 110 ran to
    197."""
    maxit = snes.getTolerances()[3]
    return maxit, (maxit if budget is None else min(maxit, budget + 1 - spent))


def confirmed_count(solver, count: int) -> int:
    """The negative tangent eigenvalues ``count`` read from the factors, confirmed with J's own
    LDLᵀ where the fascicle Schur factors counted J − K_×'s (linalg/fieldsplit.py) and found some:
    the contact curvature between fascicles tips it (the paper's tendon at 2 elements, sliding:
    1 negative eigenvalue of J − K_× at 100 and 400 N, none of J)."""
    if count <= 0 or solver.fascicle_schur is None:
        return count
    exact = exact_pivot_counts(solver.problem.J)
    return count if exact is None else exact[0] - solver.problem.n_constraints + exact[1]


class SNESSolver:
    """One SNES for ``problem`` (its options, callbacks, preconditioner and counters)."""
    _where: str = "in a Newton solve"           # the solve under way, for an interruption (_monitor)
    spent: int = 0                              # SNES iterations so far: solver.max_newton_iterations' cap

    def __init__(self, problem: Problem, spec: SolverSpec, petsc_options: dict, max_level: float = 1.0,
                 linear: str = "direct", floor: float | None = None):
        self.problem, self.spec = problem, spec
        self.prefix = spec.options_prefix
        self.linear = linear                    # 'direct' | 'fieldsplit' (linalg.choice.choose)
        self.snes = PETSc.SNES().create(comm=problem.comm)
        if self.prefix:
            self.snes.setOptionsPrefix(self.prefix)
        self.snes.setFunction(problem.residual, problem.F)
        self.snes.setJacobian(self._jacobian, problem.J, problem.J)
        objective = spec.merit == "energy" and problem.has_potential
        if objective:
            # with contact multipliers the residual is the gradient of a Lagrangian (a saddle):
            # line searches then decrease ‖F‖²
            self.snes.setObjective(problem.objective)
        # absolute tolerance: 1e-10 of the largest load, at least the residual's rounding floor ‖F(q0, 0)‖
        # (zero in exact arithmetic; ``floor``: the replaced solver's, not re-measured mid-run, fade_switch.py)
        self.load_norm = problem.loads.scale(max_level)
        self.rounding_floor = rounding_floor(problem) if floor is None else floor
        atol = self.own_atol = absolute_tolerance(self.load_norm, self.rounding_floor)
        self.petsc_options = petsc_options
        self._history: list[float] = []        # residual norms of the current SNES solve
        self.trail = IterateTrail()             # its last iterates: a failed level's jump scan
        #: friction, unilateral contact: a Newton cycle or wandering ends the solve early
        #: (cycle_stop.py; set before the options, so that -snes_convergence_test replaces it)
        self.cycle_stop, stop = None, stop_window(problem.contact)
        if stop is not None:
            self.cycle_stop = CycleStop(lambda: self._history, petsc_options, self.prefix, *stop)
            self.snes.setConvergenceTest(self.cycle_stop)
        self.linesearch, self._kept_options = configure_options(
            self.snes, petsc_options,
            run_defaults(petsc_options, problem.comm.size, atol, self.prefix, linear,
                         saddle_point=problem.n_constraints > 0, symmetric=problem.symmetric,
                         law_defaults=problem.solver_defaults), self.prefix,
            problem.symmetric)
        self.full_step_first = install_full_step_first(        # friction's l2, whole step first
            self.snes, self.linesearch, spec.full_step_first and not objective, self.prefix)
        if problem.limits.configure(spec.min_det_f, spec.section_update, self.linesearch, spec.band_step):
            self.snes.setLineSearchPreCheck(problem.limits.precheck)
        schur = None
        if linear == "fieldsplit":
            # imported here: scipy.linalg is start-up time the direct solver does not need
            from ..linalg.fascicles import fascicle_split
            from ..linalg.fieldsplit import FascicleSchur
            pc = self.snes.getKSP().getPC()
            pc.setType(PETSc.PC.Type.PYTHON)
            schur = FascicleSchur(fascicle_split(problem), problem.comm, self.prefix)
            pc.setPythonContext(schur)
        self.compact = None                    # linalg/compact_factor.py's context, where it applies
        self._check_factorisation()
        self.history: list[float] = []         # ... of all solves of the current increment
        self.snes.setMonitor(self._monitor)
        self.fascicle_schur = schur            # linalg/fieldsplit.py (solver.linear: fieldsplit)
        self.chord = TangentReuse(spec.reuse_tangent, schur)
        problem.mixed = mixed_tangent(spec.tangent)     # solver.tangent (petsc/mixed_tangent.py)
        self.contact_steps = ContactSteps(problem)
        self.ksp_reason, self.stalled_at = 0, 0.0   # the last KSP reason, |F| of a step-length stop
        self.assemblies = self.accepted_assemblies = 0   # tangents factored; at the last accept
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
                                                self.prefix, self.problem.symmetric)) from None
        self.compact = install_for(self.problem, ksp, self.spec.compact_factor, self.prefix)

    @property
    def factor_reanalyses(self) -> int:
        """Analyses of the compact factor for scalings gone stale (linalg/compact_factor.py)."""
        return self.compact.reanalyses if self.compact is not None else 0

    def close(self, collective: bool = True) -> None:
        """Remove this stepper's options from PETSc's database (config ones PETSc never read go to
        ``unused_config_options``) and the fascicle Schur PC's parallel objects (collective)."""
        n = len(self.prefix)
        if collective and self.linear == "fieldsplit":
            self.snes.getKSP().getPC().setType(PETSc.PC.Type.NONE)
        if collective:
            mine = [k for k in self._kept_options if k[n:] in self.petsc_options]
            used = used_anywhere(mine, self.problem.comm)
            self.unused_config_options = [k[n:] for k, u in zip(mine, used) if not u]
        for key in self._kept_options:
            remove(key)
        self._kept_options = []

    def destroy(self) -> None:
        """Free the SNES (with its KSP, PC and factor); not collective.  On one rank a Python PC
        lets go of its context first: a wrapper of this SNES kept by a traceback's frames left it
        to PETSc's final clean-up, after Python had finalised (a SEGV at exit)."""
        release_python_pc(self.snes.getKSP(), self.problem.comm)
        self.trail.destroy()
        self.snes.destroy()

    @property
    def last_solve_history(self) -> list[float]:
        """|F| of every iterate of the last SNES solve (its failure message reads it)."""
        return list(self._history)

    def negative_eigenvalues(self, X: PETSc.Vec | None = None, own: bool = False) -> int | None:
        """Eigenvalues ≤ 0 of the last factored tangent on the constraint surface: the LDLᵀ inertia
        less one per contact constraint (m independent constraints give m negative eigenvalues
        besides the constrained tangent's), plus the null pivots (a mechanism the supports leave
        free).  ``X``: the converged state, factored first where the last factor is no Newton
        iterate of it (``factor_at``), or (``own``) is not X's own."""
        if X is not None and not self.factor_at(X, own):
            return None
        counts = solver_pivot_counts(self.snes, self.problem.symmetric)
        if counts is None:
            return None
        negative, null = counts
        return confirmed_count(self, negative - self.problem.n_constraints + null)

    def accepted(self) -> None:
        """The stepper accepted the state the last solve converged to."""
        self.accepted_assemblies = self.assemblies

    def factor_at(self, X: PETSc.Vec, own: bool = False) -> bool:
        """Factor the tangent at X (the converged state of the last solve) when that solve took
        no Newton iteration and a tangent was factored since the last accepted state: the factor
        is then another state's, a failed attempt's iterate (after a cut-back a unilateral
        increment can converge in its complementarity prediction alone, which factors K with its
        own solver) or an earlier solve's of this attempt.  Its inertia had stopped the second
        subject's 135 deg gastrocnemius-biased unilateral column at 37.75 N (UNSTABLE_STATE, one
        negative eigenvalue: the diverging attempt's before it).  Without a factor since the
        accepted state (a stride frame whose loads did not change) that state's is kept.  The
        contact status is kept (the stepper has checked it at X).  False where the factorisation
        failed (no count, as for a solver without inertia).  With ``solver.tangent: mixed`` a
        factor whose tangent was corrected (petsc/mixed_tangent.py) is replaced too (``own``: any).  Collective."""
        mixed = self.problem.mixed is not None and counts_inertia(self.snes, self.problem.symmetric) \
            and self.problem.comm.tompi4py().allreduce(self.problem.mixed.corrected, op=MPI.LOR)
        if not (mixed or own) and (self.snes.getIterationNumber() > 0 or self.assemblies == self.accepted_assemblies):
            return True
        if self.fascicle_schur is not None:
            self.fascicle_schur.keep_factors = False
        J, P, _ = self.snes.getJacobian()
        ksp = self.snes.getKSP()
        try:
            self._assemble_at(X, J, P)
            ksp.setOperators(J, P)
            ksp.setUp()
        except PETSc.Error:                     # the same on every rank (MUMPS's own error)
            return False
        return True

    def tangent_at(self, X: PETSc.Vec) -> PETSc.Mat | None:
        """The tangent at X assembled into the SNES's preconditioning matrix (returned); nothing
        is factored.  None where that is no assembled matrix (``-snes_mf``).  Collective."""
        J, P, _ = self.snes.getJacobian()
        if P.getType() in (PETSc.Mat.Type.MFFD, PETSc.Mat.Type.SHELL, PETSc.Mat.Type.PYTHON):
            return None
        self._assemble_at(X, J, P)
        return P

    def _assemble_at(self, X: PETSc.Vec, J: PETSc.Mat, P: PETSc.Mat) -> None:
        """The Jacobian at X with the contact status kept (the stepper has checked it at X)."""
        c = self.problem.contact
        update = c is not None and c.allow_update
        if c is not None:
            c.allow_update = False
        try:
            self._assemble(self.snes, X, J, P)
        finally:
            if c is not None:
                c.allow_update = update

    def _assemble(self, snes, X: PETSc.Vec, J: PETSc.Mat, P: PETSc.Mat) -> None:
        self.assemblies += 1
        self.problem.jacobian(snes, X, J, P)

    def _monitor(self, snes, its, fnorm):
        self._history.append(float(fnorm))
        self.trail.record(its, snes.getSolution(), fnorm)
        # SIGTERM/SIGINT at every iteration (collective): mpirun sends SIGKILL 1 s after the SIGTERM
        # it forwards, and a friction column's solves take seconds (interrupt.py)
        signum = stop_requested(self.problem.comm)
        if signum:
            raise RunInterrupted(signum, self._where)

    def _jacobian(self, snes, X: PETSc.Vec, J: PETSc.Mat, P: PETSc.Mat) -> None:
        """SNES Jacobian callback: the problem's tangent, or none for a chord step (chord.py)."""
        mixed = self.problem.mixed
        if mixed is not None:                   # the Newton iterate the tangent is formed at
            mixed.iterate = (mixed.solves, snes.getIterationNumber())
        try:
            self.chord.jacobian(snes, self._history, lambda: self._assemble(snes, X, J, P))
        finally:
            if mixed is not None:
                mixed.iterate = None
        self.contact_steps.next_iterate()

    def describe(self) -> str:
        """The solver in one line (the run's header)."""
        return solver_messages.describe(self)

    def solve(self, X: PETSc.Vec, target: float, lam: float, reached: float) -> tuple[int, int]:
        """One SNES solve from ``X`` at ``lam`` (from ``reached`` to ``target``): reason, iterations."""
        self._history = []
        self._where = f"in the Newton solve at load factor {lam:g} (last converged {reached:g})"
        maxit, left = budget_left(self.spec.max_newton_iterations, self.spent, self.snes)
        if left <= 0:                           # the stepper stops the run (over_budget)
            return PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT, 0
        self.chord.start_solve()
        if self.problem.mixed is not None:
            self.problem.mixed.start_solve()
        try:
            self.snes.setTolerances(max_it=left)
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
        finally:
            self.snes.setTolerances(max_it=maxit)
            self.spent += self.snes.getIterationNumber()
        self.ksp_reason = self.snes.getKSP().getConvergedReason()
        self.history += self._history
        return self.snes.getConvergedReason(), self.snes.getIterationNumber()

    def residual_small(self, reason: int, fnorm: float) -> bool:
        """A level is accepted at the stated tolerances only: the residual tests (FNORM_ABS,
        FNORM_RELATIVE) pass, and a solve that stopped on the step length (SNORM_RELATIVE: a
        line search that no longer moves) counts only with |F| at the absolute tolerance."""
        rtol, atol, stol, maxit = self.snes.getTolerances()
        if reason in (PETSc.SNES.ConvergedReason.CONVERGED_FNORM_ABS,
                      PETSc.SNES.ConvergedReason.CONVERGED_FNORM_RELATIVE):
            return True
        return fnorm <= atol

