"""``accuracy: {probe, rtol}``: model no more than the scene needs.

The model is solved on a ladder of meshes (every beam's element count scaled together: the first
beam runs ``start``, 2·start, 4·start, … elements), each rung being the scene up to the probe's
load level.  After every rung the last three finite rungs give a Richardson estimate of the
converged probe (``refinement.choose``); the coarsest rung within ``rtol`` of it is chosen.  When
the probe's level is the scene's last step (or the scene follows a load history, whose rungs run
every frame), the chosen rung already is the full run and its files are adopted as the run's output; otherwise the scene is solved again with that element
count.  The rungs stay on disk under ``<output>/accuracy/``.
"""
from __future__ import annotations

import copy
import json
import math
import os
import shutil
import time

from .. import status as st
from ..config.parse import parse_config
from ..config.values import ConfigError
from ..config.specs import ModelSpec
from ..io.files import atomic_write
from ..io.levels import gap_note, reported_at
from .refinement import choose, level_step, quantity
from .section_order import check_section_order


def rung_elements(elements: int, factor: float) -> int:
    """A beam's element count on the rung that scales the first beam's by ``factor``."""
    return max(1, int(round(elements * factor)))


def _scaled_raw(spec: ModelSpec, factor: float, out_dir: str, level: float) -> dict:
    """The scene up to ``level`` with every beam's element count scaled by ``factor`` (a load
    history's rungs run its frames: a history has no ``steps`` to cut, and refused one)."""
    raw = copy.deepcopy({k: v for k, v in spec.raw.items() if k != "accuracy"})
    if spec.history is None:
        raw["steps"] = [s for s in spec.steps if s <= level * (1 + 1e-12)]
    raw["output"] = {"dir": out_dir, "vtk": spec.output.vtk}
    if spec.output.vtk:                      # vtk_samples with vtk off is refused (config/solving.py)
        raw["output"]["vtk_samples"] = spec.output.vtk_samples
    for b in raw.get("beams", []):
        b["elements"] = rung_elements(b["elements"], factor)
    return raw


#: what a rung takes from the spec itself, not from its config (``_scaled_raw``)
_RUNG_OWN = ("raw", "output", "accuracy", "steps", "base_dir")


def check_rungs_carry(spec: ModelSpec) -> None:
    """The rungs are the config (``spec.raw``) parsed again: a spec changed after parsing (the
    Python API) where the config does not say it (``api._raw_as_solved`` writes element counts,
    materials, steps and PETSc options) would be solved unchanged, as the bending scene with
    its loads halved was (tip 40.29 mm against 23.07 mm, 'completed').  ConfigError naming the
    first such change."""
    import dataclasses
    import numpy as np
    again = parse_config(spec.raw, base_dir=spec.base_dir)

    def first(a, b, path: str) -> str | None:
        if dataclasses.is_dataclass(a) and type(a) is type(b):
            a, b = vars(a), vars(b)
        if isinstance(a, dict) and isinstance(b, dict):
            keys = list(a) + [k for k in b if k not in a]
            return next((d for k in keys if (d := first(a.get(k), b.get(k), f"{path}.{k}"))), None)
        if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)) and len(a) == len(b):
            return next((d for i, (x, y) in enumerate(zip(a, b)) if (d := first(x, y, f"{path}[{i}]"))), None)
        same = np.array_equal(a, b) if isinstance(a, np.ndarray) or isinstance(b, np.ndarray) else a == b
        return None if same else path
    found = next((d for k, v in vars(spec).items() if k not in _RUNG_OWN
                  and (d := first(v, getattr(again, k), k))), None)
    if found:
        raise ConfigError("accuracy", f"the ladder's rungs are made from the config, and spec.{found} was "
                                      "changed after parsing, which the config does not say: the change "
                                      "would be ignored; write it into the config and parse that "
                                      "(parse_config), or set spec.accuracy = None")


def _adopt(rung_dir: str, out_dir: str, info: dict, comm) -> None:
    """Copy a rung's files into the run's output directory and record the choice (collective)."""
    if comm.rank == 0:
        os.makedirs(out_dir, exist_ok=True)
        for name in os.listdir(rung_dir):
            src = os.path.join(rung_dir, name)
            if os.path.isfile(src):
                shutil.copy2(src, os.path.join(out_dir, name))
        path = os.path.join(out_dir, "summary.json")
        with open(path) as fh:
            summary = json.load(fh)
        summary.update(info, output_dir=os.path.abspath(out_dir))
        atomic_write(path, json.dumps(summary, indent=1))
    comm.tompi4py().Barrier()


def element_counts(spec: ModelSpec) -> list[int]:
    """First-beam element counts of the ladder: start, 2 start, … ≤ max_elements, but those on
    which some beam's pretwist is under-resolved (``unresolved``) or some beam's count is rounded
    (``inexact``) while three others remain."""
    counts = _rungs(spec.accuracy)
    left = set(unresolved(spec, counts)) | set(inexact(spec, counts))
    resolved = [n for n in counts if n not in left]
    return resolved if len(resolved) >= 3 else counts


def inexact(spec: ModelSpec, counts: list[int]) -> list[int]:
    """The counts of ``counts`` whose rung rounds some beam's element count (beams of 4 and 6
    elements from start 1: 1, 1.5 -> 2, 3, 6): that beam is not refined by 2 from such a rung to
    the next, as the Richardson estimate assumes (refinement.richardson)."""
    base = spec.beams[0].elements
    return [n for n in counts if any((b.elements * n) % base for b in spec.beams)]


def _rungs(acc) -> list[int]:
    """start, 2 start, … ≤ max_elements."""
    counts, n = [], acc.start
    while n <= acc.max_elements:
        counts.append(n)
        n *= 2
    return counts


def unresolved(spec: ModelSpec, counts: list[int]) -> list[int]:
    """The counts of ``counts`` whose rung interpolates some beam's pretwist with a reference area
    off by more than 1 % (the build's warning, docs/model.md): the paper's tendon at 180 deg over 1
    and 2 elements (22 %, 1.9 %) put the Richardson limit of the soleus at 6.9030 mm, and 4 elements
    'met' rtol 2e-3 with an estimated 5.4e-4 where they are 3.3e-3 off (6.8838 mm at 32)."""
    from ..model.plausibility import elements_resolving
    from ..physics.elements import ELEMENTS
    if not spec.twist_deg:
        return []
    base = spec.beams[0].elements
    need = [(b.elements, (elements_resolving(spec.twist_deg, b.axial_points, ELEMENTS[b.element].block)
                          or (10 ** 9,))[0]) for b in spec.beams]
    return [n for n in counts if any(rung_elements(e, n / base) < k for e, k in need)]


def _left_out_note(spec: ModelSpec, skipped: list[int]) -> str:
    """Why the rungs ``skipped`` are left out of the ladder ('' when none is)."""
    rounded = inexact(spec, skipped)
    why = [f"{', '.join(map(str, w))} left out: {what}" for w, what in (
        ([n for n in skipped if n not in rounded], f"the {spec.twist_deg:g} deg pretwist is under-resolved there, "
                                                     "docs/model.md"),
        (rounded, "some beam's element count would be rounded, not doubled")) if w]
    return f" ({'; '.join(why)})" if why else ""


def select_and_run(spec: ModelSpec, comm, log, run_model):
    """Run the ladder, choose the element count, then ``run_model`` the chosen model (collective)."""
    from ..linalg.database import own_prefix
    from ..model.contact_setup import check_model
    check_model(spec)                   # the scene as written, before its rungs scale it
    acc = spec.accuracy
    say = log if comm.rank == 0 else (lambda *_: None)
    level = acc.level if acc.level is not None else max(spec.steps)
    base = spec.beams[0].elements
    t0 = time.perf_counter()
    rungs, values, results, chosen, errs, ex = [], [], [], None, [], None
    counts = element_counts(spec)
    skipped = [n for n in _rungs(acc) if n not in counts]
    say(f"[accuracy] probe {acc.probe} ({acc.component}) at load factor {level:g}, rtol {acc.rtol:g}: "
        f"ladder over elements per beam {counts}" + _left_out_note(spec, skipped))
    quiet = (lambda *_: None)
    for n in counts:
        out = os.path.join(spec.output.dir, "accuracy", f"elements_{n}")
        rung = parse_config(_scaled_raw(spec, n / base, out, level), base_dir=spec.base_dir,
                            source=f"accuracy rung {n}")
        say(f"[accuracy]   solving with {n} elements per beam ...")
        t1 = time.perf_counter()
        with own_prefix(rung.solver, "rung"):     # a rung's PETSc options apart from the others'
            res = run_model(rung, comm, quiet)
        if res.status == "interrupted" or res.reason_code == "OUTPUT_ERROR":
            return res                              # stop the ladder: a signal, or a full disk
        results.append(res)
        solved = res.status in ("completed", "unstable")    # unstable: the run's verdict, a value still
        value = quantity(res.summary, acc.probe, acc.component, level) if comm.rank == 0 and solved else None
        value = comm.tompi4py().bcast(value if solved else math.nan, root=0)
        gap = comm.tompi4py().bcast(gap_note(reported_at(level_step(res.summary, level)), "")
                                    if comm.rank == 0 and solved else "", root=0)
        seconds = time.perf_counter() - t1
        values.append(value)
        rungs.append({"elements": n, "value": value, "seconds": seconds, "status": res.status,
                      **({"level_passed_over": gap} if gap else {})})
        chosen, errs, ex = choose(values, acc.rtol)
        est = "" if ex is None or not ex.reliable else (
            f", limit {ex.limit:.8g} (order {ex.order:.2f})" if ex.kind == "richardson" else
            f", {ex.kind}: the last three agree within rtol/2, limit {ex.limit:.8g}")
        say(f"[accuracy]   {n:5d} elements: {acc.probe} = {value:.8g}  ({res.status}{', ' + gap if gap else ''}, "
            f"{seconds:.2f} s){est}")
        if chosen is not None:
            break
    for r, e in zip(rungs, errs):
        r["estimated_error"] = e
    ladder_time = time.perf_counter() - t0
    info = {"probe": acc.probe, "component": acc.component, "level": level, "rtol": acc.rtol,
            "ladder": rungs, "ladder_seconds": ladder_time, **({"left_out": skipped} if skipped else {}),
            "limit": None if ex is None else ex.limit, "order": None if ex is None else ex.order,
            "estimate": None if ex is None else ex.kind}
    if acc.section_order == "check" and rungs and math.isfinite(values[0]):
        start = os.path.join(spec.output.dir, "accuracy", "start")
        info["section_order"] = check_section_order(spec, comm, run_model, _scaled_raw(
            spec, rungs[0]["elements"] / base, start, level), values[0], level, say)
    if chosen is None:
        n = next((r["elements"] for r in reversed(rungs) if r["status"] in ("completed", "unstable")), None)
        info.update(chosen_elements=n or base, estimated_error=None, met=False)
        say(f"[accuracy] no rung met rtol {acc.rtol:g} with a reliable estimate up to "
            f"{acc.max_elements} elements; " + (f"solving with the finest finite rung, {n} elements" if n else
                                                f"every rung failed: solving the scene as written, {base} elements"))
        n = n or base
    else:
        n = rungs[chosen]["elements"]
        info.update(chosen_elements=n, estimated_error=errs[chosen], met=True)
        say(f"[accuracy] chosen: {n} elements per beam (first beam), estimated error "
            f"{errs[chosen]:.2e} <= {acc.rtol:g}; ladder {ladder_time:.2f} s")
    k = next((i for i, r in enumerate(rungs) if r["elements"] == n), None)    # None: n is no rung
    if k is not None and results[k].status in ("completed", "unstable") \
            and (spec.history is not None or level >= max(spec.steps) * (1 - 1e-12)):   # a history's rung: every frame
        info["reused_rung"] = True          # the chosen rung is the whole scene: no second solve
        _adopt(os.path.join(spec.output.dir, "accuracy", f"elements_{n}"), spec.output.dir,
               {"accuracy": info}, comm)
        res = results[k]
        if comm.rank == 0:
            res.summary.update(accuracy=info, output_dir=os.path.abspath(spec.output.dir))
        say(f"[accuracy] the {n}-element rung is the whole scene: its results are in {spec.output.dir}")
        say(f"[ancf] {res.status}: {res.message}; results in {spec.output.dir}")    # the rung ran quiet
        return _say_not_met(res, info, spec.output.dir, comm, say)
    info["reused_rung"] = False
    final = parse_config(_scaled_raw(spec, n / base, spec.output.dir, max(spec.steps)),
                         base_dir=spec.base_dir)
    return _say_not_met(run_model(final, comm, log, info={"accuracy": info}), info, spec.output.dir, comm, say)


def _say_not_met(res, info: dict, out_dir: str, comm, say):
    """A completed run whose ladder met no rtol says so (reason code ACCURACY_NOT_MET, in its message
    and summary.json): it ended as a plain "completed", its error unknown (collective)."""
    if info["met"] or res.status != "completed":
        return res
    note = (f"accuracy not met: no rung met rtol {info['rtol']:g} with a reliable estimate "
            f"(ladder {[r['elements'] for r in info['ladder']]} elements); this is the "
            f"{info['chosen_elements']}-element answer, its error unknown (raise accuracy.max_elements)")
    res.message = f"{res.message}; {note}"
    if res.reason_code == st.COMPLETED:
        res.reason_code = st.ACCURACY_NOT_MET
    if comm.rank == 0:
        path = os.path.join(out_dir, "summary.json")
        with open(path) as fh:
            summary = json.load(fh)
        summary.update(message=res.message, reason_code=res.reason_code)
        atomic_write(path, json.dumps(summary, indent=1))
        res.summary.update(message=res.message, reason_code=res.reason_code)
    comm.tompi4py().Barrier()
    say(f"[accuracy] {note}")
    return res
