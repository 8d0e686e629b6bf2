"""The calibration's log: ``samples.jsonl`` in the output directory, one JSON line per sample
(parameters, residuals, status, reason code, cost, how it was solved), written and flushed to
disk as each batch of samples completes.  A calibration that was stopped (Ctrl-C, kill, a time
limit) and started again reads it back: the optimiser, which is deterministic, asks for the same
parameter sets again and gets the logged residuals instead of solves, up to where it stopped.

The first line identifies the fit (a hash of the model config, the parameters and the data); a
log of another fit is not reused (an input error naming the output directory).  A line cut short
by a kill is ignored.
"""
from __future__ import annotations

import hashlib
import json
import os

import numpy as np

from .errors import CalibrationError
from .sample import Sample
from .spec import FitSpec

LOG_NAME = "samples.jsonl"


def _read_files(raw, base: str) -> dict:
    """The content hashes of the files a model config reads (every ``file`` and ``source`` value:
    outlines, label images, load tables), by their path as written."""
    out = {}
    if isinstance(raw, dict):
        for key, value in raw.items():
            if key in ("file", "source") and isinstance(value, str):
                path = value if os.path.isabs(value) else os.path.join(base, value)
                try:
                    with open(path, "rb") as fh:
                        out[value] = hashlib.sha256(fh.read()).hexdigest()[:16]
                except OSError:
                    out[value] = "unreadable"
            else:
                out.update(_read_files(value, base))
    elif isinstance(raw, list):
        for value in raw:
            out.update(_read_files(value, base))
    return out


def fingerprint(spec: FitSpec) -> str:
    """What makes residuals comparable: the model config and the files it reads (a changed
    outline file resumed a log of the old geometry: mu 1.07e8 against 2.60e7 fitted afresh),
    parameters, data, levels, penalty."""
    words = json.dumps({
        "model": spec.model_raw, "files": _read_files(spec.model_raw, spec.model_dir),
        "parameters": [[p.name, [list(k) for k in p.keys], p.lower, p.upper, p.log, p.factor, p.start]
                       for p in spec.parameters],
        "data": [[d.name, d.quantity, d.options, d.levels.tolist(), d.values.tolist(), d.sigmas.tolist()]
                 for d in spec.data],
        "levels": spec.levels, "penalty": spec.penalty}, sort_keys=True, default=str)
    return hashlib.sha256(words.encode()).hexdigest()[:16]


def _key(u) -> tuple:
    return tuple(float(x) for x in u)


class SampleLog:
    """The samples of one calibration, from disk and as they come (rank 0 writes)."""

    def __init__(self, directory: str, spec: FitSpec, fresh: bool = False, writer: bool = True):
        self.path = os.path.join(directory, LOG_NAME)
        self.writer = writer
        self.fingerprint = fingerprint(spec)
        self.samples: list[Sample] = []
        self.by_u: dict[tuple, Sample] = {}
        self.resumed = 0                    # samples read back from an earlier run
        if not fresh and os.path.exists(self.path):
            self._read()
        elif writer:
            os.makedirs(directory, exist_ok=True)
            with open(self.path, "w") as fh:
                fh.write(json.dumps({"fit": spec.name, "fingerprint": self.fingerprint}) + "\n")

    def _read(self) -> None:
        with open(self.path) as fh:
            lines = fh.read().split("\n")
        try:
            head = json.loads(lines[0])
        except (ValueError, IndexError):
            head = {}
        if head.get("fingerprint") != self.fingerprint:
            raise CalibrationError("output", f"{os.path.dirname(self.path)} holds the log of another fit "
                                             "(its model, parameters or data differ); give another "
                                             "output directory or run with --fresh")
        for line in lines[1:]:
            try:
                self._keep(Sample.from_record(json.loads(line)))
            except (ValueError, TypeError):
                continue                    # empty, or cut short by a kill
        self.resumed = len(self.samples)

    def _keep(self, s: Sample) -> None:
        self.samples.append(s)
        self.by_u[_key(s.u)] = s

    def get(self, u) -> Sample | None:
        return self.by_u.get(_key(u))

    def add(self, new: list[Sample]) -> None:
        """Keep ``new`` and append them to the file (flushed and synced)."""
        for s in new:
            s.index = len(self.samples)
            self._keep(s)
        if self.writer and new:
            with open(self.path, "a") as fh:
                for s in new:
                    fh.write(json.dumps(s.record()) + "\n")
                fh.flush()
                os.fsync(fh.fileno())

    def best(self, phase_prefix: str = "") -> Sample | None:
        """The sample of lowest cost (of phases starting with ``phase_prefix``)."""
        cands = [s for s in self.samples if s.phase.startswith(phase_prefix)]
        return min(cands, key=lambda s: s.cost) if cands else None

    def counts(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for s in self.samples:
            out[s.status] = out.get(s.status, 0) + 1
        return out

    def throughput(self) -> dict:
        """Solves, their wall time and how they were started (this process's samples)."""
        new = self.samples[self.resumed:]
        t = np.array([s.wall_time for s in new]) if new else np.zeros(0)
        return {"samples": len(self.samples), "solved_now": len(new), "resumed": self.resumed,
                "solve_time": float(t.sum()), "cpu_time": float(sum(s.cpu_time for s in new)),
                "starts": {k: sum(s.start == k for s in new) for k in ("cold", "nearest", "affine")},
                "fallback_levels": int(sum(s.fallbacks for s in new)),
                "newton_iterations": int(sum(s.newton_iterations for s in new))}
