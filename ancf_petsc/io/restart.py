"""Continue a run from the last converged level in its results.h5 (``ancf-solve --restart DIR``).

Every converged level stores what the load stepping needs to go on exactly as an uninterrupted
run would (results.py): the nodal vectors, the contact multipliers, the projection state of every
contact point and the status of every multiplier, the last accepted increment of the state and
of the load, and the next load increment.  All of it is in model order, so a restart may use
another number of ranks.  The model must be the one that wrote the file: the config's model
keys are compared, and the first difference is named.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass

import numpy as np
import yaml

from ..errors import InputError

#: config keys that define the model (a restart must not change them; steps, solver, petsc,
#: output and partition may change)
MODEL_KEYS = ("units", "geometry", "beams", "boundary_conditions", "loads", "contact", "bundle")


@dataclass
class RestartPoint:
    """The last converged level of a run, read from its results.h5 (model order)."""
    step: int                     # its number (1-based)
    load_factor: float
    blocks: np.ndarray            # (n_blocks, 18): nodal vectors, then multiplier blocks
    increment_blocks: np.ndarray  # (n_blocks, 18): the last accepted increment of the state
    increment: float              # the next load increment
    last_increment: float         # the last accepted one
    accepted_negative: int
    projection: np.ndarray | None  # (points, 3) e_B, ξ_B, t_B
    status: np.ndarray | None      # (multipliers,) active
    summary: dict                 # summary.json with the steps up to ``step``


def _first_difference(old, new, path: str = "") -> str | None:
    """Key path of the first difference between two config trees (None if equal)."""
    if isinstance(old, dict) and isinstance(new, dict):
        for key in list(old) + [k for k in new if k not in old]:
            sub = f"{path}.{key}" if path else str(key)
            if key not in old or key not in new:
                return sub
            found = _first_difference(old[key], new[key], sub)
            if found:
                return found
        return None
    if isinstance(old, list) and isinstance(new, list):
        if len(old) != len(new):
            return f"{path} (length {len(old)} → {len(new)})"
        for i, (a, b) in enumerate(zip(old, new)):
            found = _first_difference(a, b, f"{path}[{i}]")
            if found:
                return found
        return None
    return None if old == new else path


def read_restart(directory: str, raw: dict) -> RestartPoint:
    """The last converged level of the run in ``directory``; ``raw`` is the config of the
    continuing run (its model keys must equal the stored ones).  InputError with one line when
    the directory has no usable results or was made by another model."""
    import h5py
    path = os.path.join(directory, "results.h5")
    if not os.path.isfile(path):
        raise InputError("--restart", f"{path}: no such file (restart from a run's output directory)")
    summary_path = os.path.join(directory, "summary.json")
    try:
        with open(summary_path) as fh:
            summary = json.load(fh)
    except (OSError, ValueError):
        summary = {"steps": []}
    try:
        with h5py.File(path, "r") as h5:
            stored = yaml.safe_load(h5["model"].attrs["config_yaml"])
            steps = h5["steps"]
            # a run killed between writing a level to results.h5 and to summary.json: continue
            # from the last level both hold (the other is solved again)
            k = min(int(steps.attrs.get("converged", 0)), len(summary.get("steps", [])))
            if k == 0:
                raise InputError("--restart", f"{path}: no converged level to restart from; run it afresh")
            g = steps[f"step_{k:04d}"]
            if "restart" not in g:
                raise InputError("--restart", f"{path}: written without restart data (an older version)")
            r = g["restart"]
            point = RestartPoint(step=k, load_factor=float(g.attrs["load_factor"]),
                                 blocks=r["blocks"][()], increment_blocks=r["increment_blocks"][()],
                                 increment=float(r.attrs["increment"]),
                                 last_increment=float(r.attrs["last_increment"]),
                                 accepted_negative=int(r.attrs["accepted_negative"]),
                                 projection=g["contact/projection"][()] if "contact" in g else None,
                                 status=g["contact/multiplier_active"][()] if "contact" in g else None,
                                 summary={})
    except (OSError, KeyError) as exc:
        raise InputError("--restart", f"{path}: not a readable results file ({exc})") from None
    differs = _first_difference({k: stored.get(k) for k in MODEL_KEYS}, {k: raw.get(k) for k in MODEL_KEYS})
    if differs:
        raise InputError("--restart", f"{directory} was written by another model: {differs} differs "
                                      "from the config's; restart with the config that made it")
    summary["steps"] = summary.get("steps", [])[:point.step]
    point.summary = summary
    return point
