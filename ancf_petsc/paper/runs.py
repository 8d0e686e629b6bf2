"""Studies of the reproduction as sweeps over the Achilles config (workflows/sweep): finished runs
are reused, failures stay clean, runs may use several ranks."""
from __future__ import annotations

import json
import os

import numpy as np
import yaml

from ..workflows import sweep as sw
from .inputs import PROBE, PaperInputs


def make_sweep(inputs: PaperInputs, out: str, name: str, parameters: dict, mode: str = "list", ranks: int = 1,
               jobs: int = 1, petsc: list[str] | None = None) -> sw.Sweep:
    """Write ``<out>/<name>.sweep.yaml`` and load it."""
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, f"{name}.sweep.yaml")
    # the report marks unstable levels itself (Table 2's "u"): they are results, not failures
    n = len(next(iter(parameters.values()))) if mode == "list" else 1
    parameters = {**parameters, "solver.allow_unstable": [True] * n}
    doc = {"base": inputs.base, "name": name, "mode": mode, "parameters": parameters,
           "run": {"ranks": ranks, "jobs": jobs, "petsc": list(petsc or [])},
           "output": os.path.join(out, name)}
    with open(path, "w") as fh:
        yaml.safe_dump(doc, fh, sort_keys=False)
    return sw.load_sweep(path)


def execute(sweep: sw.Sweep, log=print) -> list[sw.RunState]:
    """Run what is not done yet; the state of every run afterwards.  A sweep stopped by Ctrl-C
    or SIGTERM (its runs stopped at their next safe point) raises KeyboardInterrupt: a report
    does not read its runs stopped half-way as levels not reached."""
    report = sw.run_sweep(sweep, log=log)
    sw.collect(sweep)
    if report.interrupted:
        raise KeyboardInterrupt
    return [sw.run_state(r) for r in sw.expand(sweep)]


def summary_of(state: sw.RunState) -> dict | None:
    """The run's summary.json, its ``output_dir`` the run's directory now (a sweep moved after its
    runs keeps them; summary.json names where they ran, which the figures read otherwise)."""
    path = os.path.join(state.run.dir, "summary.json")
    if not os.path.exists(path):
        return None
    with open(path) as fh:
        return dict(json.load(fh), output_dir=os.path.abspath(state.run.dir))


def elongation(step: dict, probe: str = PROBE) -> float:
    """A converged step's x-elongation [mm] of a probe."""
    return 1e3 * step["probes"][probe]["displacement"][0]


def elongations(summary: dict, probe: str = PROBE) -> tuple[np.ndarray, np.ndarray]:
    """(load levels, x-elongation [mm]) of a probe over the converged steps."""
    steps = summary["steps"]
    return (np.array([s["load_factor"] for s in steps]),
            np.array([elongation(s, probe) for s in steps]))
