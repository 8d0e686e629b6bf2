"""Many solves of one model in one process: a calibration's samples.

A ``SampleSolver`` keeps one ``Run`` (the model, the contact set-up, the layout, the Jacobian with
its preallocated pattern, the SNES with its factorisation) for every parameter set it is given.
A new spec that differs from the current one only in values the run can take in place
(``IN_PLACE``: the material laws) is applied to it: the element blocks get the new laws, the
tolerance its new rounding floor, and the matrix, its pattern, the symbolic factorisation and the
contact points stay.  Any other change builds the run again.

Each level is solved either by load stepping from the reference (cold, as ``ancf-solve`` does) or
from a given start state (a warm start: the converged state of a nearby parameter set at that
level, or a prediction from several).  A warm level that does not converge stably is solved
again by load stepping from this sample's previous level, so a warm start changes the cost of a
solve, never which equilibrium it finds beyond the solver's tolerance; a contact law with a
history (Coulomb friction) follows its load path, so its samples are always solved cold, each
from the reference's history.  Nothing is written to disk.  Serial: every sample is solved on a communicator of one rank (one sample per rank).
"""
from __future__ import annotations

import time
from contextlib import ExitStack
from types import SimpleNamespace
from dataclasses import dataclass, field

import numpy as np

from petsc4py import PETSc

from .. import status as st
from ..config.specs import ModelSpec
from ..contact.partners import HISTORY
from ..linalg.database import option, own_prefix
from ..model.fibre_setup import set_fibre_directions
from ..petsc.blocks import refresh_parts
from ..petsc.potential import rounding_floor
from ..physics.laws import make_material
from .records import LoadStepFailure, PathState, StepRecord, reason_name
from .run import Run, serial_comm
from . import step_over
from .snes_solver import absolute_tolerance
from .stepper import LoadStepper


@dataclass
class LevelState:
    """A converged level: every block of the state in model order (n_blocks, V, 3) and the
    contact's projection state, multiplier status and its terms' history (a friction law's
    anchors, as ``Contact.restore_state`` reads them; None without contact)."""
    x: np.ndarray
    projection: np.ndarray | None = None
    status: np.ndarray | None = None
    history: dict | None = None


@dataclass
class SampleOutcome:
    """How one parameter set solved: its status and reason code (``status.py``), the levels it
    reached with every probe's displacement and value there, and its converged states."""
    status: str                               # completed | failed | unstable
    reason_code: str
    message: str
    load_factors: list[float]
    displacements: dict[str, np.ndarray]      # probe → (levels reached, 3) [m]
    values: dict[str, np.ndarray]             # probe → (levels reached, 3) the nodal vector
    states: list[LevelState] = field(default_factory=list)
    inverted: bool = False
    newton_iterations: int = 0
    warm_levels: int = 0                      # levels solved from their start state
    fallbacks: int = 0                        # warm levels solved again by load stepping
    rebuilt: bool = False                     # the run was (re)built for this sample
    wall_time: float = 0.0
    cpu_time: float = 0.0                     # this process's CPU seconds for the sample
    #: levels reported past a gap of the load path: (level, last converged, reported at), step_over.py
    passed_over: list = field(default_factory=list)


def changed_paths(a, b, prefix: tuple = ()) -> list[tuple]:
    """Key paths (tuples of keys and indices) where two config trees differ."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = []
        for k in dict.fromkeys(list(a) + list(b)):
            if k not in a or k not in b:
                out.append(prefix + (k,))
            else:
                out += changed_paths(a[k], b[k], prefix + (k,))
        return out
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return [p for i, (x, y) in enumerate(zip(a, b)) for p in changed_paths(x, y, prefix + (i,))]
    return [] if a == b else [prefix]


def _matches(path: tuple, pattern: tuple) -> bool:
    """``path`` lies under ``pattern`` (``int`` in a pattern matches any index)."""
    return len(path) >= len(pattern) and all(
        isinstance(t, int) if p is int else t == p for t, p in zip(path, pattern))


def _update_materials(solver: "SampleSolver", spec: ModelSpec, paths: list[tuple]) -> None:
    """New material laws of the beams ``paths`` name, in the built run (fibres set up again)."""
    run = solver.run
    beams = sorted({p[1] for p in paths})
    for i in beams:
        beam = run.model.beams[i]
        beam.material = make_material(spec.beams[i].material)
        set_fibre_directions(beam, run.spec.length, run.spec.twist_deg, run.spec.twist_axis)
        run.spec.beams[i].material = spec.beams[i].material
    refresh_parts(run.problem.blocks, run.model, run.layout, beams)
    run.problem.limits.find_fibres()


#: config values a built run takes in place: (key-path pattern, updater).  A parameter of
#: another kind (e.g. an interface law's coefficient) becomes in-place by an entry here.
IN_PLACE = (
    (("beams", int, "material"), _update_materials),
)
#: config parts that do not change the solve (nothing is written)
IGNORED = (("output",),)


def refresh_tolerance(stepper: LoadStepper) -> None:
    """After material parameters changed in place: the residual's rounding floor (it scales with
    the stiffness) and the absolute tolerance again, as a new run would set them; an snes_atol
    given on the command line or in ``petsc:`` stays (collective)."""
    key, S = "snes_atol", stepper.solver
    if option(key, S.prefix) is not None or key in S.petsc_options:
        return
    S.rounding_floor = rounding_floor(stepper.problem)
    atol = absolute_tolerance(S.load_norm, S.rounding_floor)
    S.snes.setTolerances(atol=float(f"{atol:.3e}"))      # as the options string sets it


def contact_state(c) -> tuple | None:
    """(projection, status, the terms' history fields) of the contact's current state, as
    ``Contact.restore_state`` takes them (None without contact)."""
    if c is None:
        return None
    history = {HISTORY + k: v.copy() for t in c.terms for k, v in t.state.items()}
    return c.projector.state().copy(), c.status.copy(), history


def path_dependent(c) -> bool:
    """Whether the contact has a term with a history (Coulomb friction): its answer at a level
    depends on the path to it, so a level is not solved from another sample's state."""
    return c is not None and any(t.state for t in c.terms)


def solve_level(stepper: LoadStepper, lam: float) -> StepRecord | None:
    """Newton at load factor ``lam`` from the problem's current state X (a warm start, with its
    contact state).  Its record when it converges at the stated tolerances to a stable state
    (then checkpointed); else None, with X and the contact state back at the last checkpoint
    (collective: every decision is on global norms and reasons)."""
    P = stepper.problem
    t0 = time.perf_counter()
    X0 = P.X.copy()
    try:
        reason, its, fnorm = stepper.solve_at(lam, P.X, lam, lam)
    except LoadStepFailure:                 # PETSc or MUMPS gave up
        reason, its, fnorm = PETSc.SNES.ConvergedReason.DIVERGED_FUNCTION_DOMAIN, 0, np.nan
    ok = (reason > 0 and np.isfinite(fnorm) and stepper.solver.residual_small(reason, fnorm)
          and P.state_is_clean())
    neg = stepper.solver.negative_eigenvalues(P.X) if ok else None      # the state's own count
    if not ok or (neg is not None and neg > 0):
        X0.copy(P.X)
        X0.destroy()
        P.restore()
        return None
    X0.destroy()
    stepper.solver.accepted()
    P.checkpoint()
    return StepRecord(load_factor=lam, iterations=its, substeps=1, cutbacks=0, reason=reason_name(reason),
                      residual_norm=float(fnorm), wall_time=time.perf_counter() - t0,
                      iteration_history=[list(stepper.history)], negative_eigenvalues=neg,
                      tresca_solves=stepper.tresca_solves, weights_unsettled=stepper.unsettled)


class SampleSolver:
    """One model solved for many parameter sets (module docstring); serial."""

    def __init__(self, comm=None, log=lambda *_: None):
        self.comm = serial_comm() if comm is None else comm
        if self.comm.getSize() != 1:
            raise ValueError("a SampleSolver solves on one rank (one sample per rank)")
        self.log = log
        self.run: Run | None = None
        self.raw: dict | None = None            # the config the run holds now
        self.initial_contact = None             # (projection, status, history) of the reference
        self.builds = 0                         # how often a run was built
        self.options = ExitStack()              # the run's options prefix (``_prepare``)

    def destroy(self) -> None:
        """Free the run's PETSc objects."""
        if self.run is not None:
            self.run.stepper.close()
            self.run.destroy()
            self.run = None
        self.options.close()

    def _prepare(self, spec: ModelSpec) -> bool:
        """The run for ``spec``: the current one updated in place when it can be, else a new
        one; True when it was built (config errors propagate)."""
        if self.run is not None:
            paths = [p for p in changed_paths(self.raw, spec.raw)
                     if not any(_matches(p, pat) for pat in IGNORED)]
            groups: dict = {}
            for p in paths:
                updater = next((u for pat, u in IN_PLACE if _matches(p, pat)), None)
                if updater is None:
                    break
                groups.setdefault(updater, []).append(p)
            else:
                for updater, ps in groups.items():
                    updater(self, spec, ps)
                if groups:
                    refresh_tolerance(self.run.stepper)
                self.raw = spec.raw
                return False
            self.destroy()
        # the run's PETSc options under its own prefix while it lives (linalg.database.own_prefix)
        self.options.enter_context(own_prefix(spec.solver, "sample"))
        self.run = Run(spec, self.comm, self.log)
        self.raw, self.builds = spec.raw, self.builds + 1
        c = self.run.contact
        self.initial_contact = contact_state(c)
        return True

    def solve(self, spec: ModelSpec, start: list[LevelState | None] | None = None) -> SampleOutcome:
        """Solve ``spec`` at its load levels (``spec.steps``), cold or from ``start`` (one state
        or None per level).  Raises ``RunInterrupted`` on a signal and input errors of the spec."""
        t0, c0 = time.perf_counter(), time.process_time()
        rebuilt = self._prepare(spec)
        run = self.run
        # solver.max_newton_iterations is per sample
        run.stepper.newton_iterations = run.stepper.solver.spent = 0
        levels = [float(s) for s in spec.steps]
        out = SampleOutcome("completed", st.COMPLETED, "completed", [], {}, {}, rebuilt=rebuilt)
        records = []
        try:
            # a law with a history (friction) answers along its load path: no warm starts
            if start is None or all(s is None for s in start) or path_dependent(run.contact):
                self._set_contact(self.initial_contact)
                run.stepper.release_path()
                run.stepper.run(levels, lambda rec: records.append(self._record(rec, out)))
            else:
                self._warm(levels, start, records, out)
        except LoadStepFailure as exc:
            out.status, out.reason_code, out.message, out.inverted = "failed", exc.code, str(exc), exc.inverted
        unstable = [r.load_factor for r in records if r.negative_eigenvalues]
        out.passed_over = [tuple(r.passed_over) for r in records if r.passed_over]
        if out.status == "completed" and unstable and not spec.solver.allow_unstable:
            out.status, out.reason_code = "unstable", st.NEGATIVE_EIGENVALUES
            out.message = f"negative tangent eigenvalues at load factor {unstable[0]:g}"
        elif out.status == "completed" and out.passed_over:
            out.reason_code = st.LEVELS_PASSED_OVER
            out.message = f"completed, but {step_over.sentence(out.passed_over)}"
        out.newton_iterations = run.stepper.newton_iterations
        for name in run.model.probes:
            out.displacements[name] = np.array(out.displacements.get(name, [])).reshape(-1, 3)
            out.values[name] = np.array(out.values.get(name, [])).reshape(-1, 3)
        out.wall_time, out.cpu_time = time.perf_counter() - t0, time.process_time() - c0
        return out

    def _warm(self, levels: list[float], start: list, records: list, out: SampleOutcome) -> None:
        """Each level from its start state; a level that does not converge (or has none) by
        load stepping from this sample's previous level."""
        run = self.run
        P, stepper = run.problem, run.stepper
        for k, lam in enumerate(levels):
            last = records[-1] if records else None     # a level its step over passed: with it, as cold
            rec = None if last is None else step_over.behind(stepper, SimpleNamespace(
                lam=last.load_factor, dlam=last.increment, dlam_last=last.last_increment), lam, last)
            if rec is None and start[k] is not None:
                self._set_state(start[k])
                P.load_factor = lam
                rec = solve_level(stepper, lam)
                out.warm_levels += rec is not None
            if rec is None:
                out.fallbacks += start[k] is not None
                path = self._path_from(out, levels, k)
                stepper.release_path()
                rec = stepper.run([lam], lambda r: None, start=path)[-1]
            records.append(self._record(rec, out))

    def _path_from(self, out: SampleOutcome, levels: list[float], k: int) -> PathState | None:
        """The load path at this sample's level k − 1, at its reported load factor (None: from
        the reference)."""
        if k == 0:
            self._set_contact(self.initial_contact)
            return None
        s, lam = out.states[k - 1], out.load_factors[k - 1]
        self._set_contact(None if s.projection is None else (s.projection, s.status, s.history))
        P = self.run.problem
        X = P.global_vector(s.x.reshape(-1))
        dX = X.duplicate()
        dX.set(0.0)
        return PathState(X=X, dX_last=dX, lam=lam, dlam=levels[k] - lam, dlam_last=0.0)

    def _set_contact(self, state) -> None:
        c = self.run.contact
        if c is not None and state is not None:
            c.restore_state(*state)

    def _set_state(self, s: LevelState) -> None:
        """The problem's state X (and contact state) from a level state in model order."""
        P = self.run.problem
        lo, hi = self.run.layout.owned_nodes
        inv = np.argsort(self.run.layout.perm)[lo:hi]
        P.X.setArray(s.x.reshape(-1, P.model.dofs_per_node)[inv].ravel())
        self._set_contact(None if s.projection is None else (s.projection, s.status, s.history))

    def _record(self, rec, out: SampleOutcome):
        """Probes and the state of a converged level into ``out``."""
        run = self.run
        x = run.problem.X.getArray(readonly=True).reshape(-1, run.model.block.vectors_per_node, 3)[run.layout.perm]   # model order
        for name, (u, v) in run.model.probe_values(x).items():
            out.displacements.setdefault(name, []).append(u)
            out.values.setdefault(name, []).append(v)
        out.states.append(LevelState(x.copy(), *(contact_state(run.contact) or ())))
        out.load_factors.append(rec.load_factor)
        return rec
