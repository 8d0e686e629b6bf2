"""How many elements a stride needs: the walking stride of the gait envelope (workflows/envelope.py,
100 frames, 2.63 kN peak) solved on a ladder of meshes, and each output's largest difference over
the frames from the finest mesh's, beside the frames per second (issue 38; docs/gait.md, "How many
elements a stride needs").

An output's *error* at n elements is max over the frames |q_n − q_finest| / max over the frames
|q_finest|: the finest mesh is the reference (no exact answer exists for the stride), so the
finest rung has none and the next one's error is an estimate of its own.  The *observed order*
of the three finest rungs, log2(|q_a − q_b| / |q_b − q_c|) with the maxima over the frames, says
whether the ladder is in the asymptotic range (about 2 for a smooth output of a mesh halved).
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass

import numpy as np

from .envelope import NEO, EnvelopeCell, run_cell

#: the outputs compared, summary.json's per frame: (kind, where in a step, unit)
KINDS = ("strain", "difference", "normal force", "pressing force", "slip")
UNITS = {"strain": "", "difference": "m", "normal force": "N", "pressing force": "N", "slip": "m"}


def stride_series(summary: dict) -> dict[str, np.ndarray]:
    """Per output of a stride's summary.json, its value at every frame: ``strain <subtendon>``,
    ``difference <first|second>`` (the end difference, first − second), ``normal force
    <interface>`` (pressing + tension), ``pressing force <interface>`` and, with a tangential
    law, ``slip <interface>`` (the largest tangential slip)."""
    out: dict[str, list[float]] = {}
    for st in summary["steps"]:
        for name, v in st.get("subtendons", {}).items():
            out.setdefault(f"strain {name}", []).append(v["strain"])
        for pair, v in st.get("displacement_differences", {}).items():
            out.setdefault(f"difference {pair}", []).append(v["end"])
        for key, v in st.get("contact", {}).items():
            if not isinstance(v, dict) or "normal_force" not in v:
                continue
            itf = key.split()[0]
            out.setdefault(f"normal force {itf}", []).append(v["normal_force"])
            out.setdefault(f"pressing force {itf}", []).append(v["pressing_force"])
            if "max_tangential_slip" in v:
                out.setdefault(f"slip {itf}", []).append(v["max_tangential_slip"])
    return {k: np.asarray(v, dtype=float) for k, v in out.items()}


def kind_of(output: str) -> str:
    """The kind (``KINDS``) of an output name of ``stride_series``."""
    return next(k for k in sorted(KINDS, key=len, reverse=True) if output.startswith(k + " "))


def mesh_errors(series: dict[int, dict[str, np.ndarray]]) -> dict[int, dict[str, float]]:
    """Per element count but the finest, per output: max over the frames |q_n − q_finest| / max
    over the frames |q_finest| (NaN where the finest output is 0 at every frame or the frame
    counts differ)."""
    finest = max(series)
    ref = series[finest]
    out = {}
    for n, s in series.items():
        if n == finest:
            continue
        row = {}
        for k, r in ref.items():
            scale = float(np.max(np.abs(r), initial=0.0))
            q = s.get(k)
            ok = q is not None and q.shape == r.shape and scale > 0.0
            row[k] = float(np.max(np.abs(q - r)) / scale) if ok else math.nan
        out[n] = row
    return out


def observed_order(series: dict[int, dict[str, np.ndarray]], output: str) -> float:
    """log2 of the ratio of the two finest differences of ``output`` over the three finest rungs
    (NaN with fewer rungs or a zero difference)."""
    if len(series) < 3:
        return math.nan
    a, b, c = (series[n].get(output) for n in sorted(series)[-3:])
    if a is None or b is None or c is None or not a.shape == b.shape == c.shape:
        return math.nan
    d1, d2 = float(np.max(np.abs(a - b))), float(np.max(np.abs(b - c)))
    return math.log2(d1 / d2) if d1 > 0.0 and d2 > 0.0 else math.nan


def worst_by_kind(errors: dict[str, float]) -> dict[str, float]:
    """The largest error of each kind present (NaN errors left out)."""
    out: dict[str, float] = {}
    for k, e in errors.items():
        if not math.isnan(e):
            kind = kind_of(k)
            out[kind] = max(out.get(kind, 0.0), e)
    return out


@dataclass(frozen=True)
class Law:
    """A contact law of the study: its label, ``contact.mode``, Coulomb μ (0: none) and the
    pressure's degree along the beam (``contact.projection.axial``; None: the default)."""
    label: str
    mode: str
    friction: float = 0.0
    pressure_axial: int | None = None


LAWS = {"sliding": Law("sliding", "sliding"), "unilateral": Law("unilateral", "unilateral"),
        "mu0.3": Law("mu 0.3", "sliding", 0.3),
        "mu0.3-quadratic": Law("mu 0.3, quadratic pressure", "sliding", 0.3, 2)}


def run_ladder(law: Law, elements: list[int], solver: list[str], workdir: str, twist: float = 45.0,
               bias: str = "uniform", base: str = NEO) -> tuple[list[dict], dict[int, dict[str, np.ndarray]]]:
    """Solve the stride of ``law`` at each element count: (a row per rung: elements, status,
    Newton iterations, frames cut back, solve and wall time [s], frames per second of solve;
    the series of the rungs that completed, by element count)."""
    rows, series = [], {}
    for n in elements:
        cell = EnvelopeCell(base, twist, bias, law.mode, law.friction, n, stride=True,
                            pressure_axial=law.pressure_axial)
        r = run_cell(cell, solver, workdir)
        rows.append({"law": law.label, "twist": twist, "bias": bias, "elements": n, "status": r.status,
                     "iterations": r.iterations, "frames": r.frames, "frames_cut_back": r.cutback_levels,
                     "solve_time": round(r.solve_time, 3), "wall_time": round(r.wall_time, 2),
                     "frames_per_s": round(r.frames / r.solve_time, 2) if r.solve_time > 0 else 0.0})
        path = os.path.join(workdir, cell.name, "run", "summary.json")
        if r.status == "completed" and os.path.isfile(path):
            with open(path) as fh:
                series[n] = stride_series(json.load(fh))
    return rows, series


def with_errors(rows: list[dict], series: dict[int, dict[str, np.ndarray]]) -> list[dict]:
    """``rows`` of one law with, per kind, the rung's worst error against the finest completed
    rung (``error_<kind>``, empty for the finest and for a rung that did not complete) and the
    worst observed order of the kind (``order_<kind>``, on the finest row)."""
    errors = mesh_errors(series) if len(series) > 1 else {}
    finest = max(series) if series else None
    out = []
    for row in rows:
        row = dict(row)
        worst = worst_by_kind(errors.get(row["elements"], {}))
        for kind in KINDS:
            key = kind.replace(" ", "_")
            row[f"error_{key}"] = f"{worst[kind]:.3g}" if kind in worst else ""
            orders = [observed_order(series, k) for k in (series[finest] if finest else {})
                      if kind_of(k) == kind] if row["elements"] == finest else []
            orders = [p for p in orders if not math.isnan(p)]
            row[f"order_{key}"] = f"{min(orders):.2f}" if orders else ""
        out.append(row)
    return out


def markdown(rows: list[dict]) -> str:
    """The study's table: per law and mesh, frames/s, Newton iterations, frames cut back and the
    worst error of each kind against the law's finest mesh; the finest row says "reference" and
    the lowest observed order of the kind's outputs; "—" where a law has no such output."""
    kinds = [k for k in KINDS if any(r.get(f"error_{k.replace(' ', '_')}") for r in rows)]
    has = {(r["law"], k) for r in rows for k in kinds if r.get(f"error_{k.replace(' ', '_')}")}
    head = ["law", "elements", "frames/s (solve)", "Newton iterations", "frames cut back"] + [
        f"{k} error" for k in kinds]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * 2 + "---:|" * (len(head) - 2)]
    for r in rows:
        if r["status"] != "completed":
            cells = [r["law"], str(r["elements"]), r["status"], "", ""] + [""] * len(kinds)
        else:
            errs = []
            for k in kinds:
                key = k.replace(" ", "_")
                e, p = r.get(f"error_{key}", ""), r.get(f"order_{key}", "")
                errs.append("—" if (r["law"], k) not in has else f"{float(e):.1e}" if e else
                            f"reference (order {p})" if p else "reference")
            cells = [r["law"], str(r["elements"]), f"{float(r['frames_per_s']):.1f}", str(r["iterations"]),
                     str(r["frames_cut_back"])] + errs
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)
