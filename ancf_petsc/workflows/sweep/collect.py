"""Collecting a sweep: every run's status, probes and timings in one CSV, failures in failed.txt."""
from __future__ import annotations

import csv
import json
import os
from dataclasses import dataclass, field
from typing import Any

from ...io.files import atomic_write
from .base import DONE_STATUSES, FAILED_STATUSES, FINAL_STATUSES, STATUS_ORDER, read_json
from .execute import reason_code
from .expand import expand, same_config
from .spec import RunSpec, Sweep


# ------------------------------------------------------------------------------ collection
@dataclass
class RunState:
    """The state of one run directory as collection sees it."""
    run: RunSpec
    status: str                     # FINAL_STATUSES, 'running' or 'missing'
    reason: str = ""
    reason_code: str = ""           # machine-readable (execute.reason_code); read this, not ``reason``
    load_factor: float | None = None
    probes: dict[str, list] = field(default_factory=dict)
    newton_iterations: int | None = None
    wall_time: float | None = None


#: the reason of a run directory solved with another config than the sweep's current one
EDITED = ("it ran with another config.yaml, run.petsc or data file than the sweep's now (the sweep, its "
          "base config or a file they name was edited after it ran): rerun the sweep (a SLURM array: "
          "ancf-sweep SWEEP --slurm again, then resubmit)")


def run_state(run: RunSpec, current: bool = True) -> RunState:
    """Combine summary.json (solver) and run.json (sweep) of one run directory; ``current``
    False (its config.yaml is another config's): missing, its numbers not read."""
    if not current:
        return RunState(run, "missing", EDITED)
    summary = read_json(os.path.join(run.dir, "summary.json"))
    record = read_json(os.path.join(run.dir, "run.json"))
    st = RunState(run, "missing")
    sstat = summary.get("status") if summary else None
    rstat = record.get("status") if record else None
    if sstat in DONE_STATUSES:
        st.status = sstat
        st.reason = str(summary.get("message") or "") if sstat != "completed" else ""  # type: ignore[union-attr]
    elif rstat in FAILED_STATUSES:
        st.status, st.reason = rstat, str(record.get("reason") or "")  # type: ignore[union-attr]
    elif sstat in ("failed", "interrupted"):
        st.status, st.reason = sstat, str(summary.get("message") or "")  # type: ignore[union-attr]
    elif sstat == "running" or rstat == "running":
        st.status = "running"
        st.reason = "running, or died without a record (rerun the sweep to redo it)"
    elif os.path.isdir(run.dir):
        st.reason = "not run yet"
    else:
        st.reason = "run directory missing"
    if summary:
        steps = summary.get("steps") or []
        if steps:
            st.load_factor = steps[-1].get("load_factor")
            st.probes = {k: v.get("displacement") for k, v in (steps[-1].get("probes") or {}).items()}
        st.newton_iterations = run_iterations(summary)
        st.wall_time = (summary.get("timings") or {}).get("total")
    if st.status in FINAL_STATUSES:
        st.reason_code = reason_code(run.dir, st.status) if rstat != st.status or not record \
            else str(record.get("reason_code") or reason_code(run.dir, st.status))
    if record and record.get("wall_time") is not None and rstat != "running":
        st.wall_time = record["wall_time"] + float(record.get("earlier_wall_time") or 0.0)
    return st


def run_iterations(summary: dict) -> int:
    """The run's Newton iterations: summary.json's ``newton_iterations`` counts the last process
    only, so a restarted run adds the levels it continued from (each level's ``iterations``,
    as the Newton budget counts them; docs/running.md, Restart)."""
    steps = summary.get("steps") or []
    its = summary.get("newton_iterations")
    if its is None:
        return sum(s.get("iterations") or 0 for s in steps)
    before = int((summary.get("restarted_from") or {}).get("step") or 0)
    return its + sum(s.get("iterations") or 0 for s in steps[:before])


def _csv_value(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, str):
        return v
    return json.dumps(v, default=str)


@dataclass
class Collection:
    """Collected states with the paths of results.csv and failed.txt."""
    states: list[RunState]
    csv_path: str
    failed_path: str

    def counts(self) -> dict[str, int]:
        c = {s: 0 for s in STATUS_ORDER}
        for s in self.states:
            c[s.status] += 1
        return c

    def all_completed(self) -> bool:
        return all(s.status == "completed" for s in self.states)

    def summary_line(self) -> str:
        c = self.counts()
        parts = [f"{c['completed']} completed"] + [f"{n} {s}" for s, n in c.items()
                                                   if s != "completed" and n]
        return f"{len(self.states)} runs: " + ", ".join(parts)


def collect(sweep: Sweep) -> Collection:
    """Write ``<output>/results.csv`` (one row per run) and ``<output>/failed.txt``."""
    states = [run_state(r, not os.path.isfile(os.path.join(r.dir, "config.yaml"))
                        or same_config(sweep, r)) for r in expand(sweep)]
    probes: list[str] = []
    for s in states:
        for name in s.probes:
            if name not in probes:
                probes.append(name)
    header = (["run_id"] + [p.path for p in sweep.parameters] + ["status", "reason_code", "reason", "load_factor"]
              + [f"{p}_{c}" for p in probes for c in ("dx", "dy", "dz")]
              + ["newton_iterations", "wall_time"])
    os.makedirs(sweep.output, exist_ok=True)
    csv_path = os.path.join(sweep.output, "results.csv")
    tmp = csv_path + f".tmp{os.getpid()}"
    with open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for s in states:
            row = [s.run.run_id] + [_csv_value(s.run.params[p.path]) for p in sweep.parameters]
            row += [s.status, s.reason_code, s.reason, _csv_value(s.load_factor)]
            for p in probes:
                d = s.probes.get(p) or [None, None, None]
                row += [_csv_value(x) for x in d]
            row += [_csv_value(s.newton_iterations),
                    f"{s.wall_time:.3f}" if s.wall_time is not None else ""]
            w.writerow(row)
    os.replace(tmp, csv_path)
    failed_path = os.path.join(sweep.output, "failed.txt")
    # every run that did not reach a final good status: failed ones and those never run
    lines = [f"{s.run.run_id}\t{s.status}\t{s.reason}" for s in states
             if s.status in FAILED_STATUSES + ("missing",)]
    atomic_write(failed_path, "".join(ln + "\n" for ln in lines))
    return Collection(states, csv_path, failed_path)
