#!/usr/bin/env python3
"""Strong scaling and linear solvers on the 37-fascicle bundle (issue 4).

Runs ``configs/bundle_hex37.yaml`` (5 994 DOFs, 216 sliding interfaces, METIS partition) with
``ancf-solve`` under mpirun and prints, per run, the wall time of each phase (element assembly,
contact projection + assembly, linear solve: PETSc events of the -log_view stages), Newton and
Krylov work, the speed-up and parallel efficiency of 2 ranks over 1, and one table comparing
linear solvers: MUMPS LDLᵀ (the default), MUMPS LU, GMRES + block Jacobi (ILU), GMRES + ASM (overlap 1, ILU), GMRES + GAMG
with the rigid-body near null space.  Every run's probes are compared with the 1-rank LU run.
Each run's full -log_view is kept in <out>/<run>/log_view.txt.

Usage: python scripts/bench_scaling.py [--steps 0.5 1.0] [--out results/bench_scaling] [--quick]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
KRYLOV = ["-ksp_type", "gmres", "-ksp_rtol", "1e-8", "-ksp_max_it", "1000", "-ksp_gmres_restart", "200"]
SOLVERS = {
    "mumps-ldlt": ["-ksp_type", "preonly", "-pc_type", "cholesky", "-pc_factor_mat_solver_type", "mumps"],
    "mumps-lu": ["-ksp_type", "preonly", "-pc_type", "lu", "-pc_factor_mat_solver_type", "mumps"],
    "gmres+bjacobi(ilu)": KRYLOV + ["-pc_type", "bjacobi", "-sub_pc_type", "ilu"],
    "gmres+asm(ilu)": KRYLOV + ["-pc_type", "asm", "-pc_asm_overlap", "1", "-sub_pc_type", "ilu"],
    "gmres+gamg(rbm)": KRYLOV + ["-pc_type", "gamg", "-pc_gamg_threshold", "0.01"],
}


def run(name: str, ranks: int, opts: list[str], base: dict, out: str) -> dict:
    d = os.path.join(out, name)
    os.makedirs(d, exist_ok=True)
    raw = dict(base, output={"dir": d, "vtk": False})
    cfg = os.path.join(d, "config.yaml")
    with open(cfg, "w") as fh:
        yaml.safe_dump(raw, fh, sort_keys=False)
    exe = os.path.join(ROOT, ".venv", "bin", "ancf-solve")
    cmd = ["mpirun", "--oversubscribe", "-n", str(ranks), exe, cfg,
           "-log_view", f":{os.path.join(d, 'log_view.txt')}", "-ksp_converged_reason"] + opts
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, env=ENV, cwd=ROOT)
    wall = time.perf_counter() - t0
    with open(os.path.join(d, "log.txt"), "w") as fh:
        fh.write(p.stdout + p.stderr)
    s = json.load(open(os.path.join(d, "summary.json")))
    t = s.get("timings", {})
    ksp_its = [int(line.split()[-1]) for line in p.stdout.splitlines()
               if "Linear solve converged" in line and line.split()[-1].isdigit()]
    return {"name": name, "ranks": ranks, "status": s["status"], "wall": wall,
            "total": t.get("total", np.nan), "setup": t.get("setup", np.nan),
            "elements": t.get("element_kernels", 0.0) + t.get("element_assembly", 0.0),
            "contact": t.get("contact_projection", 0.0) + t.get("contact_assembly", 0.0),
            "linear": t.get("linear_solve", np.nan), "newton": s.get("newton_iterations", 0),
            "krylov": int(np.sum(ksp_its)) if ksp_its else 0, "summary": s,
            "failed_linear": p.stdout.count("Linear solve did not converge")}


def probe_error(a: dict, ref: dict) -> float:
    if a["status"] != "completed" or ref["status"] != "completed":
        return np.nan
    def table(s):
        return np.array([st["probes"][k]["displacement"] for st in s["steps"] for k in sorted(st["probes"])])
    ta, tr = table(a["summary"]), table(ref["summary"])
    return float(np.abs(ta - tr).max() / np.abs(tr).max()) if ta.shape == tr.shape else np.nan


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=os.path.join(ROOT, "configs", "bundle_hex37.yaml"))
    ap.add_argument("--steps", type=float, nargs="+", default=None)
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "bench_scaling"))
    ap.add_argument("--quick", action="store_true", help="only the direct solvers")
    a = ap.parse_args(argv)
    base = yaml.safe_load(open(a.config))
    if a.steps:
        base["steps"] = a.steps
    base.setdefault("solver", {})["max_cutbacks"] = 1       # a failing solver stops early
    print(f"[bench] {base['name']}: steps {base['steps']}, {os.cpu_count()} cores")
    rows = [run(f"{name}_n{n}", n, SOLVERS[name], base, a.out)
            for name in ("mumps-ldlt", "mumps-lu") for n in (1, 2)]
    if not a.quick:
        for name, opts in list(SOLVERS.items())[2:]:
            rows.append(run(f"{name}_n2", 2, opts, base, a.out))
    ref = rows[0]
    print("\nPhase times [s] (rank 0; elements = kernels + MatSetValues, contact = projection + "
          "assembly, linear = KSPSolve + PCSetUp)")
    hdr = f"{'run':24s} {'status':9s} {'wall':>7s} {'elements':>8s} {'contact':>8s} {'linear':>8s} " \
          f"{'Newton':>6s} {'Krylov':>7s} {'vs first':>9s}"
    print(hdr)
    print("-" * len(hdr))
    for r in rows:
        print(f"{r['name']:24s} {r['status']:9s} {r['wall']:7.1f} {r['elements']:8.2f} {r['contact']:8.2f} "
              f"{r['linear']:8.2f} {r['newton']:6d} {r['krylov']:7d} {probe_error(r, ref):9.1e}")
    for n1, n2 in ((rows[0], rows[1]), (rows[2], rows[3])):
        if n1["status"] != "completed" or n2["status"] != "completed":
            continue
        print(f"\n{n1['name'][:-3]}, 1 -> 2 ranks: speed-up {n1['wall'] / n2['wall']:.2f}x (wall), "
              f"efficiency {n1['wall'] / n2['wall'] / 2:.0%}; per phase: elements "
              f"{n1['elements'] / max(n2['elements'], 1e-9):.2f}x, contact "
              f"{n1['contact'] / max(n2['contact'], 1e-9):.2f}x, linear {n1['linear'] / max(n2['linear'], 1e-9):.2f}x")
    print(f"\npartition at 2 ranks: {rows[1]['summary']['partition']}")
    print(f"exchange at 2 ranks: {rows[1]['summary'].get('exchange')}")
    with open(os.path.join(a.out, "bench_scaling.json"), "w") as fh:
        json.dump([{k: v for k, v in r.items() if k != "summary"} for r in rows], fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
