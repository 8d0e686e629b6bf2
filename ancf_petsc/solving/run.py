"""One run: spec → model → layout → problem → load stepping → results (no argument parsing)."""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field

import numpy as np
from petsc4py import PETSc

from .. import status as st
from ..petsc.problem import STAGE_ASSEMBLY, Problem
from ..config.specs import ModelSpec
from ..errors import InputError
from .interrupt import RunInterrupted
from ..parallel.partition import make_layout, partition_stats
from ..model.build import build_model
from ..io.results import OutputError, ResultsWriter, prepare_output_dir
from ..petsc.options import unused_command_line_options
from .stepper import STAGE_SOLVE, LoadStepFailure, LoadStepper, matrix_type

STAGE_SETUP = PETSc.Log.Stage("ANCF setup")
STAGE_OUTPUT = PETSc.Log.Stage("ANCF output")


def petsc_event_time(name: str) -> float:
    """Seconds spent in a PETSc log event, summed over all stages (logging is on, see run_model)."""
    ev = PETSc.Log.Event(name)
    stages = [0] + [st.id for st in (STAGE_SETUP, STAGE_OUTPUT, STAGE_SOLVE, STAGE_ASSEMBLY)]
    return float(sum(ev.getPerfInfo(sid)["time"] for sid in sorted(set(stages))))


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


def check_output_dir(path: str, comm) -> None:
    """Fail fast (before the model is built) if ``path`` cannot hold results; collective."""
    err = None
    if comm.rank == 0:
        try:
            prepare_output_dir(path)
        except OutputError as exc:
            err = (exc.path, exc.reason)
    if comm.size > 1:
        err = comm.tompi4py().bcast(err, root=0)
    if err:
        raise OutputError(*err)


def _final_status(records: list, failure: tuple | None, allow_unstable: bool) -> tuple[str, str, str]:
    """(status, reason code, message) of a run from its converged levels and how it stopped."""
    unstable = [r.load_factor for r in records if r.negative_eigenvalues]
    if failure is not None:
        return failure
    if unstable and not allow_unstable:
        return ("unstable", st.NEGATIVE_EIGENVALUES,
                f"{len(unstable)} of {len(records)} levels are unstable equilibria (negative tangent "
                f"eigenvalues at load factor {', '.join(f'{x:g}' for x in unstable)}): a buckled "
                "or under-supported model; set solver.allow_unstable: true to accept them")
    return "completed", st.COMPLETED, "completed"


def _fmt_vec(v) -> str:
    return "[" + ", ".join(f"{x:+.4e}" for x in v) + "]"


def solve(spec: ModelSpec, comm=PETSc.COMM_WORLD, log=print, restart: str | None = None) -> RunResult:
    """Solve ``spec``; with ``accuracy:`` first choose its element count (accuracy.py);
    ``restart``: continue the run in that directory (run_model)."""
    if spec.accuracy is not None:
        if restart is not None:
            raise InputError("--restart", "a run with accuracy: chooses its mesh first; restart "
                                          "the chosen run's config instead")
        from ..workflows.accuracy import select_and_run
        return select_and_run(spec, comm, log, run_model)
    return run_model(spec, comm, log, restart=restart)


def _read_restart(directory: str, spec: ModelSpec, comm):
    """``restart.read_restart`` on rank 0, its result or its input error on every rank."""
    from ..io.restart import read_restart
    point, err = None, None
    if comm.rank == 0:
        try:
            point = read_restart(directory, spec.raw)
        except InputError as exc:
            err = (exc.path, str(exc).split(": ", 1)[1] if ": " in str(exc) else str(exc))
    if comm.size > 1:
        point, err = comm.tompi4py().bcast((point, err), root=0)
    if err:
        raise InputError(*err)
    return point


def _check_supports(problem) -> None:
    """One input error naming the beams and motions the supports and contact leave free."""
    from .supports import free_rigid_motions
    free = free_rigid_motions(problem)
    if free:
        held = " (frictionless contact lets beams slide along each other)" if problem.contact else ""
        raise InputError("boundary_conditions", "nothing holds " + "; ".join(free) + held
                         + "; add supports so that no beam can move as a rigid body")


def _continue_path(problem, contact, point):
    """The load path of a restart point (``PathState``), with the contact state restored."""
    from .stepper import PathState
    if contact is not None:
        contact.restore_state(point.projection, point.status)
    X = problem._global_from_model(point.blocks.ravel())
    dX = problem._global_from_model(point.increment_blocks.ravel())
    return PathState(X=X, dX_last=dX, lam=point.load_factor, dlam=point.increment,
                     dlam_last=point.last_increment, accepted_negative=point.accepted_negative)


def run_model(spec: ModelSpec, comm=PETSc.COMM_WORLD, log=print, info: dict | None = None,
              restart: str | None = None) -> RunResult:
    """Solve ``spec``; every converged level is on disk before the next one starts.
    ``info`` is stored in summary.json beside the run's own information.  ``restart``: a run's
    output directory to continue from its last converged level (it is the output directory)."""
    rank = comm.rank
    say = log if rank == 0 else (lambda *_: None)
    point = None
    if restart is not None:
        spec.output.dir = restart
        point = _read_restart(restart, spec, comm)
    check_output_dir(spec.output.dir, comm)
    PETSc.Log.begin()                 # event timings for the summary (cheap)
    # PETSc's event times add up over the process: this run's share is the difference
    solver_events0 = petsc_event_time("KSPSolve") + petsc_event_time("PCSetUp")
    t_start = time.perf_counter()
    STAGE_SETUP.push()
    model = build_model(spec)
    contact = None
    if spec.contact is not None:
        from ..contact import build_contact
        contact = build_contact(model, spec.contact, say)
    layout = make_layout(model, spec.partition, comm.size, rank, contact, comm.tompi4py())
    partition = partition_stats(layout, model, contact)
    problem = Problem(model, layout, comm, contact,
                      matrix_type(model, spec.solver.matrix, spec.petsc))
    if point is None:
        _check_supports(problem)
    stepper = LoadStepper(problem, spec.solver, spec.petsc, say, max_level=max(spec.steps))
    STAGE_SETUP.pop()
    t_setup = time.perf_counter() - t_start

    say(f"[ancf] {spec.name}: {len(model.beams)} beam(s), {model.n_elements} elements, "
        f"{model.n_dofs} DOFs, {comm.size} rank(s)")
    for line in model.describe():
        say("[ancf]   " + line)
    say("[ancf]   " + layout.summary() + (
        f", cut contact pairs {partition['cut_contact_pairs']}/{partition['contact_pairs']}"
        if "contact_pairs" in partition else "") + f", cut beam nodes {partition['cut_beam_nodes']}")
    say("[ancf]   " + stepper.describe())
    run_info = {"output_dir": os.path.abspath(spec.output.dir), "twist_deg": spec.twist_deg,
                "dofs": model.n_dofs, "elements": model.n_elements, "ranks": comm.size,
                "partition": partition, "solver": stepper.describe(),
                "sections": {b.name: {"area": b.section.area, "centroid": b.section.centroid.tolist(),
                                      "points": int(len(b.section.weights))} for b in model.beams},
                "elements_per_beam": {b.name: b.n_elements for b in model.beams},
                "element_types": {b.name: b.element for b in model.beams},
                "twist_axis": list(spec.twist_axis), "geometry": model.geometry_report,
                "contact_interfaces": [itf.name for itf in contact.interfaces] if contact else [],
                **(info or {})}
    levels = list(spec.steps)
    start = None
    if point is not None:
        start = _continue_path(problem, contact, point)
        levels = [f for f in spec.steps if f > point.load_factor * (1.0 + 1e-12)]
        say(f"[ancf] restart from step {point.step} (load factor {point.load_factor:g}) of {restart}: "
            f"{len(levels)} level(s) to go")
    try:
        writer = ResultsWriter(model, layout, comm, run_info, restart=point)
    except OutputError:
        stepper.close()
        raise
    n_levels = len(spec.steps)
    timings = {"setup": t_setup, "output": 0.0}
    converged = []

    def on_level(rec):
        STAGE_OUTPUT.push()
        try:
            t0 = time.perf_counter()
            blocks = problem.gather(blocks=True)
            increment = problem.gather(stepper.path.dX_last, blocks=True)
            q = None if blocks is None else blocks[:model.n_nodes]
            gaps = problem.contact_gaps(problem.X)          # collective: every rank its own points
            fields = problem.contact_fields(problem.X)
            extra = {"contact": gaps} if gaps is not None else None
            path = None if blocks is None else {
                "blocks": blocks.reshape(-1, 18), "increment_blocks": increment.reshape(-1, 18),
                "accepted_negative": stepper.path.accepted_negative}
            writer.write_step(rec, q, extra, fields, path)
            converged.append(rec)
            timings["output"] += time.perf_counter() - t0
        finally:
            STAGE_OUTPUT.pop()
        if rank == 0:
            k = len(writer.summary["steps"])
            probes = "  ".join(f"{n} u={_fmt_vec(p['displacement'])}"
                               for n, p in writer.summary["steps"][-1]["probes"].items())
            unstable = (f"  UNSTABLE: {rec.negative_eigenvalues} negative tangent eigenvalue(s)"
                        if rec.negative_eigenvalues else "")
            say(f"[ancf] step {k}/{n_levels}  load factor {rec.load_factor:.6g}  "
                f"Newton {rec.iterations} in {rec.substeps} substep(s)  {rec.reason}  "
                f"|F| {rec.residual_norm:.2e}  {rec.wall_time:.2f} s{unstable}  {probes}")

    failure, signum, inverted = None, 0, False
    try:
        stepper.run(levels, on_level, start) if levels else None
    except LoadStepFailure as exc:
        failure = ("failed", exc.code, str(exc))
        inverted = exc.inverted
    except RunInterrupted as exc:
        signum = exc.signum
        failure = ("interrupted", st.signal_reason(signum), str(exc))
    except OutputError as exc:
        failure = ("failed", st.OUTPUT_ERROR, f"output error: {exc}")
    except BaseException as exc:
        # a bug, possibly on this rank only: no collective calls; record it where we can
        stepper.close(collective=False)
        writer.finish("failed", reason_code=st.INTERNAL_ERROR, message=f"{type(exc).__name__}: {exc}")
        raise
    stepper.close()
    records = converged
    status, code, message = _final_status(records, failure, spec.solver.allow_unstable)
    unused = [f"petsc.{k}" for k in stepper.unused_config_options] + unused_command_line_options(comm)
    timings["total"] = time.perf_counter() - t_start
    timings["solve"] = timings["total"] - timings["setup"] - timings["output"]
    timings.update(problem.timers)
    timings["linear_solve"] = petsc_event_time("KSPSolve") + petsc_event_time("PCSetUp") - solver_events0
    lo, hi = layout.owned_nodes
    ghosts = int(np.sum((problem.needed < lo) | (problem.needed >= hi)))
    exchange = {"rebuilds": problem.exchanges,
                "ghost_nodes_per_rank": comm.tompi4py().gather(ghosts, root=0),
                "total_nodes": model.n_nodes}
    unstable = [r.load_factor for r in records if r.negative_eigenvalues]
    problem_writing = writer.finish(
        status, reason_code=code, message=message, timings=timings,
        newton_iterations=stepper.newton_iterations, exchange=exchange,
        jacobian_pattern_growths=problem.pattern_growths,
        unstable_levels=unstable, allow_unstable=spec.solver.allow_unstable,
        stability_checked=all(r.negative_eigenvalues is not None for r in records),
        unused_petsc_options=unused)
    if comm.size > 1:
        problem_writing = comm.tompi4py().bcast(problem_writing, root=0)
    if problem_writing:
        status, code, message = "failed", st.OUTPUT_ERROR, f"output error: {problem_writing}"
    if comm.size > 1:
        say(f"[ancf] exchange: node blocks received per rank {exchange['ghost_nodes_per_rank']} of "
            f"{model.n_nodes}; rebuilt {problem.exchanges} times (the set of projected-on elements changed)")
    say(f"[ancf] {status}: {message}; {stepper.newton_iterations} Newton iterations, "
        f"{timings['total']:.2f} s (setup {timings['setup']:.2f} s); results in {spec.output.dir}")
    return RunResult(status, message, writer.summary if rank == 0 else None, records, code,
                     st.exit_code(status, code, signum), unused, spec.output.dir, inverted)
