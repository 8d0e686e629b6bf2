"""``accuracy: {probe, rtol}`` on three scenes: does the chosen model meet the tolerance against a
fine reference, and does choosing it (ladder + run) cost less than solving a fixed fine model?

    .venv/bin/python scripts/accuracy_demo.py [--out docs/accuracy_demo.md] [--quick]

Scenes: uniaxial tension (configs/uniaxial_neohookean.yaml), bending (configs/bending_neohookean.yaml)
and the Achilles tendon (configs/achilles_type3_psi45.yaml, soleus elongation at 400 N), the last two
with 2 axial Gauss points (the front of the speed-accuracy studies).  Every run is in this process on one core; times are wall-clock seconds of the runs
(set-up + load stepping + output), the automatic one including its whole refinement ladder, after
one untimed run that takes the process's start-up (0.3 s, else charged to the first scene).
"""
from __future__ import annotations

import argparse
import copy
import os
import sys
import time

from ancf_verify import paths

ROOT = paths.ROOT
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

SCENES = [  # (label, config, accuracy block, beam overrides, fine element count)
    ("uniaxial tension", "uniaxial_neohookean.yaml",
     {"probe": "tip", "component": "x", "rtol": 1e-6}, {"elements": 8}, 64),
    ("bending (K/mu = 50)", "bending_neohookean.yaml",
     {"probe": "tip", "component": "z", "rtol": 1e-3, "start": 2}, {"axial_points": 2}, 64),
    ("Achilles, psi = 45 deg (2 axial pts)", "achilles_type3_psi45.yaml",
     {"probe": "soleus", "component": "x", "rtol": 5e-3, "start": 4, "max_elements": 32},
     {"axial_points": 2}, 32),
]


def _shipped(name: str) -> dict:
    """A config of configs/ as a dict."""
    import yaml
    with open(os.path.join(ROOT, "configs", name)) as fh:
        return yaml.safe_load(fh)


def _solve(raw: dict, log=lambda *_: None):
    """Solve a config dict (configs/ relative paths) in this process; its result and wall time."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.api import solve
    t0 = time.perf_counter()
    res = solve(parse_config(raw, base_dir=os.path.join(ROOT, "configs")), log=log)
    return res, time.perf_counter() - t0


def _scene(label: str, cfg: str, acc: dict, over: dict, fine_n: int, work: str) -> tuple:
    """One scene: the ``accuracy:`` run and the fixed fine model; the table's row."""
    from ancf_petsc.workflows.refinement import quantity
    raw = _shipped(cfg)
    for b in raw["beams"]:
        b.update(over)
    raw["output"] = {"dir": os.path.join(work, cfg[:-5], "auto"), "vtk": False}
    auto = copy.deepcopy(raw)
    auto["accuracy"] = acc
    res, t_auto = _solve(auto, log=print)
    info = res.summary["accuracy"]
    fine = copy.deepcopy(raw)
    factor = fine_n / fine["beams"][0]["elements"]
    for b in fine["beams"]:
        b["elements"] = int(round(b["elements"] * factor))
    fine["output"]["dir"] = os.path.join(work, cfg[:-5], "fine")
    ref, t_fine = _solve(fine)
    level = info["level"]
    q_auto = quantity(res.summary, acc["probe"], acc["component"], level)
    q_fine = quantity(ref.summary, acc["probe"], acc["component"], level)
    err = abs(q_auto - q_fine) / abs(q_fine)
    print(f"[demo] {label}: chosen {info['chosen_elements']} elements, estimated error "
          f"{info['estimated_error']:.2e}, error vs {fine_n} elements {err:.2e}; "
          f"{t_auto:.1f} s (ladder {info['ladder_seconds']:.1f} s) vs fixed fine {t_fine:.1f} s", flush=True)
    return (label, acc["rtol"], info["chosen_elements"], info["estimated_error"], err,
            ", ".join(str(r["elements"]) for r in info["ladder"]), info["ladder_seconds"],
            t_auto, fine_n, t_fine)


def main() -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "accuracy_demo.md"))
    ap.add_argument("--work", default=os.path.join(ROOT, "results", "accuracy_demo"))
    ap.add_argument("--quick", action="store_true", help="skip the Achilles scene")
    args = ap.parse_args()
    from mpi4py import MPI  # noqa: F401
    import petsc4py
    petsc4py.init([])
    # one untimed run first: the process's one-time start-up (imports, compiled kernels; 0.3 s)
    # would otherwise land in the first scene's automatic run
    _solve({**_shipped("uniaxial_neohookean.yaml"),
            "output": {"dir": os.path.join(args.work, "warm_up"), "vtk": False}})
    rows = [_scene(*scene, args.work) for scene in (SCENES[:2] if args.quick else SCENES)]
    lines = ["| scene | rtol | chosen elements | estimated error | error vs fine | ladder (elements) | "
             "ladder [s] | ladder + run [s] | fine elements | fine run [s] | met | cheaper |",
             "|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---|---|"]
    for (label, rtol, n, est, err, ladder, t_lad, t_auto, fine_n, t_fine) in rows:
        lines.append(f"| {label} | {rtol:g} | {n} | {est:.1e} | {err:.1e} | {ladder} | {t_lad:.1f} | "
                     f"{t_auto:.1f} | {fine_n} | {t_fine:.1f} | {'yes' if err <= rtol else 'NO'} | "
                     f"{'yes' if t_auto < t_fine else 'NO'} |")
    text = "\n".join(lines) + "\n"
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w") as fh:
        fh.write("# `accuracy:` on three scenes (scripts/accuracy_demo.py)\n\n" + text)
    print(text)
    return 0 if all(r[4] <= r[1] for r in rows) else 1
