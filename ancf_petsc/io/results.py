"""Results on disk, written step by step by rank 0 so a killed run keeps every finished step.

* ``results.h5``  — ``/model`` (reference nodal vectors, connectivity, sections, config text,
  partition) and ``/steps/step_NNNN`` (load factor, nodal vectors, SNES iterations/reason,
  wall time).  The file is opened and closed for every step.
* ``summary.json`` — probes per step, iterations, timings; replaced atomically after a level
  while that takes at most ``SUMMARY_SHARE`` of the run's time (every level but in long
  histories) and at the run's end (every ending: completed, failed, interrupted).  Each level's
  entry is also in results.h5 (attribute
  ``summary_entry`` of ``steps/step_NNNN``), so a run killed between two rewrites loses nothing:
  ``reader.read_results`` and ``--restart`` append the levels summary.json does not list yet.
* ``surface_NNNN.vtu`` + ``surface.pvd`` — the deformed 3D surfaces of all beams (sections sampled
  along ξ), with displacement, axial Green–Lagrange strain E_xx and volume ratio J (io/vtu.py, meshio's layout).
* ``contact_NNNN.vtu`` + ``contact.pvd`` — the contact points at their deformed positions with gap,
  pressure, slip (vector and its axial part) and interface; the same per step in results.h5
  (``steps/step_NNNN/contact``) with the multipliers and the projection state.

Every converged level is in results.h5 when it converges, also when the disk fills: a level is
written to results.h5 under a temporary name and renamed when complete (``/steps`` attributes
``converged`` and ``last_load_factor`` name the last one, for a restart); summary.json lists
the levels results.h5 holds (while running, possibly not yet the last few: see above).  Before each level the free space is checked against the
size of the previous one, and a small reserve file (``RESERVE``) set aside at the start is
released when writing fails, so that the final summary.json can still be written.  Every file
problem becomes an ``OutputError`` naming the path, raised on every rank.
"""
from __future__ import annotations

import json
import os
import re
import time

import numpy as np

from ..model.beams import Model
from ..model.plausibility import strain_warning
from ..model.section_forces import AxialForces
from ..status import OUTPUT_ERROR
from ..version import version_info
from . import h5fast
from .files import NO_SPACE, OutputError, atomic_write, os_reason, prepare_output_dir, remove_quietly
from .groups import config_text, recover_level, truncate_levels, write_level_group, write_model_group
from .vtk import SurfaceSampler, VtkSeries, contact_cells, surface_cells

#: space set aside for the final summary.json (released on a write error and at the end)
RESERVE = ".ancf-space-reserve"
RESERVE_BYTES = 64 * 1024


#: summary.json is rewritten after level 1, at the end, and after a level when the time since
#: its last rewrite is at least its cost over SUMMARY_SHARE: its rewrites take at most that share
#: of the run.  A column's or a 100-frame stride's rewrite costs ~0.1–1 ms against a level's
#: 20 ms or more, so there it is every level: a fixed interval (0.5 s) saved ~3 ms a stride frame,
#: but a run killed while writing results.h5 left that file unreadable and summary.json without
#: its last levels (tests/solving/test_restart.py, 2026-11-28).  In a long history the file grows
#: with every level, and rewriting it at each made the output O(levels) per level: 7.4 → 16.1 ms
#: from the first to the tenth hundred levels of a 1000-frame history (docs/gait.md).  Each
#: level's entry is in results.h5 meanwhile.  ``math.inf``: at every level.
SUMMARY_SHARE = 0.05


#: stands for the levels in the summary's text before they are put in (``compact_summary``)
STEPS_MARK = "@ancf-steps@"


def compact_summary(summary: dict, cache: list) -> str:
    """``json.dumps(summary, separators=(",", ":"))``, byte for byte, with each level's entry in
    ``summary["steps"]`` encoded once and kept in ``cache`` [(entry, text)]: an entry never changes
    once appended, and re-encoding them all made a long history cost O(levels) per level (3.5 ms
    a frame on average over a 100-frame stride).  A steps list replaced or cut (a restart) is
    encoded afresh."""
    steps = summary["steps"]
    if len(cache) > len(steps) or any(kept is not entry for (kept, _), entry in zip(cache, steps)):
        cache.clear()
    cache.extend((entry, json.dumps(entry, separators=(",", ":"))) for entry in steps[len(cache):])
    head = json.dumps(dict(summary, steps=STEPS_MARK), separators=(",", ":"))
    return head.replace(f'"steps":"{STEPS_MARK}"', '"steps":[' + ",".join(t for _, t in cache) + "]", 1)


def step_entry(record, probes: dict) -> dict:
    """A converged level's entry of summary.json's ``steps`` (and results.h5's): the stepper's
    StepRecord (solving/records.py) with the level's ``probes``."""
    entry = {"load_factor": record.load_factor, "probes": probes,
             "iterations": record.iterations, "substeps": record.substeps,
             "cutbacks": record.cutbacks, "tresca_solves": record.tresca_solves,
             "reason": record.reason,
             "residual_norm": record.residual_norm, "wall_time": record.wall_time,
             "negative_eigenvalues": record.negative_eigenvalues,
             "weights_unsettled": record.weights_unsettled,
             "newton_history": record.iteration_history}
    if record.branch_switches:
        entry["branch_switches"] = record.branch_switches
    if record.passed_over:                 # a level in a gap of the load path (solving/step_over.py)
        level, last, at = record.passed_over
        entry["passed_over"] = {"level": level, "last_converged": last, "reported_at": at}
    return entry


#: the files a run writes, which a new run in the same directory replaces (``stale_output``)
RUN_SERIES = re.compile(r"(surface|contact)(_[0-9]{4,}\.vtu|\.pvd)")


def level_fields(record) -> dict:
    """A VTU's field data: ``load_factor``, ``negative_eigenvalues`` of the tangent (-1: not
    counted) and ``stable`` (1; 0 with negative eigenvalues, -1 not counted) of a converged
    level's StepRecord; the rest state's (None): load factor 0, not counted."""
    neg = -1 if record is None or record.negative_eigenvalues is None else record.negative_eigenvalues
    return {"load_factor": np.array([0.0 if record is None else record.load_factor]),
            "negative_eigenvalues": np.array([neg], dtype=np.int32),
            "stable": np.array([-1 if neg < 0 else int(neg == 0)], dtype=np.int32)}


def series_time(entry: dict, timed: bool) -> float:
    """A level's time in the VTU series: a history's time [s] (``timed``), else its load factor."""
    return entry["time"] if timed else entry["load_factor"]


def stale_output(name: str) -> bool:
    """Whether ``name`` in an output directory is a file a run writes (results.h5, summary.json,
    the reserve, the VTU series and their .pvd collections), which a new run replaces.  Nothing
    else is touched: a user's ``surface_plots/`` or ``contact_notes.txt`` beside the results
    stays (every name starting with surface/contact was removed before, and a folder so named
    stopped the run half-way through the clean-up)."""
    return name in ("results.h5", "summary.json", RESERVE) or RUN_SERIES.fullmatch(name) is not None


class ResultsWriter:
    """Writes results.h5, summary.json and the VTU series (rank 0 does the I/O; every method is
    called on every rank, and a file-system error becomes an ``OutputError`` on every rank)."""

    def __init__(self, model: Model, layout, comm, run_info: dict, restart=None, rest_contact=None):
        self.model, self.comm = model, comm
        self.timed = model.spec.history is not None     # the VTU series over the history's clock
        self.restart = restart
        self.rank = comm.rank
        spec = model.spec
        self.dir = spec.output.dir
        self.h5_path = os.path.join(self.dir, "results.h5")
        self.summary_path = os.path.join(self.dir, "summary.json")
        self.summary = {"name": spec.name, "status": "running", **run_info,
                        "warnings": list(model.warnings), "steps": []}   # + the first level's strain
        self.sampler = SurfaceSampler(model, spec.output.vtk_samples) if spec.output.vtk else None
        self.axial_forces = AxialForces(model)   # the section forces of every level
        self.vtk = VtkSeries(self.dir, compress=spec.output.vtk_compress)
        self._last_sizes = {"vtu": 0, "h5": 0, "summary": 0}
        self._step_texts: list = []            # each level's entry and its JSON (compact_summary)
        self._summary_time = -np.inf           # when summary.json was last written (monotonic)
        self._summary_cost = 0.0                # how long that took [s]
        self._on_root(lambda: self._create_or_fail(layout, run_info, rest_contact) if restart is None
                      else self._resume(layout, run_info))

    def _on_root(self, action) -> None:
        """Run ``action`` on rank 0; its error is raised on every rank as an ``OutputError``
        (collective).  Any exception counts, not only the OS's: h5py raises ValueError and
        KeyError for a file another process changed, and one rank must never raise alone."""
        err = None
        if self.rank == 0:
            try:
                action()
            except OutputError as exc:
                err = (exc.path, exc.reason)
            except OSError as exc:
                self._release_reserve()
                err = (exc.filename or self.dir, os_reason(exc))
            except Exception as exc:           # noqa: BLE001 -- raised on every rank below
                self._release_reserve()
                err = (self.dir, f"{type(exc).__name__}: {exc}")
        if self.comm.size > 1:
            err = self.comm.tompi4py().bcast(err, root=0)
        if err:
            raise OutputError(*err)

    def _create_or_fail(self, layout, run_info: dict, rest_contact: dict | None) -> None:
        """``_create``; if it fails (a full disk before level 1), the files that exist say
        ``failed`` with ``OUTPUT_ERROR`` (never ``running``), as far as the disk lets them."""
        try:
            self._create(layout, run_info, rest_contact)
        except OutputError as exc:
            self._fail_early(f"output error: {exc}")
            raise
        except OSError as exc:
            self._fail_early(f"output error: {exc.filename or self.dir}: {os_reason(exc)}")
            raise

    def _fail_early(self, message: str) -> None:
        """Best effort after a failed start: summary.json and results.h5 (if any) say ``failed``."""
        self._release_reserve()
        self.summary.update(status="failed", reason_code=OUTPUT_ERROR, message=message,
                            steps=[])
        try:
            atomic_write(self.summary_path, json.dumps(self.summary, indent=1))
        except OSError:
            pass                                   # no room even for that: the exit code says it
        if os.path.exists(self.h5_path):
            try:
                with h5fast.open_file(self.h5_path, "a") as h5:
                    h5.attrs["status"] = "failed"
                    h5.attrs["reason_code"] = OUTPUT_ERROR
            except (OSError, RuntimeError):
                remove_quietly(self.h5_path)      # a results.h5 that cannot say failed goes

    def _create(self, layout, run_info: dict, rest_contact: dict | None) -> None:
        model = self.model
        prepare_output_dir(self.dir)
        for stale in os.listdir(self.dir):
            if stale_output(stale) and os.path.isfile(os.path.join(self.dir, stale)):
                os.remove(os.path.join(self.dir, stale))
        self.summary["version"] = version_info()
        try:
            with open(os.path.join(self.dir, RESERVE), "wb") as fh:
                fh.write(b"\0" * RESERVE_BYTES)
        except OSError as exc:
            self._release_reserve()
            raise OutputError(self.dir, f"cannot set aside {RESERVE_BYTES // 1024} KB for the results: "
                                        f"{os_reason(exc)}") from None
        try:
            with h5fast.open_file(self.h5_path, "w") as h5:
                write_model_group(h5, self.model, layout, run_info, self.summary["version"])
        except (OSError, RuntimeError) as exc:
            self._release_reserve()
            raise OutputError(self.h5_path, f"cannot write: {os_reason(exc)}") from None
        if self.sampler is not None:                 # the rest state: no history time (VtkSeries)
            self._write_vtus(0, None if self.timed else 0.0, surface_cells(self.sampler, model.q0),
                             rest_contact, level_fields(None))
        self._write_summary()

    def _resume(self, layout, run_info: dict) -> None:
        """Continue the files of ``self.restart`` (a ``restart.RestartPoint``): the levels after
        its step are dropped from results.h5, summary.json and the VTU series; results.h5's
        partition becomes this process's (``layout``, as summary.json's)."""
        point = self.restart
        self.summary["version"] = version_info()
        self.summary["restarted_from"] = {"step": point.step, "load_factor": point.load_factor}
        self.summary["steps"] = list(point.summary.get("steps", []))
        self.summary["last_converged"] = {"step": point.step, "load_factor": point.load_factor}
        self.summary["warnings"] = list(point.summary.get("warnings", self.summary["warnings"]))
        rest = None if self.timed else 0.0          # a history's rest state: no time (VtkSeries)
        self.vtk.resume([rest] + [series_time(st, self.timed) for st in self.summary["steps"]],
                        self.summary["warnings"] if self.sampler is not None else None)
        truncate_levels(self.h5_path, point.step, point.load_factor, config_text(self.model.spec),
                        layout, run_info.get("partition"))
        with open(os.path.join(self.dir, RESERVE), "wb") as fh:
            fh.write(b"\0" * RESERVE_BYTES)
        self._write_summary()

    def _release_reserve(self) -> None:
        remove_quietly(os.path.join(self.dir, RESERVE))

    def _write_summary(self, final: bool = False):
        """summary.json: compact while the run goes on (json's C encoder: half the time of the
        indented form, which grows with every level), indented once the run has ended."""
        self.summary["updated"] = time.strftime("%Y-%m-%dT%H:%M:%S")
        text = json.dumps(self.summary, indent=1) if final else compact_summary(self.summary, self._step_texts)
        self._last_sizes["summary"] = len(text)
        t0 = time.monotonic()
        try:
            atomic_write(self.summary_path, text)
        except OSError as exc:
            if exc.errno not in NO_SPACE or not os.path.exists(os.path.join(self.dir, RESERVE)):
                raise OutputError(self.summary_path, f"cannot write: {os_reason(exc)}") from None
            self._release_reserve()               # the space set aside for exactly this
            try:
                atomic_write(self.summary_path, text)
            except OSError as exc2:
                raise OutputError(self.summary_path, f"cannot write: {os_reason(exc2)}") from None
        self._summary_time = time.monotonic()
        self._summary_cost = self._summary_time - t0

    def _write_vtus(self, k: int, t: float | None, surface: tuple, contact: dict | None, fields: dict) -> None:
        """Level ``k``'s surface and contact VTUs at time ``t``, both or neither
        (``vtk.VtkSeries.write_level``); a failure is an OutputError."""
        meshes = {"surface": surface, **({"contact": contact_cells(contact)} if contact is not None else {})}
        try:
            self._last_sizes["vtu"] = self.vtk.write_level(k, t, meshes, fields)
        except OSError as exc:
            self._release_reserve()
            raise OutputError(exc.filename or os.path.join(self.dir, f"surface_{k:04d}.vtu"),
                              f"cannot write: {os_reason(exc)}") from None

    def probe_values(self, q: np.ndarray) -> dict:
        return {name: {"displacement": u.tolist(), "value": v.tolist()}
                for name, (u, v) in self.model.probe_values(q).items()}

    def write_step(self, record, q: np.ndarray | None, extra: dict | None = None,
                   contact: dict | None = None, path: dict | None = None) -> None:
        """Append one converged level; ``q`` is the gathered nodal vectors (rank 0), ``contact``
        the gathered contact fields (``petsc.contact_reports.contact_fields``), ``path`` what a restart needs:
        ``blocks`` and ``increment_blocks`` (every block in model order, (n, D), D DOFs per node) and
        ``accepted_negative``.  Collective."""
        self._on_root(lambda: self._write_step(record, q, extra, contact, path))

    def _check_space(self, k: int, q: np.ndarray) -> None:
        """Stop before level ``k`` if the file system has clearly no room for it."""
        try:
            st = os.statvfs(self.dir)
        except OSError:
            return
        free = st.f_bavail * st.f_frsize
        need = (max(self._last_sizes["h5"], q.nbytes) + self._last_sizes["vtu"]
                + 2 * self._last_sizes["summary"] + 16 * 1024)
        if free < need:
            raise OutputError(self.dir, f"no space left on device for level {k}: {free // 1024} KB "
                                        f"free, about {need // 1024} KB needed")

    def _write_step(self, record, q: np.ndarray, extra: dict | None, contact: dict | None,
                    path: dict | None) -> None:
        k = len(self.summary["steps"]) + 1
        entry = step_entry(record, self.probe_values(q))
        if extra:
            entry.update(extra)
        text = json.dumps(entry, separators=(",", ":"))          # summary.json's, and results.h5's
        if k == 1:                          # a first level strained beyond belief: wrong units?
            note = strain_warning(self.model, q, record.load_factor)
            if note:
                self.summary["warnings"].append(note)
        self._check_space(k, q)
        name = f"step_{k:04d}"
        size0 = os.path.getsize(self.h5_path)
        level = dict(extra or {}, probes=entry["probes"], section_forces=self.axial_forces(q))
        surface = surface_cells(self.sampler, q) if self.sampler is not None else None
        if surface is not None:
            level["surface"] = {"points": surface[0], **surface[2]}
            # the VTUs before results.h5 takes the level: a run killed between leaves VTUs a
            # restart removes, never a level on disk without them (a frame missing after it)
            self._write_vtus(k, series_time(entry, self.timed), surface, contact, level_fields(record))
        try:
            with h5fast.open_file(self.h5_path, "a") as h5:
                steps = h5["steps"]
                g = steps.create_group(name + ".partial")      # renamed once complete
                write_level_group(g, record, q, level, contact, path, self.model)
                h5fast.attribute(g.id, "summary_entry", text)
                steps.move(name + ".partial", name)
                steps.attrs["converged"] = k
                steps.attrs["last_load_factor"] = record.load_factor
        except (OSError, RuntimeError) as exc:
            self._release_reserve()
            if recover_level(self.h5_path, name):            # the level made it to disk after all
                self._append(entry)
            else:
                self.vtk.discard(k)
            raise OutputError(self.h5_path, f"cannot write level {k}: {os_reason(exc)}") from None
        self._last_sizes["h5"] = max(os.path.getsize(self.h5_path) - size0, q.nbytes)
        self._append(entry, text)
        if k == 1 or time.monotonic() - self._summary_time >= self._summary_cost / SUMMARY_SHARE:
            self._write_summary()

    def _append(self, entry: dict, text: str | None = None) -> None:
        """Add a level to the summary (``text``: its compact JSON, kept for ``compact_summary``)."""
        if text is not None and len(self._step_texts) == len(self.summary["steps"]):
            self._step_texts.append((entry, text))
        self.summary["steps"].append(entry)
        self.summary["last_converged"] = {"step": len(self.summary["steps"]),
                                          "load_factor": entry["load_factor"]}

    def finish(self, status: str, **info) -> str | None:
        """Write the final status and the .pvd collections (rank 0; not collective).  Returns
        None, or the one-line reason the final files could not be written."""
        if self.rank != 0:
            return None
        self.summary["status"] = status
        self.summary.update(info)
        self._release_reserve()
        problem = self.vtk.write_indexes()          # the .pvd collections with every level's VTU
        if problem:
            self.summary.update(status="failed", reason_code=OUTPUT_ERROR, message=f"output error: {problem}")
        try:
            self._write_summary(final=True)
        except OutputError as exc:
            problem = str(exc)
        try:
            with h5fast.open_file(self.h5_path, "a") as h5:
                h5.attrs["status"] = status
                h5.attrs["reason_code"] = str(info.get("reason_code", ""))
        except (OSError, RuntimeError):
            pass                                   # results.h5 keeps its levels; the summary has the status
        return problem


def record_crash(writer: ResultsWriter, reason_code: str, message: str, status: str = "failed") -> None:
    """A bug raised on this rank, possibly on it alone: the final status (``failed``; a Ctrl-C
    of a Python session: ``interrupted``) in summary.json without a collective call.  Rank 0
    finishes as usual; another rank (whose rank 0 waits in a collective until the abort) rewrites
    rank 0's summary.json itself, so that the run does not stay ``running``."""
    if writer.rank == 0:
        writer.finish(status, reason_code=reason_code, message=message)
        return
    try:
        with open(writer.summary_path) as fh:
            summary = json.load(fh)
        summary.update(status=status, reason_code=reason_code, message=f"rank {writer.rank}: {message}",
                       updated=time.strftime("%Y-%m-%dT%H:%M:%S"))
        atomic_write(writer.summary_path, json.dumps(summary, indent=1))
    except (OSError, ValueError):
        pass                                   # no summary to mark: the traceback says it
