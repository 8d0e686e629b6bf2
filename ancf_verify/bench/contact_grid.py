"""Unilateral contact wherever a user takes it (issue 24): Newton iterations / cut-backs of the
Table 1 column (10 … 400 N) over tendon × ψ × elements × axial points, the bundles and a second
subject's traced outlines, before and after.

    python scripts/bench_contact_grid.py                       # this tree, 2 runs at a time
    python scripts/bench_contact_grid.py --baseline ce988a8    # also COMMIT's, side by side
    python scripts/bench_contact_grid.py --quick               # 4 and 8 elements only
    python scripts/bench_contact_grid.py --bundles             # + bundle_hex37 (slow)

Every cell is one ``ancf-solve`` process (1 rank, default settings but for the cell's keys) as a
user runs it; a cell prints ``iterations/cut-backs``, or ``fails`` with the load level reached.
``--baseline COMMIT`` checks COMMIT out into a temporary git worktree and runs the same cells
with its code (the configs written here, so both trees solve the same models).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

import yaml

from ancf_verify import paths

ROOT = paths.ROOT
ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
       "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
TABLE1 = [10, 20, 30, 40, 45, 60, 80, 90, 100, 150, 200, 300, 400]
ELEMENTS = (1, 2, 4, 6, 8, 12, 16)


def _load(name: str) -> dict:
    with open(os.path.join(ROOT, "configs", name)) as fh:
        return yaml.safe_load(fh)


def _absolute_files(raw: dict) -> dict:
    """Section files and geometry.sections relative to configs/ made absolute."""
    for b in raw.get("beams", []):
        sec = b.get("section", {})
        if "file" in sec:
            sec["file"] = os.path.join(ROOT, "configs", sec["file"])
    secs = raw.get("geometry", {}).get("sections")
    if isinstance(secs, dict) and "file" in secs:
        secs["file"] = os.path.join(ROOT, "configs", secs["file"])
    return raw


def cells(quick: bool, bundles: bool) -> list[tuple[str, str, dict]]:
    """(row, column, raw config) of every cell."""
    out = []
    els = (4, 8) if quick else ELEMENTS
    for psi in (0, 15, 45):
        for axial in (2, 3):
            for n in els:
                raw = _absolute_files(_load(f"achilles_type3_psi{psi}.yaml"))
                raw["contact"]["mode"] = "unilateral"
                for b in raw["beams"]:
                    b["elements"], b["axial_points"] = n, axial
                out.append((f"paper Type III, ψ = {psi}°, {axial} axial points", f"{n} el", raw))
    for n in ((4, 8) if quick else (2, 4, 8, 16)):
        raw = _absolute_files(_load("geometry_mask_demo.yaml"))
        raw["geometry"]["twist_deg"] = 30
        raw["contact"]["mode"] = "unilateral"
        raw["steps"] = TABLE1
        raw.pop("solver", None)
        for b in raw["beams"]:
            b["elements"] = n
        out.append(("a second subject's traced outlines, ψ = 30°, 2 axial points", f"{n} el", raw))
    for name in ("bundle_hex7.yaml", "bundle_circle7.yaml") + (("bundle_hex37.yaml",) if bundles else ()):
        raw = _load(name)
        raw["contact"]["mode"] = "unilateral"
        out.append((f"{name[:-5]}, unilateral", "bundle", raw))
    return out


def run_cell(root: str, raw: dict, work: str, key: str) -> dict:
    cfg = os.path.join(work, f"{key}.yaml")
    out = os.path.join(work, key)
    raw = dict(raw, output={"dir": out, "vtk": False})
    with open(cfg, "w") as fh:
        yaml.safe_dump(raw, fh)
    p = subprocess.run([sys.executable, "-m", "apps.ancf_solve", cfg, "--quiet"], cwd=root,
                       capture_output=True, text=True, env=dict(os.environ, **ENV, PYTHONPATH=root))
    try:
        with open(os.path.join(out, "summary.json")) as fh:
            s = json.load(fh)
    except (OSError, ValueError):
        return {"text": f"crash ({p.returncode})", "ok": False}
    steps = s.get("steps", [])
    its = s.get("newton_iterations")
    cuts = sum(st.get("cutbacks", 0) for st in steps)
    if s.get("status") == "completed":
        return {"text": f"{its}/{cuts}", "ok": True, "its": its, "cuts": cuts}
    reached = steps[-1]["load_factor"] if steps else 0.0
    return {"text": f"fails ({reached:g})", "ok": False, "its": its, "cuts": cuts}


def grid(root: str, todo: list, jobs: int, label: str) -> dict:
    work = tempfile.mkdtemp(prefix="ancf-grid-")
    keys = [f"c{i:03d}" for i in range(len(todo))]
    with ThreadPoolExecutor(jobs) as ex:
        res = list(ex.map(lambda a: run_cell(root, a[0][2], work, a[1]), zip(todo, keys)))
    out = {}
    for (row, col, _), r in zip(todo, res):
        out[(row, col)] = r
        print(f"[{label}] {row} | {col}: {r['text']}", flush=True)
    return out


def table(results: dict, title: str) -> str:
    rows = list(dict.fromkeys(r for r, _ in results))
    cols = list(dict.fromkeys(c for _, c in results))
    lines = [f"### {title}", "", "| cell | " + " | ".join(cols) + " |", "|---|" + "---|" * len(cols)]
    for row in rows:
        lines.append(f"| {row} | " + " | ".join(results[(row, c)]["text"] if (row, c) in results else ""
                                                for c in cols) + " |")
    ok = [r for r in results.values() if r["ok"]]
    its = sorted(r["its"] for r in ok)
    lines += ["", f"{len(ok)} of {len(results)} cells converge; Newton iterations: median "
                  f"{its[len(its) // 2] if its else '-'}, largest {its[-1] if its else '-'}; "
                  f"{sum(1 for r in ok if r['its'] > 100)} cells above 100; cut-backs in "
                  f"{sum(1 for r in ok if r['cuts'])} cells"]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--baseline", metavar="COMMIT")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--bundles", action="store_true", help="also bundle_hex37 (slow)")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    todo = cells(args.quick, args.bundles)
    now = grid(ROOT, todo, args.jobs, "this tree")
    print()
    print(table(now, "This tree"))
    if args.baseline:
        base_root = tempfile.mkdtemp(prefix="ancf-baseline-")
        subprocess.run(["git", "worktree", "add", "--detach", base_root, args.baseline], cwd=ROOT,
                       check=True, capture_output=True)
        try:
            subprocess.run([sys.executable, "-m", "compileall", "-q", "ancf_petsc", "apps"],
                           cwd=base_root, check=True, capture_output=True)
            base = grid(base_root, todo, args.jobs, args.baseline)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", base_root], cwd=ROOT,
                           capture_output=True)
        print()
        print(table(base, f"Baseline {args.baseline}"))
    return 0
