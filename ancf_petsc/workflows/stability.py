"""Stability map: where the nonlinear solution strategy converges, where it fails, and how.

A stability file (YAML)::

    kind: stability
    name: bending_stability
    base: ../bending_neohookean.yaml       # the scene, relative to this file
    probe: tip                              # quantity of interest for the error column
    component: z
    axes:                                   # every combination is solved (each axis optional)
      increment: [adaptive, 0.25, 1.0]      # 'adaptive' = the config's load stepping (cut-backs,
                                            #   growth); a number = fixed increments of that fraction
                                            #   of the last load level, no cut-back: the raw method
      linesearch: [basic, bt, l2, cp]       # -snes_linesearch_type
      bulk_ratio: [10, 1000]                # K / mu of every neo-Hookean beam (mu kept)
      contact: [sliding, unilateral]        # contact.mode (contact scenes)
      element: ["3363", "3333", "3333-none"]  # element type (-none: 3333 without its locking remedy)
    reference: {element: "3363", axial_points: 2, elements: 32}   # per (bulk_ratio, contact)
    max_it: 50                              # Newton iterations per increment
    max_newton: 2000                        # Newton iterations per cell (a slow cell is a failure)
    output: ../../results/studies/bending_stability

Every cell is solved in this process to the base config's last load level.  A cell records
converged / failed, the Newton iterations, the SNES reason of a failure and the one-line message
the solver gave, and the relative error of the probe against the reference solution at the same
physical parameters (the reference discretisation solved with the adaptive default strategy):
so discretisation failures (locking: a converged but wrong answer) show beside solver failures.
Results: ``<output>/stability.csv`` and ``<output>/stability.png``.
"""
from __future__ import annotations

import copy
import csv
import itertools
import math
import os
import time
from dataclasses import dataclass
from typing import Callable


from .. import yamlio
from ..io.files import prepare_output_dir
from ..config.specs import LOCKING
from ..contact.laws import LAWS
from ..physics.elements import ELEMENTS
from ..physics.materials import NeoHookean
from ..status import CONFIG_ERROR
from .refinement import Discretisation, apply, quantity
from .study import (Scene, StudyError, check_reference, expect, parse_discretisation, parse_scene, read_yaml,
                    solve_raw)

AXES = ("increment", "linesearch", "bulk_ratio", "contact", "element")
PHYSICAL = ("bulk_ratio", "contact")     # change the model: one reference per value
LINESEARCHES = ("basic", "bt", "l2", "cp")
KEYS = ("kind", "name", "base", "probe", "component", "axes", "reference", "max_it", "max_newton",
        "output")
ADAPTIVE = "adaptive"


@dataclass
class StabilitySpec:
    name: str
    scene: Scene
    axes: dict[str, list]
    reference: Discretisation
    max_it: int
    output: str
    max_newton: int | None = None


def _element(value: str) -> dict:
    """'3363' | '3333' | '3333-none' → the beam keys it sets."""
    element, _, locking = str(value).partition("-")
    return {"element": element, **({"locking": locking} if locking else {})}


def cell_config(scene: Scene, cell: dict, max_it: int, max_newton: int | None = None) -> dict:
    """The raw config of one cell of the map."""
    raw = copy.deepcopy(scene.raw)
    last = float(raw["steps"][-1])
    raw["steps"] = [last]
    for beam in raw["beams"]:
        if "element" in cell:
            beam.pop("locking", None)
            beam.update(_element(cell["element"]))
        mat = beam["material"]
        if "bulk_ratio" in cell:
            if mat.get("model") != NeoHookean.name or "mu" not in mat:
                raise StudyError("axes.bulk_ratio", f"beam {beam['name']}: needs a neo-hookean "
                                                    "material given by mu and bulk_modulus")
            mat["bulk_modulus"] = float(cell["bulk_ratio"]) * float(mat["mu"])
    if "contact" in cell:
        if raw.get("contact") is None:
            raise StudyError("axes.contact", "the base config has no contact")
        raw["contact"]["mode"] = str(cell["contact"])
    solver = raw.setdefault("solver", {})
    if max_newton is not None:
        solver["max_newton_iterations"] = max_newton
    inc = cell.get("increment", ADAPTIVE)
    if inc != ADAPTIVE:
        step = float(inc) * last
        solver.update(initial_increment=step, max_increment=step, max_cutbacks=0, growth=1.0)
    petsc = raw.setdefault("petsc", {})
    petsc["snes_max_it"] = max_it
    if "linesearch" in cell:
        petsc["snes_linesearch_type"] = cell["linesearch"]
    return raw


def short_reason(code: str, inverted: bool = False) -> str:
    """A few letters for a chart cell from a run's reason code (RunResult.reason_code)."""
    if not code or not code.isupper():
        return "error"
    text = code.replace("DIVERGED_", "").replace("FNORM_NAN", "NaN")
    text = text.replace("NEWTON_BUDGET_EXCEEDED", "budget")
    return text.replace("LINE_SEARCH", "LS").replace("MAX_IT", "max it") + (" J<0" if inverted else "")


def _physical(cell: dict) -> tuple:
    return tuple((k, cell[k]) for k in PHYSICAL if k in cell)


def run_stability(spec: StabilitySpec, log: Callable[[str], None] = print) -> dict:
    """Solve every cell (and the references); write stability.csv and stability.png."""
    from ..viz.charts import stability_chart
    prepare_output_dir(spec.output, "output / --out")   # OutputError naming the path and keys
    t0 = time.perf_counter()
    keys = [k for k in AXES if k in spec.axes]
    cells = [dict(zip(keys, combo)) for combo in itertools.product(*(spec.axes[k] for k in keys))]
    refs: dict[tuple, float] = {}
    for phys in dict.fromkeys(_physical(c) for c in cells):
        raw = apply(cell_config(spec.scene, dict(phys), 100), spec.reference)
        res, summary = solve_raw(raw, spec.scene.base_dir, os.path.join(spec.output, "reference"))
        if res.reason_code == CONFIG_ERROR:      # the scene refuses this axis value (e.g. sliding circles)
            raise StudyError("axes." + ", axes.".join(k for k, _ in phys) if phys else "reference",
                             f"the scene refuses {dict(phys)}: {res.message}")
        if res.status != "completed":
            raise StudyError("reference", f"the reference at {dict(phys)} did not converge: {res.message}")
        refs[phys] = check_reference(spec.scene, quantity(summary, spec.scene.probe, spec.scene.component))
        log(f"[stability] reference {dict(phys)}: {spec.scene.probe} = {refs[phys]:.8g}")
    out = []
    for k, cell in enumerate(cells):
        raw = cell_config(spec.scene, cell, spec.max_it, spec.max_newton)
        res, summary = solve_raw(raw, spec.scene.base_dir, os.path.join(spec.output, "cell"))
        ok = res.status == "completed"
        value = quantity(summary, spec.scene.probe, spec.scene.component) if ok else math.nan
        ref = refs[_physical(cell)]
        row = {**cell, "status": res.status, "iterations": int(summary["newton_iterations"]) if summary else 0,
               "wall_time": float(summary["timings"]["total"]) if summary else math.nan,
               "value": value, "rel_error": abs(value - ref) / abs(ref) if ok else math.nan,
               "message": "" if ok else res.message,
               "short": "" if ok else short_reason(res.reason_code, res.inverted),
               "reason_code": "" if ok else res.reason_code}
        out.append(row)
        what = (f"{row['iterations']} its, error {row['rel_error']:.1e}" if ok
                else f"FAILED {row['short']} after {row['iterations']} its")
        log(f"[stability] {k + 1}/{len(cells)} " + " ".join(f"{key}={cell[key]}" for key in keys)
            + f": {what}")
    path = os.path.join(spec.output, "stability.csv")
    fields = keys + ["status", "iterations", "wall_time", "value", "rel_error", "short", "message"]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        w.writerows(out)
    axes4 = _chart_axes(keys)
    png = stability_chart(out, os.path.join(spec.output, "stability.png"), *axes4,
                          title=f"{spec.name.replace('_', ' ')}: Newton iterations to the last load "
                                f"level") if axes4 else None
    n_ok = sum(r["status"] == "completed" for r in out)
    log(f"[stability] {n_ok}/{len(out)} cells converged, {time.perf_counter() - t0:.1f} s; {path}"
        + (f", {png}" if png else ""))
    return {"cells": out, "references": refs, "csv": path, "png": png}


def _chart_axes(keys: list[str]) -> tuple[str, str, str, str] | None:
    """(row, column, x, y) keys of the chart: x increment, y line search, the rest on panels."""
    if "increment" not in keys or "linesearch" not in keys:
        return None
    rest = [k for k in keys if k not in ("increment", "linesearch")]
    if len(rest) > 2:
        return None
    rest = (rest + ["", ""])[:2]
    return rest[0], rest[1], "increment", "linesearch"


def default_strategy_converged(result: dict) -> bool:
    """Did the adaptive default (basic line search) converge in every cell that uses it?"""
    cells = [c for c in result["cells"] if c.get("increment", ADAPTIVE) == ADAPTIVE
             and c.get("linesearch", "basic") == "basic"]
    return bool(cells) and all(c["status"] == "completed" for c in cells)


def load_stability(path: str) -> StabilitySpec:
    """Read and check a stability file."""
    doc = read_yaml(path)
    expect(isinstance(doc, dict), "", yamlio.not_a_mapping(doc, KEYS))
    for key in doc:
        expect(key in KEYS, key, f"unknown key; allowed: {', '.join(KEYS)}")
    here = os.path.dirname(os.path.abspath(path))
    scene = parse_scene(doc, here)
    axes = doc.get("axes")
    expect(isinstance(axes, dict) and axes, "axes", f"expected a mapping of lists over {', '.join(AXES)}")
    for key, vals in axes.items():
        kp = f"axes.{key}"
        expect(key in AXES, kp, f"unknown key; allowed here: {', '.join(AXES)}")
        expect(isinstance(vals, list) and vals, kp, "expected a non-empty list")
        if key == "increment":
            expect(all(v == ADAPTIVE or (isinstance(v, (int, float)) and 0 < v <= 1) for v in vals),
                    kp, "expected 'adaptive' or fractions 0 < f <= 1 of the last load level")
        elif key == "linesearch":
            expect(all(v in LINESEARCHES for v in vals), kp, f"expected values from {', '.join(LINESEARCHES)}")
        elif key == "contact":
            expect(all(v in LAWS for v in vals), kp, f"expected {' or '.join(LAWS)}")
        elif key == "element":
            axes[key] = vals = [str(v) for v in vals]
            expect(all(_element(v)["element"] in ELEMENTS
                        and _element(v).get("locking", LOCKING[0]) in LOCKING for v in vals),
                    kp, f"expected an element type ({', '.join(ELEMENTS)}), optionally with a locking "
                        f"remedy: {', '.join(f'{e}-{lock}' for e in ELEMENTS for lock in LOCKING)}")
        else:
            expect(all(isinstance(v, (int, float)) and v > 0 for v in vals), kp, "expected positive numbers")
    if "contact" in axes:
        expect(scene.raw.get("contact") is not None, "axes.contact", "the base config has no contact")
    ref = Discretisation(**parse_discretisation(doc.get("reference", {}), "reference"))
    max_it = doc.get("max_it", 50)
    expect(isinstance(max_it, int) and max_it >= 1, "max_it", "expected an integer >= 1")
    max_newton = doc.get("max_newton")
    expect(max_newton is None or (isinstance(max_newton, int) and max_newton >= 1), "max_newton",
            "expected an integer >= 1 (Newton iterations per cell)")
    name = str(doc.get("name", os.path.splitext(os.path.basename(path))[0]))
    output = os.path.normpath(os.path.join(here, str(doc.get("output", os.path.join("studies", name)))))
    return StabilitySpec(name=name, scene=scene, axes=axes, reference=ref, max_it=max_it, output=output,
                         max_newton=max_newton)
