"""A restart's probes must be the run's: every level's summary entry lists the same probes, and
``read_results(DIR).probe(name)`` reads one across all levels.  Compared by what they measure at
the restart point's state (so ``node: -1`` for ``last`` is the same probe), not by their text."""
from __future__ import annotations

import numpy as np

from ..errors import InputError


def probe_difference(stored: dict, now: dict) -> str | None:
    """What differs between the restart level's probe entries and the same probes evaluated by
    this model at its state ({name: {"displacement", "value"}}); None when the same."""
    added, removed = [n for n in now if n not in stored], [n for n in stored if n not in now]
    if added or removed:
        return "; ".join(f"{what} {', '.join(names)}" for what, names in
                         (("added", added), ("removed", removed)) if names)
    for name, entry in stored.items():
        a = np.asarray([entry["displacement"], entry["value"]], dtype=float)
        b = np.asarray([now[name]["displacement"], now[name]["value"]], dtype=float)
        if not np.allclose(a, b, rtol=1e-9, atol=1e-12 * max(1.0, float(np.abs(a).max()))):
            return f"{name} measures another place or vector (value {_vec(a[1])} → {_vec(b[1])})"
    return None


def check_same_probes(point, model, directory: str) -> None:
    """InputError naming the first probe the config adds, removes or changes against the run in
    ``directory`` (``point``: its io.restart.RestartPoint)."""
    steps = point.summary.get("steps") or []
    if not steps or "probes" not in steps[-1]:
        return
    q = np.asarray(point.blocks).reshape(-1, *np.shape(model.q0)[1:])[:model.n_nodes]
    now = {name: {"displacement": u.tolist(), "value": v.tolist()}
           for name, (u, v) in model.probe_values(q).items()}
    differs = probe_difference(steps[-1]["probes"], now)
    if differs:
        raise InputError("--restart", f"the config's probes differ from the run's in {directory}: "
                                      f"{differs}; every level lists the same probes: restart with the "
                                      "run's probes, or run afresh into another directory")


def _vec(v) -> str:
    return "[" + ", ".join(f"{x:.6g}" for x in np.ravel(v)) + "]"
