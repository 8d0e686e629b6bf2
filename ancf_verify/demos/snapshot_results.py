"""Behaviour snapshot for refactors: the paper's columns, Table 2 models and bundles, to full precision.

    python scripts/snapshot_results.py --write before.json          # record
    python scripts/snapshot_results.py --compare before.json        # re-run and compare (rel 1e-12)

Every case is one ``ancf-solve`` process on 1 rank (2 with ``--ranks 2``), exactly as a user runs
it; the snapshot keeps every converged level's probe displacements, Newton iterations and
negative-eigenvalue counts, and the column wall times (best of ``--repeat``).  ``--compare``
prints the largest relative difference per case and the wall-time ratios, and exits 1 when any
value differs by more than ``--rtol`` or any count differs.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import yaml

from ancf_verify import paths

ROOT = paths.ROOT
ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
       "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "PYTHONPATH": ROOT}


def cases() -> dict[str, tuple[str, dict]]:
    """name -> (config, changes given as ``dotted.key: value``)."""
    out = {}
    for psi in (0, 15, 45):
        cfg = f"configs/achilles_type3_psi{psi}.yaml"
        out[f"table1_psi{psi}"] = (cfg, {})
        out[f"table1_psi{psi}_unilateral"] = (cfg, {"contact.mode": "unilateral"})
        for n in (1, 2):
            out[f"table2_psi{psi}_{n}el"] = (cfg, {f"beams[{b}].elements": n for b in range(3)})
    out["bundle_hex7"] = ("configs/bundle_hex7.yaml", {})
    out["bundle_circle7"] = ("configs/bundle_circle7.yaml", {})
    return out


def _set(raw: dict, dotted: str, value) -> None:
    node = raw
    parts = dotted.replace("]", "").replace("[", ".").split(".")
    for p in parts[:-1]:
        node = node[int(p)] if p.isdigit() else node[p]
    node[int(parts[-1]) if parts[-1].isdigit() else parts[-1]] = value


def write_config(cfg: str, changes: dict, out: str) -> str:
    with open(os.path.join(ROOT, cfg)) as fh:
        raw = yaml.safe_load(fh)
    for k, v in changes.items():
        _set(raw, k, v)
    here = os.path.dirname(os.path.join(ROOT, cfg))
    for b in raw.get("beams", []):
        sec = b.get("section", {})
        if isinstance(sec, dict) and "file" in sec:
            sec["file"] = os.path.join(here, sec["file"])
    path = os.path.join(out, os.path.basename(cfg) + f".{abs(hash(json.dumps(changes))) % 10**8}.yaml")
    with open(path, "w") as fh:
        yaml.safe_dump(raw, fh)
    return path


def run_case(cfg: str, changes: dict, out: str, ranks: int, repeat: int) -> dict:
    path = write_config(cfg, changes, out)
    run_dir = path + ".out"
    exe = [sys.executable, "-m", "apps.ancf_solve", path, "--output-dir", run_dir, "--quiet"]
    if ranks > 1:
        exe = ["mpirun", "-n", str(ranks), "--oversubscribe"] + exe
    best = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        p = subprocess.run(exe, cwd=ROOT, capture_output=True, text=True, env=dict(os.environ, **ENV))
        wall = time.perf_counter() - t0
        best = wall if best is None else min(best, wall)
    s = paths.run_summary(run_dir, p, "snapshot_results")
    levels = [{"load_factor": st["load_factor"], "iterations": st["iterations"],
               "negative_eigenvalues": st.get("negative_eigenvalues"),
               "probes": {k: v["displacement"] for k, v in st["probes"].items()}} for st in s["steps"]]
    return {"status": s["status"], "returncode": p.returncode, "newton_iterations": s.get("newton_iterations"),
            "levels": levels, "wall": best, "in_process": s["timings"]["total"]}


def _floats(x):
    if isinstance(x, dict):
        for k in sorted(x):
            yield from _floats(x[k])
    elif isinstance(x, list):
        for v in x:
            yield from _floats(v)
    elif isinstance(x, float):
        yield x


def compare(before: dict, after: dict, rtol: float) -> bool:
    ok = True
    print(f"{'case':28s} {'max rel diff':>13s} {'its':>9s} {'wall before':>11s} {'after':>7s} {'ratio':>6s}")
    for name, b in before.items():
        a = after.get(name)
        if a is None:
            print(f"{name:28s} missing")
            ok = False
            continue
        same_shape = (len(a["levels"]) == len(b["levels"]) and a["status"] == b["status"]
                      and [(x["iterations"], x["negative_eigenvalues"]) for x in a["levels"]]
                      == [(x["iterations"], x["negative_eigenvalues"]) for x in b["levels"]])
        fb, fa = list(_floats(b["levels"])), list(_floats(a["levels"]))
        scale = max((abs(v) for v in fb), default=1.0) or 1.0
        diff = max((abs(x - y) / scale for x, y in zip(fb, fa)), default=0.0) if same_shape else float("inf")
        ok &= same_shape and diff <= rtol
        print(f"{name:28s} {diff:13.2e} {a['newton_iterations']:>4}/{b['newton_iterations']:<4} "
              f"{b['wall']:11.2f} {a['wall']:7.2f} {a['wall'] / b['wall']:6.2f}")
    return ok


def main() -> int:
    ap = argparse.ArgumentParser(prog="snapshot_results.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", help="record the snapshot to this JSON file")
    ap.add_argument("--compare", help="re-run and compare with this JSON file")
    ap.add_argument("--only", nargs="*", help="case names (default: all)")
    ap.add_argument("--ranks", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=1, help="runs per case; the best wall time is kept")
    ap.add_argument("--rtol", type=float, default=1e-12, help="relative to the case's largest value")
    args = ap.parse_args()
    unknown = [k for k in args.only or () if k not in cases()]
    if unknown:
        ap.error(f"--only: no case {unknown[0]!r}; cases: {', '.join(cases())}")
    chosen = {k: v for k, v in cases().items() if not args.only or k in args.only}
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, (cfg, changes) in chosen.items():
            results[name] = run_case(cfg, changes, tmp, args.ranks, args.repeat)
            r = results[name]
            print(f"{name:28s} {r['status']:10s} {r['newton_iterations']:>4} its  {r['wall']:.2f} s", flush=True)
    if args.write:
        with open(args.write, "w") as fh:
            json.dump(results, fh, indent=1)
    if args.compare:
        with open(args.compare) as fh:
            before = json.load(fh)
        for name in (k for k in results if k not in before):
            print(f"{name:28s} not in {args.compare}: nothing to compare")
        same = compare({k: v for k, v in before.items() if k in results}, results, args.rtol)
        return 0 if same and set(results) <= set(before) else 1
    return 0
