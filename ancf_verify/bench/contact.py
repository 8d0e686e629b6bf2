"""Contact benchmark (issue 13): Newton iterations, cut-backs and wall time of the Table 1 columns.

    python scripts/bench_contact.py                 # both laws, best of 3 wall times per column
    python scripts/bench_contact.py --baseline daf134a   # also the same runs at an older commit

Each column is one `ancf-solve` process (start-up included, 1 rank), as a user runs it; the wall
time is the best of ``--repeat`` runs.  For every run it prints the Newton iterations, cut-backs,
the largest first-iteration residual growth of an increment (|F_1| / |F_0|: the penalty spikes of
the former formulation), the in-process time and the wall time, then the ratios against the
baseline.  ``--baseline COMMIT`` checks COMMIT out into a temporary git worktree and runs its own
configs the same way (the penalty formulation before this work is daf134a; unilateral contact
there needs the config key it had then, so only the sliding columns are compared).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

from ancf_verify import paths

ROOT = paths.ROOT
ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
       "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
TWISTS = (0, 15, 45)


def run_column(root: str, psi: int, mode: str, repeat: int, out: str) -> dict:
    """Best-of-``repeat`` wall time of one column run by ``root``'s ancf-solve."""
    cfg = os.path.join(root, "configs", f"achilles_type3_psi{psi}.yaml")
    if mode != "sliding":
        import yaml
        with open(cfg) as fh:
            raw = yaml.safe_load(fh)
        raw["contact"]["mode"] = mode
        for b in raw["beams"]:
            b["section"]["file"] = os.path.join(root, "configs", b["section"]["file"])
        cfg = os.path.join(out, f"psi{psi}_{mode}.yaml")
        with open(cfg, "w") as fh:
            yaml.safe_dump(raw, fh)
    exe = [sys.executable, "-m", "apps.ancf_solve"]
    best = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        p = subprocess.run(exe + [cfg, "--output-dir", os.path.join(out, f"psi{psi}_{mode}"), "--quiet"],
                           cwd=root, capture_output=True, text=True, env=dict(os.environ, **ENV, PYTHONPATH=root))
        wall = time.perf_counter() - t0
        best = wall if best is None else min(best, wall)
    if p.returncode not in (0,):
        sys.exit(f"bench_contact: {root} ψ={psi} {mode} exited {p.returncode}: "
                 f"{(p.stderr or p.stdout).strip().splitlines()[-1:]}")
    with open(os.path.join(out, f"psi{psi}_{mode}", "summary.json")) as fh:
        s = json.load(fh)
    jumps = [h[1] / h[0] for st in s["steps"] for h in st.get("newton_history", []) if len(h) > 1 and h[0] > 0]
    return {"status": s["status"], "iterations": s.get("newton_iterations"),
            "cutbacks": sum(st["cutbacks"] for st in s["steps"]), "levels": len(s["steps"]),
            "first_jump": max(jumps) if jumps else float("nan"),
            "in_process": s["timings"]["total"], "wall": best, "returncode": p.returncode}


def table(rows: dict, title: str) -> str:
    lines = [f"### {title}", "",
             "| column | status | Newton its | cut-backs | max |F1|/|F0| | in-process [s] | wall [s] |",
             "|---|---|---:|---:|---:|---:|---:|"]
    for key, r in rows.items():
        lines.append(f"| {key} | {r['status']} | {r['iterations']} | {r['cutbacks']} | {r['first_jump']:.2g} | "
                     f"{r['in_process']:.2f} | {r['wall']:.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--baseline", metavar="COMMIT", help="also run COMMIT's sliding columns")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as out:
        now = {f"ψ={p}° {m}": run_column(ROOT, p, m, args.repeat, out)
               for m in ("sliding", "unilateral") for p in TWISTS}
        print(table(now, "This tree"))
        if args.baseline:
            base_root = os.path.join(out, "baseline")
            subprocess.run(["git", "worktree", "add", "--detach", base_root, args.baseline], cwd=ROOT,
                           check=True, capture_output=True)
            # byte-compiled like this tree (scripts/setup.sh), so that only the code differs
            subprocess.run([sys.executable, "-m", "compileall", "-q", "ancf_petsc", "apps"], cwd=base_root,
                           check=True, capture_output=True)
            try:
                base = {f"ψ={p}° sliding": run_column(base_root, p, "sliding", args.repeat, out) for p in TWISTS}
            finally:
                subprocess.run(["git", "worktree", "remove", "--force", base_root], cwd=ROOT, capture_output=True)
            print()
            print(table(base, f"Baseline {args.baseline}"))
            print()
            print("| column | Newton its (baseline → now) | wall [s] (baseline → now) | speed-up |")
            print("|---|---|---|---:|")
            for key, b in base.items():
                n = now[key]
                print(f"| {key} | {b['iterations']} → {n['iterations']} | {b['wall']:.2f} → {n['wall']:.2f} | "
                      f"{b['wall'] / n['wall']:.2f}x |")
    return 0
