"""``accuracy: {probe, rtol}``: model no more than the scene needs.

Before the real run, the model is solved on a ladder of meshes (every beam's element count
scaled together: the first beam runs ``start``, 2·start, 4·start, … elements), each rung only up
to the probe's load level and without ParaView output.  After every rung the last three finite
rungs give a Richardson estimate of the converged probe (``refinement.choose``); the coarsest
rung within ``rtol`` of it is chosen, and the full run (every step, every output) is done with
that element count.  The ladder's rungs stay on disk under ``<output>/accuracy/``.
"""
from __future__ import annotations

import copy
import math
import os
import time

from .config import ModelSpec, parse_config
from .refinement import choose, quantity


def _rung_raw(spec: ModelSpec, factor: float, out_dir: str, level: float) -> dict:
    raw = copy.deepcopy({k: v for k, v in spec.raw.items() if k != "accuracy"})
    raw["steps"] = [s for s in spec.steps if s <= level * (1 + 1e-12)][-1:]
    raw["output"] = {"dir": out_dir, "vtk": False}
    for b in raw.get("beams", []):
        b["elements"] = max(1, int(round(b["elements"] * factor)))
    return raw


def element_counts(spec: ModelSpec) -> list[int]:
    """First-beam element counts of the ladder: start, 2 start, … ≤ max_elements."""
    acc = spec.accuracy
    counts, n = [], acc.start
    while n <= acc.max_elements:
        counts.append(n)
        n *= 2
    return counts


def select_and_run(spec: ModelSpec, comm, log, run_model):
    """Run the ladder, choose the element count, then ``run_model`` the chosen model (collective)."""
    acc = spec.accuracy
    say = log if comm.rank == 0 else (lambda *_: None)
    level = acc.level if acc.level is not None else max(spec.steps)
    base = spec.beams[0].elements
    t0 = time.perf_counter()
    rungs, values, chosen, errs, ex = [], [], None, [], None
    say(f"[accuracy] probe {acc.probe} ({acc.component}) at load factor {level:g}, rtol {acc.rtol:g}: "
        f"ladder over elements per beam {element_counts(spec)}")
    quiet = (lambda *_: None)
    for n in element_counts(spec):
        out = os.path.join(spec.output.dir, "accuracy", f"elements_{n}")
        rung = parse_config(_rung_raw(spec, n / base, out, level), base_dir=spec.base_dir,
                            source=f"accuracy rung {n}")
        t1 = time.perf_counter()
        res = run_model(rung, comm, quiet)
        value = quantity(res.summary, acc.probe, acc.component, level) if comm.rank == 0 else None
        value = comm.tompi4py().bcast(value if res.status == "completed" else math.nan, root=0)
        seconds = time.perf_counter() - t1
        values.append(value)
        rungs.append({"elements": n, "value": value, "seconds": seconds, "status": res.status})
        chosen, errs, ex = choose(values, acc.rtol)
        est = "" if ex is None or not ex.reliable else f", limit {ex.limit:.8g} (order {ex.order:.2f})"
        say(f"[accuracy]   {n:5d} elements: {acc.probe} = {value:.8g}  ({res.status}, {seconds:.2f} s){est}")
        if chosen is not None:
            break
    for r, e in zip(rungs, errs):
        r["estimated_error"] = e
    ladder_time = time.perf_counter() - t0
    info = {"probe": acc.probe, "component": acc.component, "level": level, "rtol": acc.rtol,
            "ladder": rungs, "ladder_seconds": ladder_time,
            "limit": None if ex is None else ex.limit, "order": None if ex is None else ex.order}
    if chosen is None:
        n = next((r["elements"] for r in reversed(rungs) if r["status"] == "completed"), base)
        info.update(chosen_elements=n, estimated_error=None, met=False)
        say(f"[accuracy] no rung met rtol {acc.rtol:g} with a reliable estimate up to "
            f"{acc.max_elements} elements; solving with the finest finite rung, {n} elements")
    else:
        n = rungs[chosen]["elements"]
        info.update(chosen_elements=n, estimated_error=errs[chosen], met=True)
        say(f"[accuracy] chosen: {n} elements per beam (first beam), estimated error "
            f"{errs[chosen]:.2e} <= {acc.rtol:g}; ladder {ladder_time:.2f} s")
    final_raw = copy.deepcopy({k: v for k, v in spec.raw.items() if k != "accuracy"})
    for b in final_raw.get("beams", []):
        b["elements"] = max(1, int(round(b["elements"] * n / base)))
    final = parse_config(final_raw, base_dir=spec.base_dir)
    final.output = spec.output
    return run_model(final, comm, log, info={"accuracy": info})
