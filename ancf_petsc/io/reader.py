"""A finished (or interrupted) run read back from its directory: summary.json and results.h5.

``read_results(directory)`` is the public reader (``ancf_petsc.read_results``); it reads what
``results.ResultsWriter`` wrote, level by level, without PETSc.  While a run goes on (or after
it was killed) summary.json may not list its last level yet (it is rewritten after results.h5;
``results.SUMMARY_SHARE`` spaces its rewrites in long histories); ``append_levels`` takes them
from results.h5, where every level carries its summary entry.
"""
from __future__ import annotations

import json
import operator
import os
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .h5fast import open_file
from .files import os_reason


#: what a probe reports at each level (summary.json ``probes``): its change and its nodal vector
PROBE_FIELDS = ("displacement", "value")


@dataclass
class Results:
    """The converged levels of one run (``summary`` is summary.json as a dict)."""
    directory: str
    summary: dict

    @property
    def status(self) -> str:
        """completed | unstable | failed | interrupted | running (summary.json ``status``)."""
        return str(self.summary.get("status", ""))

    @property
    def load_factors(self) -> np.ndarray:
        """Load factor of every converged level (step 1, 2, ...)."""
        return np.array([s["load_factor"] for s in self.summary.get("steps", [])])

    def probe(self, name: str, what: str = "displacement") -> np.ndarray:
        """A probe's displacement (or ``value``) at every converged level, shape (levels, 3)."""
        if what not in PROBE_FIELDS:
            raise ValueError(f"probe {name!r}: what must be one of {', '.join(PROBE_FIELDS)}; got {what!r}")
        steps = self.summary.get("steps", [])
        if steps and name not in steps[0]["probes"]:
            raise KeyError(f"no probe {name!r}; the run has {', '.join(steps[0]['probes'])}")
        return np.array([s["probes"][name][what] for s in steps]).reshape(-1, 3)

    @property
    def h5_path(self) -> str:
        return os.path.join(self.directory, "results.h5")

    def level(self, step: int) -> int:
        """Level number 1 … n of ``step`` (0: the reference state; negative counts from the last
        converged level, as Python's indices do); IndexError naming the levels there are."""
        try:
            step = operator.index(step)          # 1.5 was 'Unknown format code 'd'' deep in the read
        except TypeError:
            raise TypeError(f"step must be an integer level (0 the reference state, -1 the last); "
                            f"got {step!r}") from None
        n = len(self.summary.get("steps", []))
        k = step + n + 1 if step < 0 else step
        if not 0 <= k <= n:
            raise IndexError(f"step {step}: the run has {n} converged level(s): 1 … {n}, 0 the reference "
                             "state, -1 the last")
        return k

    def nodal_vectors(self, step: int) -> np.ndarray:
        """Nodal vectors (n_nodes, V, 3) at converged level ``step`` (0: the reference state,
        -1: the last level)."""
        k = self.level(step)
        with opened(self.h5_path) as h5:
            if k == 0:
                return h5["model/reference_nodal_vectors"][()]
            return h5["steps"][f"step_{k:04d}"]["nodal_vectors"][()]

    def contact(self, step: int) -> dict:
        """Contact fields of converged level ``step`` (``read_contact``; -1: the last level)."""
        k = self.level(step)
        if k == 0:
            raise IndexError("step 0 is the reference state: contact fields are written from level 1 on")
        return read_contact(self.h5_path, k)


def append_levels(summary: dict, steps) -> None:
    """Append to ``summary["steps"]`` the converged levels the h5py group ``steps`` (results.h5's
    ``/steps``) holds beyond them, from each level's ``summary_entry`` (files written before it
    existed have none: nothing is appended)."""
    listed = summary.setdefault("steps", [])
    for k in range(len(listed) + 1, int(steps.attrs.get("converged", 0)) + 1):
        level = steps.get(f"step_{k:04d}")
        if level is None or "summary_entry" not in level.attrs:
            break
        listed.append(json.loads(level.attrs["summary_entry"]))
        summary["last_converged"] = {"step": k, "load_factor": listed[-1]["load_factor"]}


def read_results(directory: str) -> Results:
    """The run in ``directory`` (its summary.json must exist; results.h5 is read on demand, and
    for a run that still says ``running`` to add the levels summary.json does not list yet;
    ~ is the home directory, as in output.dir)."""
    directory = os.path.expanduser(directory)
    path = os.path.join(directory, "summary.json")
    try:
        with open(path) as fh:
            summary = json.load(fh)
    except FileNotFoundError:
        raise InputError("results", f"{directory}: no summary.json (not a run's output directory)") from None
    except (OSError, ValueError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
        raise InputError("results", f"{path}: cannot read: {reason}") from None
    if not isinstance(summary, dict) or not isinstance(summary.get("steps", []), list):
        raise InputError("results", f"{path}: not a run's summary (a JSON object with its status and "
                                    f"steps); got {type(summary).__name__}")
    h5_path = os.path.join(directory, "results.h5")
    if summary.get("status") == "running" and os.path.exists(h5_path):
        try:                         # no file lock: the run's next level must not find one
            with open_file(h5_path, "r") as h5:
                append_levels(summary, h5["steps"])
        except (OSError, KeyError, ValueError, RuntimeError):
            pass                     # results.h5 being written or damaged: summary.json's levels
    return Results(os.path.abspath(directory), summary)


@contextmanager
def opened(results_h5: str):
    """results.h5 open for reading, without a file lock (a running run writes its next level);
    InputError naming it when HDF5 cannot open it (truncated, empty, not HDF5: an OSError
    traceback in ancf-report --existing before)."""
    try:
        h5 = open_file(results_h5, "r")
    except OSError as exc:                 # HDF5's words run over lines: the OS's, or the first line
        raise InputError("results", f"{results_h5}: cannot read ({os_reason(exc)}): not a whole results.h5; "
                                    "run ancf-solve again") from None
    with h5:
        yield h5


def _level(h5, results_h5: str, step: int):
    """Group ``steps/step_NNNN`` of an open results.h5; InputError when the file does not hold it."""
    g = h5["steps"].get(f"step_{step:04d}") if "steps" in h5 else None
    if g is None:
        held = len(h5["steps"]) if "steps" in h5 else 0
        raise InputError("results", f"{results_h5}: no level {step} (it holds {held}): summary.json lists "
                                    "levels this results.h5 does not (another run's file?); run ancf-solve again")
    return g


def check_levels(directory: str, summary: dict) -> None:
    """The results.h5 of ``directory``, when there, opens and holds every level ``summary`` lists
    (InputError naming it if not: a truncated file or another run's ended ancf-report in a traceback)."""
    path = os.path.join(directory, "results.h5")
    if os.path.exists(path):
        with opened(path) as h5:
            for k in range(1, len(summary.get("steps", [])) + 1):
                _level(h5, path, k)


def read_contact(results_h5: str, step: int) -> dict:
    """Contact fields of one converged level of a run (``steps/step_NNNN/contact``) and its
    load factor; InputError when results.h5 cannot be read or lacks the level."""
    with opened(results_h5) as h5:
        g = _level(h5, results_h5, step)
        if "contact" not in g:
            raise KeyError(f"{results_h5}: the run has no contact (no contact fields at level {step})")
        out = {k: g["contact"][k][()] for k in g["contact"]}
        out["load_factor"] = float(g.attrs["load_factor"])
    return out
