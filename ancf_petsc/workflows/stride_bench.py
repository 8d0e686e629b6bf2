"""Frames per second of a walking stride (issue 38, point 4): the shipped stride (100 frames,
workflows/stride.py) on the paper's tendon, by elements, contact law and material.

*After* (this tree): the stride as one load history, each frame continued from the one before
(``ancf-solve`` on the history config, in a child process): frames / the run's solve time, and
frames / its wall time (start-up and output included).  *Before* (a commit without load
histories, such as 38a07d3): a frame could only be its own run from rest, its loads applied
proportionally (``steps: [1]``), losing the path and the friction history; its frames/s is the
number of sampled frames over their summed wall time.  The two are run in turns (``repeats``)."""
from __future__ import annotations

import json
import os
from dataclasses import dataclass

import numpy as np

from .envelope import STRIDE_COLUMNS, BEAMS, EnvelopeCell, cell_config, solve_config
from .stride import synthetic_stride


@dataclass(frozen=True)
class StrideCase:
    """A stride cell (``EnvelopeCell`` with stride=True) and a label."""
    label: str
    cell: EnvelopeCell


def after(case: StrideCase, cmd: list[str], work: str, petsc: dict | None = None, tag: str = "after") -> dict:
    """The stride as one history (``petsc``: options for its config, run in ``tag``): frames,
    status, Newton iterations, frames/s (solve, wall) and the summary."""
    cfg = cell_config(case.cell)
    cfg["output"] = {"vtk": False}
    if petsc:
        cfg["petsc"] = dict(cfg.get("petsc") or {}, **petsc)
    _, wall, s = solve_config(cmd, cfg, os.path.join(work, case.label, tag))
    if s is None:
        return {"status": "crashed", "frames": 0, "summary": None}
    frames = len(s["steps"])
    return {"status": s["status"], "frames": frames, "iterations": s["newton_iterations"],
            "per_solve": frames / max(s["timings"]["solve"], 1e-9), "per_wall": frames / wall, "summary": s}


def before(case: StrideCase, cmd: list[str], work: str, sample: int) -> dict:
    """``sample`` frames of the stride (evenly spaced over the stance), each its own proportional
    run from rest with ``cmd``: frames/s over their summed wall time, Newton iterations per frame."""
    times, forces = synthetic_stride(case.cell.bias)
    stance = np.flatnonzero(sum(forces.values()) > 100.0)
    frames = stance[np.linspace(0, len(stance) - 1, sample).round().astype(int)]
    base = cell_config(EnvelopeCell(case.cell.base, case.cell.twist, case.cell.bias, case.cell.law,
                                    case.cell.friction, case.cell.elements, levels=(1.0,)))
    base["output"] = {"vtk": False}
    total, its, done = 0.0, [], 0
    for k in frames:
        cfg = json.loads(json.dumps(base))
        for ld, col in zip(cfg["loads"], STRIDE_COLUMNS[:len(BEAMS)]):
            ld["traction_force"] = [float(forces[col][k]), 0.0, 0.0]
        _, wall, s = solve_config(cmd, cfg, os.path.join(work, case.label, f"before_{k:03d}"))
        total += wall
        if s is not None and s["status"] == "completed":
            done += 1
            its.append(s["newton_iterations"])
    return {"frames": len(frames), "completed": done, "per_wall": len(frames) / total,
            "median_iterations": float(np.median(its)) if its else float("nan")}


def _outputs(summary: dict) -> tuple[np.ndarray, np.ndarray]:
    """Every frame's probe displacements and differential-displacement profiles, flattened."""
    probes = [v for st in summary["steps"] for n in sorted(st["probes"]) for v in st["probes"][n]["displacement"]]
    diffs = [v for st in summary["steps"] for k in sorted(st.get("displacement_differences", {}))
             for v in st["displacement_differences"][k]["profile"]]
    return np.array(probes), np.array(diffs)


def tolerance_sweep(case: StrideCase, cmd: list[str], work: str, factors: list[float]) -> list[dict]:
    """The stride with the absolute tolerance at ``factors`` × the run's own (1e-10 of the load,
    solving/snes_solver.py, summary.json ``tolerances``; ``petsc: {snes_atol}``): per factor the tolerance, Newton iterations,
    frames/s of solve and the largest change of the probes' displacements and of the
    differential displacements over every frame against the run's own tolerance, relative to
    their largest value (speed against accuracy)."""
    rows, ref = [], None
    for f in [1.0] + [f for f in factors if f != 1.0]:
        run = after(case, cmd, work, None if ref is None else {"snes_atol": f * ref["atol"]}, f"atol_x{f:g}")
        s = run["summary"]
        if s is None:                         # no summary: no tolerance to scale or compare
            rows.append({"factor": f, "status": "crashed"})
            if ref is None:
                return rows
            continue
        row = dict(run, factor=f, atol=float(s["tolerances"]["atol"]), outputs=_outputs(s))
        if ref is None:
            ref = row
        same = ref["status"] == row["status"] and all(
            a.shape == b.shape for a, b in zip(ref["outputs"], row["outputs"]))
        row["changes"] = tuple(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300) if same and a.size else float("nan")
                               for a, b in zip(row["outputs"], ref["outputs"]))
        rows.append(row)
    return rows


def option_pairs(case: StrideCase, cmd: list[str], work: str, petsc: dict, repeats: int) -> dict:
    """The stride on this tree in turns without and with ``petsc`` options in its config (a
    solver control's before/after on one build: the machine's drift falls on both sides of each
    pair).  Per side the medians of frames/s of solve and of the linear solve's seconds
    (summary.json ``timings``), the Newton iterations and statuses seen, and the pairs' ratios
    (without / with) of frames/s: median, least and largest."""
    sides: dict[str, list[dict]] = {"without": [], "with": []}
    for _ in range(repeats):
        sides["without"].append(after(case, cmd, work, None, "without_options"))
        sides["with"].append(after(case, cmd, work, petsc, "with_options"))
    out: dict = {}
    for name, runs in sides.items():
        done = [r for r in runs if r["summary"] is not None]
        out[name] = {"per_solve": float(np.median([r["per_solve"] for r in done])) if done else float("nan"),
                     "linear_solve": float(np.median([r["summary"]["timings"].get("linear_solve", np.nan)
                                                      for r in done])) if done else float("nan"),
                     "iterations": sorted({r["iterations"] for r in done}),
                     "statuses": sorted({r["status"] for r in runs})}
    ratios = [a["per_solve"] / b["per_solve"] for a, b in zip(sides["without"], sides["with"])
              if a["summary"] is not None and b["summary"] is not None and b["per_solve"] > 0.0]
    out["ratio"] = (float(np.median(ratios)), min(ratios), max(ratios)) if ratios else (float("nan"),) * 3
    return out


def parse_options(text: str) -> dict[str, str]:
    """``"mat_mumps_icntl_6=3,snes_atol=1e-6"`` (or with leading dashes) as a ``petsc:`` mapping;
    a ValueError names a pair without ``=``."""
    out = {}
    for pair in filter(None, (p.strip() for p in text.split(","))):
        key, sep, value = pair.partition("=")
        if not sep or not key.strip("- "):
            raise ValueError(f"{pair!r}: give OPTION=VALUE, e.g. mat_mumps_icntl_6=3")
        out[key.strip().lstrip("-")] = value.strip()
    return out
