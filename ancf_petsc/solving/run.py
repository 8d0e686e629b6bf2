"""One run: spec → model → layout → problem → load stepping → results (no argument parsing).

``run_model`` builds a ``Run`` (the model and the PETSc objects of one solve), steps it through
the load levels writing every converged level before the next starts, reports how it ended, and
frees its PETSc objects, so that studies can solve many models in one process.
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field

import numpy as np
from petsc4py import PETSc

from .. import status as st
from ..config.specs import ModelSpec
from ..io.derived import displacement_differences, interface_pairs
from ..io.subtendons import subtendon_report
from ..io.files import DirectoryLock, OutputError, prepare_output_dir
from ..io.restart import check_same_run, read_restart_on_every_rank, restart_directory
from ..io.results import ResultsWriter, record_crash
from ..model.build import build_model
from ..model.contact_setup import contact_for
from ..parallel.partition import make_layout, partition_stats
from ..linalg import logging
from ..contact.kinks import add_normal_turns
from ..contact.reports import end_notes, made_at_the_end
from ..petsc.contact_reports import contact_fields, contact_gaps
from ..linalg.diagnostics import unused_command_line_options
from ..petsc.problem import Problem
from ..petsc.reactions import reaction_entries
from . import solver_messages, step_over
from .given_options import check_given_atol, rest_level_warning
from .interrupt import RunInterrupted
from ..linalg.choice import choose as choose_linear
from ..linalg.options import matrix_type
from .records import LoadStepFailure, PathState, restart_increment, restored_records, spent_before
from .restart_check import check_restart_state
from .stepper import LoadStepper
from .supports import check_supports


@dataclass
class RunResult:
    status: str                 # status.FINAL_STATUSES: completed | failed | interrupted | unstable
    message: str
    summary: dict | None        # rank 0 only
    records: list               # the converged levels' StepRecords
    reason_code: str = st.COMPLETED
    exit_code: int = st.EXIT_OK
    unused_options: list = field(default_factory=list)   # PETSc options never read, as in the summary
    output_dir: str = ""
    inverted: bool = False      # the failure came with an inverted element (J <= 0)


def serial_comm():
    """PETSc's communicator of this process alone (in-process solves of a study)."""
    return PETSc.COMM_SELF


def check_output_dir(path: str, comm, say=lambda *_: None) -> DirectoryLock | None:
    """Fail fast (before the model is built) if ``path`` cannot hold results or another run
    holds it; takes its lock (rank 0: returned, released by the caller).  Collective."""
    err, lock = None, None
    if comm.rank == 0:
        try:
            prepare_output_dir(path)
            lock = DirectoryLock(path)
            lock.acquire()
            if lock.stale:
                say(f"[ancf] {path}: removed {lock.stale}")
        except OutputError as exc:
            err = (exc.path, exc.reason)
    if comm.size > 1:
        err = comm.tompi4py().bcast(err, root=0)
    if err:
        raise OutputError(*err)
    return lock


def final_status(records: list, failure: tuple | None, allow_unstable: bool) -> tuple[str, str, str]:
    """(status, reason code, message) of a run from its converged levels and how it stopped."""
    unstable = [r.load_factor for r in records if r.negative_eigenvalues]
    if failure is not None:
        return failure[:3]
    if unstable and not allow_unstable:
        return ("unstable", st.NEGATIVE_EIGENVALUES,
                f"{len(unstable)} of {len(records)} levels are unstable equilibria (negative tangent "
                f"eigenvalues at load factor {', '.join(f'{x:g}' for x in unstable)}): a buckled "
                "or under-supported model; set solver.allow_unstable: true to accept them")
    switched = [s for r in records for s in r.branch_switches]
    unsettled = [r.load_factor for r in records if r.weights_unsettled]
    passed = [r.passed_over for r in records if r.passed_over]
    notes = [step_over.sentence(passed), solver_messages.unsettled_message(unsettled, len(records))]
    rest = "; ".join(n for n in notes if n)
    if switched:
        return ("completed", st.BRANCH_SWITCHED,
                "; ".join(x for x in (solver_messages.switched_message(switched), rest) if x))
    if rest:
        return "completed", st.LEVELS_PASSED_OVER if passed else st.WEIGHTS_UNSETTLED, f"completed, but {rest}"
    return "completed", st.COMPLETED, "completed"


def _fmt_vec(v) -> str:
    return "[" + ", ".join(f"{x:+.4e}" for x in v) + "]"


class Run:
    """The objects of one solve (built in the PETSc stage "ANCF setup"; collective)."""

    def __init__(self, spec: ModelSpec, comm, say, point=None):
        self.spec, self.comm, self.say, self.point = spec, comm, say, point
        t_start = time.perf_counter()
        logging.stage(logging.SETUP).push()
        try:
            self.model = build_model(spec)
            if point is not None:
                check_same_run(point, self.model, list(spec.steps), spec.output.dir)
            # the contact's lines follow the model header (``describe``): the header comes first
            self.contact_lines: list[str] = []
            self.contact = contact_for(self.model, spec.contact, self.contact_lines.append) \
                if spec.contact else None
            prefix = spec.solver.options_prefix
            self.linear = choose_linear(spec.solver.linear, self.model, self.contact, spec.petsc, prefix)
            # the fascicle-parallel solver keeps every beam whole on one rank
            method = "beams" if self.linear[0] == "fieldsplit" else spec.partition
            self.layout = make_layout(self.model, method, comm.size, comm.rank, self.contact,
                                      comm.tompi4py())
            self.partition = partition_stats(self.layout, self.model, self.contact)
            self.problem = Problem(self.model, self.layout, comm, self.contact,
                                   matrix_type(self.model, spec.solver.matrix, spec.petsc, prefix,
                                               self.linear[0], self.contact is None or self.contact.symmetric))
            self.stepper = None
            if point is None:
                self.model.warnings += check_supports(self.problem)
            self.stepper = LoadStepper(self.problem, spec.solver, spec.petsc, say,
                                       max_level=max(spec.steps), linear=self.linear[0])
            levels = [] if restored_records(point) else spec.steps
            check_given_atol(self.stepper.solver, levels)
            self.model.warnings += rest_level_warning(self.stepper.solver, levels)
        except BaseException:
            self.destroy()
            raise
        finally:
            logging.stage(logging.SETUP).pop()
        self.timings = {"setup": time.perf_counter() - t_start, "output": 0.0}
        self.converged: list = []
        self.writer: ResultsWriter | None = None

    def describe(self) -> None:
        """The model, partition and solver lines of the run's log."""
        model, layout, partition = self.model, self.layout, self.partition
        self.say(f"[ancf] {self.spec.name}: {len(model.beams)} beam(s), {model.n_elements} elements, "
                 f"{model.n_dofs} DOFs, {self.comm.size} rank(s)")
        for line in model.describe():
            self.say("[ancf]   " + line)
        for line in self.contact_lines:
            self.say(line)
        self.say("[ancf]   " + layout.summary((self.spec.raw.get("partition") or {}).get("method")) + (
            f", cut contact pairs {partition['cut_contact_pairs']}/{partition['contact_pairs']}"
            if "contact_pairs" in partition else "") + f", cut beam nodes {partition['cut_beam_nodes']}")
        self.say("[ancf]   " + self.stepper.describe() + "; linear solver %s (%s)" % self.linear)

    def info(self, extra: dict | None) -> dict:
        """What summary.json records about the run besides its levels."""
        spec, model, contact = self.spec, self.model, self.contact
        return {"output_dir": os.path.abspath(spec.output.dir), "twist_deg": spec.twist_deg,
                "dofs": model.n_dofs, "elements": model.n_elements, "ranks": self.comm.size,
                "partition": self.partition, "solver": self.stepper.describe(),
                "tolerances": dict(zip(("rtol", "atol", "stol", "max_it"), self.stepper.solver.snes.getTolerances())),
                "linear_solver": self._linear_solver(),
                "sections": {b.name: {"area": b.section.area, "centroid": b.section.centroid.tolist(),
                                      "points": int(len(b.section.weights))} for b in model.beams},
                "elements_per_beam": {b.name: b.n_elements for b in model.beams},
                "element_types": {b.name: b.element for b in model.beams},
                "twist_axis": list(spec.twist_axis), "geometry": model.geometry_report,
                "contact_interfaces": [itf.name for itf in contact.interfaces] if contact else [],
                **(extra or {})}

    def _linear_solver(self) -> dict:
        """The linear solver's choice and rule; with fieldsplit, its multipliers and how many of
        them lie on the cut between ranks (the interface system, linalg/substructure.py)."""
        out = {"choice": self.linear[0], "rule": self.linear[1]}
        schur = self.stepper.solver.fascicle_schur if self.stepper else None
        if schur is not None:
            sub = schur.schur
            out.update(multipliers=schur.split.n_multipliers, cut_multipliers=sub.n_gamma,
                       interface=type(sub.interface).__name__ if sub.interface else None)
        return out

    def start(self) -> tuple[list[float], PathState | None]:
        """The levels still to reach and, for a restart, the load path to continue."""
        point = self.point
        if point is None:
            return list(self.spec.steps), None
        if self.contact is not None:
            self.contact.restore_state(point.projection, point.status, point.contact_fields)
        path = PathState(X=self.problem.global_vector(point.blocks.ravel()),
                         dX_last=self.problem.global_vector(point.increment_blocks.ravel()),
                         lam=point.load_factor, dlam=point.increment, dlam_last=point.last_increment,
                         accepted_negative=point.accepted_negative, spent=spent_before(point))
        self.stepper.fade_switch.resume(self.stepper, point.pointwise_from, self.spec.output.dir)
        self.stepper.windows.resume(point.window_whole_from)
        if self.stepper.predictor is not None:      # the active set's settled streak (newton.py)
            self.stepper.predictor.settled = point.settled_increments
        check_restart_state(self.problem, self.stepper, point, path.X, self.spec.output.dir)
        if self.stepper.spec.predictor == "tangent":            # the factor the interrupted run had
            self.stepper.tangent.prime(path.X, path.lam, point.previous_contact_fields)
        levels = list(self.spec.steps[len(point.levels):])    # the converged ones start the steps
        path.dlam = restart_increment(point, levels, self.say)
        self.say(f"[ancf] restart from step {point.step} (load factor {point.load_factor:g}) of "
                 f"{self.spec.output.dir}: {len(levels)} level(s) to go")
        return levels, path

    def on_level(self, rec) -> None:
        """Write a converged level (stage "ANCF output") and print its progress line."""
        problem, stepper = self.problem, self.stepper
        logging.stage(logging.OUTPUT).push()
        try:
            t0 = time.perf_counter()
            blocks = problem.gather(blocks=True)
            increment = problem.gather(stepper.path.dX_last, blocks=True)
            q = None if blocks is None else blocks[:self.model.n_nodes]
            gaps = contact_gaps(problem, problem.X)        # collective: every rank its own points
            fields = contact_fields(problem, problem.X)
            extra, reactions = reaction_entries(problem, problem.X)
            if self.spec.history is not None:
                extra["frame"] = self.spec.history.frame_of(rec.load_factor)
                extra["time"] = self.spec.history.time_of(rec.load_factor)
            if q is not None:              # rank 0
                extra["subtendons"] = subtendon_report(self.model, q, rec.load_factor, reactions)
            if gaps is not None:
                extra["contact"] = gaps
                if q is not None:          # rank 0
                    extra["displacement_differences"] = displacement_differences(
                        self.model, q, interface_pairs(self.contact.interfaces))
                    add_normal_turns(gaps, self.contact, q, self.model.connectivity())
            path = None if blocks is None else {
                "blocks": blocks.reshape(-1, self.model.dofs_per_node),
                "increment_blocks": increment.reshape(-1, self.model.dofs_per_node),
                "accepted_negative": stepper.path.accepted_negative,
                "fade_forces_pointwise_from": stepper.fade_switch.at,
                "search_window_whole_from": stepper.windows.at,
                "settled_increments": stepper.predictor and stepper.predictor.settled}
            self.writer.write_step(rec, q, extra, fields, path)
            self.converged.append(rec)
            self.timings["output"] += time.perf_counter() - t0
        finally:
            logging.stage(logging.OUTPUT).pop()
        if self.comm.rank == 0:
            k = len(self.writer.summary["steps"])
            probes = "  ".join(f"{n} u={_fmt_vec(p['displacement'])}"
                               for n, p in self.writer.summary["steps"][-1]["probes"].items())
            unstable = (f"  UNSTABLE: {rec.negative_eigenvalues} negative tangent eigenvalue(s)"
                        if rec.negative_eigenvalues else "")
            where = (f"frame {k}/{len(self.spec.steps)} (t = {self.spec.history.time_of(rec.load_factor):.4g} s)"
                     if self.spec.history is not None else
                     f"step {k}/{len(self.spec.steps)}  load factor {rec.load_factor:.6g}")
            self.say(f"[ancf] {where}  "
                     f"Newton {rec.iterations} in {rec.substeps} substep(s)  {rec.reason}  "
                     f"|F| {rec.residual_norm:.2e}  {rec.wall_time:.2f} s{unstable}  {probes}")
            if k == 1:                      # the first level's plausibility warning, right away
                for note in self.writer.summary["warnings"][len(self.model.warnings):]:
                    self.say(f"[ancf]   {note}")

    def step_through(self, levels: list[float], start: PathState | None) -> tuple[tuple | None, int, bool]:
        """Step through ``levels``: (failure (status, code, message, cause) or None, signal, inverted)."""
        try:
            if levels:
                self.stepper.run(levels, self.on_level, start, (restored_records(self.point) or [None])[-1])
        except LoadStepFailure as exc:
            return ("failed", exc.code, str(exc), exc.cause), 0, exc.inverted
        except RunInterrupted as exc:
            return ("interrupted", st.signal_reason(exc.signum), str(exc), ""), exc.signum, False
        except OutputError as exc:
            return ("failed", st.OUTPUT_ERROR, f"output error: {exc}", ""), 0, False
        except BaseException as exc:
            # a bug (maybe this rank's alone: no collective calls) or a Python session's Ctrl-C
            self.stepper.close(collective=False)
            record_crash(self.writer, *st.crash_status(exc, [r.load_factor for r in self.converged]))
            raise
        return None, 0, False

    def exchange_report(self) -> dict:
        """Ghost node blocks per rank and exchange rebuilds (collective)."""
        lo, hi = self.layout.owned_nodes
        needed = self.problem.exchange.needed
        ghosts = int(np.sum((needed < lo) | (needed >= hi)))
        return {"rebuilds": self.problem.exchange.rebuilds,
                "ghost_nodes_per_rank": self.comm.tompi4py().gather(ghosts, root=0),
                "total_nodes": self.model.n_nodes}

    def destroy(self) -> None:
        """Free the run's PETSc objects (SNES, matrix, vectors, scatters)."""
        if getattr(self, "stepper", None) is not None:
            self.stepper.destroy()
        if getattr(self, "problem", None) is not None:
            self.problem.destroy()


def run_model(spec: ModelSpec, comm=None, log=print, info: dict | None = None,
              restart: str | None = None) -> RunResult:
    """Solve ``spec``; every converged level is on disk before the next one starts.
    ``info`` is stored in summary.json beside the run's own information.  ``restart``: a run's
    output directory to continue from its last converged level (it is the output directory)."""
    comm = PETSc.COMM_WORLD if comm is None else comm
    say = log if comm.rank == 0 else (lambda *_: None)
    point = None
    if restart is not None:
        spec.output.dir = restart_directory(restart, comm)
    lock = check_output_dir(spec.output.dir, comm, say)
    try:
        if restart is not None:
            point = read_restart_on_every_rank(restart, comm)
        return _run(spec, comm, say, info, point)
    finally:
        if lock is not None:
            lock.release()


def _run(spec: ModelSpec, comm, say, info: dict | None, point) -> RunResult:
    """``run_model`` with the output directory held."""
    PETSc.Log.begin()                 # event timings for the summary (cheap)
    logging.view_at_exit(spec.petsc)  # the config's log_view, printed when PETSc finishes
    # PETSc's event times add up over the process: this run's share is the difference
    solver_events0 = logging.event_time("KSPSolve") + logging.event_time("PCSetUp")
    t_start = time.perf_counter()
    run = Run(spec, comm, say, point)
    try:
        run.describe()
        levels, start = run.start()
        rest = None if point or not spec.output.vtk else contact_fields(run.problem, run.problem.q0)  # contact.pvd
        try:
            run.writer = ResultsWriter(run.model, run.layout, comm, run.info(info), point, rest)
        except OutputError:
            run.stepper.close()
            raise
        failure, signum, inverted = run.step_through(levels, start)
        run.stepper.close()
        result = _finish(run, failure, signum, inverted, time.perf_counter() - t_start, solver_events0)
    except BaseException:
        # on several ranks the error may be this rank's alone: destroying the PETSc objects is
        # collective (MUMPS, scatters) and would wait for ranks that never come; ancf-solve
        # aborts MPI instead
        if comm.size == 1:
            run.destroy()
        raise
    run.destroy()
    return result


def _finish(run: Run, failure, signum: int, inverted: bool, total: float, solver_events0: float) -> RunResult:
    """Write the run's final summary and say how it ended (collective)."""
    spec, comm, say, stepper = run.spec, run.comm, run.say, run.stepper
    records = restored_records(run.point) + run.converged    # a restart's earlier levels too
    status, code, message = final_status(records, failure, spec.solver.allow_unstable)
    message += stepper.fade_switch.note() + stepper.windows.note()
    unused = [f"petsc.{k}" for k in stepper.solver.unused_config_options] + unused_command_line_options(comm)
    timings = dict(run.timings, total=total)
    timings["solve"] = timings["total"] - timings["setup"] - timings["output"]
    timings.update(run.problem.timers)
    timings["linear_solve"] = logging.event_time("KSPSolve") + logging.event_time("PCSetUp") - solver_events0
    exchange = run.exchange_report()
    if run.contact is not None and comm.rank == 0 and run.writer.summary["steps"]:
        notes = run.writer.summary["warnings"]
        notes[:] = [w for w in notes if not made_at_the_end(w)]     # a restarted run's, made again
        steps = run.writer.summary["steps"]
        for note in end_notes(run.contact, steps):
            run.writer.summary["warnings"].append(note)
            say(f"[ancf] {note}")
    problem_writing = run.writer.finish(
        status, reason_code=code, message=message, timings=timings,
        newton_iterations=stepper.newton_iterations, tangent_reuses=stepper.solver.chord.count,
        residual_evaluations=run.problem.residual_evaluations, preconditioner_reuses=stepper.solver.chord.kept,
        factor_reanalyses=stepper.solver.factor_reanalyses, exchange=exchange,
        failure_cause=failure[3] if failure is not None else "", jacobian_pattern_growths=run.problem.pattern_growths,
        unstable_levels=[r.load_factor for r in records if r.negative_eigenvalues],
        allow_unstable=spec.solver.allow_unstable,
        stability_checked=bool(records) and all(r.negative_eigenvalues is not None for r in records),
        **stepper.fade_switch.summary(stepper), **stepper.windows.summary(),
        unused_petsc_options=unused)
    if comm.size > 1:
        problem_writing = comm.tompi4py().bcast(problem_writing, root=0)
    if problem_writing:
        status, code, message = "failed", st.OUTPUT_ERROR, f"output error: {problem_writing}"
    if comm.size > 1:
        say(f"[ancf] exchange: node blocks received per rank {exchange['ghost_nodes_per_rank']} of "
            f"{run.model.n_nodes}; rebuilt {exchange['rebuilds']} times (the set of projected-on "
            "elements changed)")
    reuses = ", ".join(f"{n} with the last {what}" for n, what in
                       ((stepper.solver.chord.count, "tangent"), (stepper.solver.chord.kept, "preconditioner")) if n)
    reuses = f" ({reuses})" if reuses else ""
    say(f"[ancf] {status}: {message}; {stepper.newton_iterations} Newton iterations{reuses}, "
        f"{timings['total']:.2f} s (setup {timings['setup']:.2f} s); results in {spec.output.dir}")
    return RunResult(status, message, run.writer.summary if comm.rank == 0 else None, records, code,
                     st.exit_code(status, code, signum), unused, spec.output.dir, inverted)
