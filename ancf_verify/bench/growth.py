"""How the cost of a run grows with the scene (issue 16, target 1): one rank, twisted hexagonal
bundles of 7, 19, 37, 61 and 91 fascicles with 16 elements each (configs/bundle_hex37.yaml with
``bundle.count`` changed), solved with the direct solver (MUMPS LDLᵀ of the whole saddle-point
Jacobian) and with the fascicle-parallel solver (``solver.linear: fieldsplit``).

Per run: the unknowns (beam DOFs + contact multipliers), Newton iterations, wall time per Newton
iteration (load stepping without set-up and output, divided by the Newton iterations), the
linear solver's share of it (KSPSolve + PCSetUp), the peak resident memory of the process
(``os.wait4``) and the probes' largest difference to the direct solver's answer.  Fitted
exponents p of time ∝ unknowns^p and memory ∝ unknowns^p (least squares on the logarithms) follow
the table, and a log–log chart goes to ``--chart``.  Results: <out>/bench_growth.json.

Usage: python scripts/bench_growth.py [--counts 7 19 37 61 91] [--solvers direct fieldsplit]
                                      [--out results/bench_growth] [--chart docs/figures/growth.png]
                                      [--repeat 1] [--from-json FILE]
"""
from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import time

import numpy as np
import yaml

from ancf_verify import paths

ROOT = paths.ROOT
from ancf_petsc.linalg.log_view import read_log_view  # noqa: E402

#: -log_view events kept per run (seconds over the run, slowest rank): the projection
#: (scripts/project_scaling.py) splits a Newton iteration into per-fascicle work and the
#: multiplier Schur complement's factorisation and solves (linalg/substructure.py's events;
#: MatCholFctrNum and MatSolve are the direct solver's)
EVENTS = ("ANCF element kernels", "ANCF contact", "ANCF fascicle factor", "ANCF Schur assembly",
          "ANCF fascicle apply", "ANCF Schur factor", "ANCF Schur solve", "MatCholFctrNum",
          "MatSolve", "MatMult", "KSPSolve", "PCSetUp",
          "SNESFunctionEval", "SNESJacobianEval")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
LABELS = {"direct": "MUMPS LDLᵀ of the whole Jacobian (direct)",
          "fieldsplit": "fascicle Schur + FGMRES (fieldsplit)"}


def run_one(count: int, solver: str, out: str, repeat: int, elements: int = 16) -> dict:
    """ancf-solve on the bundle of ``count`` fascicles of ``elements`` elements with ``solver``;
    the fastest of ``repeat`` runs (its peak memory, figures and probes)."""
    base = yaml.safe_load(open(os.path.join(ROOT, "configs", "bundle_hex37.yaml")))
    base["name"] = f"bundle_hex{count}"
    base["bundle"]["count"] = count
    base["bundle"]["elements"] = elements
    base["solver"] = {"linear": solver}
    d = os.path.join(out, f"hex{count}_e{elements}_{solver}")
    os.makedirs(d, exist_ok=True)
    base["output"] = {"dir": d, "vtk": False}
    cfg = os.path.join(d, "config.yaml")
    with open(cfg, "w") as fh:
        yaml.safe_dump(base, fh, sort_keys=False)
    exe = os.path.join(ROOT, ".venv", "bin", "ancf-solve")
    cmd = [exe, cfg, "-log_view", f":{os.path.join(d, 'log_view.txt')}"]
    best = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        with open(os.path.join(d, "log.txt"), "w") as log:
            p = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=ENV, cwd=ROOT)
            _, status, usage = os.wait4(p.pid, 0)
            p.returncode = os.waitstatus_to_exitcode(status)
        wall = time.perf_counter() - t0
        text = open(os.path.join(d, "log.txt")).read()
        s = json.load(open(os.path.join(d, "summary.json")))
        t = s.get("timings", {})
        its = max(int(s.get("newton_iterations", 0)), 1)
        solve = t.get("total", np.nan) - t.get("setup", 0.0) - t.get("output", 0.0)
        m = re.search(r"Lagrange multipliers .*?, (\d+) in all", text)
        row = {"count": count, "elements": elements, "solver": solver, "status": s["status"], "dofs": s.get("dofs"),
               "multipliers": int(m.group(1)) if m else 0, "newton": its, "wall": wall,
               "total": t.get("total", np.nan), "per_iteration": solve / its,
               "linear_per_iteration": t.get("linear_solve", np.nan) / its,
               "memory_mb": usage.ru_maxrss / 1024.0, "linear": s.get("linear_solver", {}),
               "probes": [st["probes"][k]["displacement"] for st in s["steps"] for k in sorted(st["probes"])],
               "negative_eigenvalues": [st.get("negative_eigenvalues") for st in s["steps"]],
               "events": {k: v["time"] for k, v in read_log_view(os.path.join(d, "log_view.txt"))["events"].items()
                          if k in EVENTS}}
        row["unknowns"] = row["dofs"] + row["multipliers"]
        print(f"[growth] {count:3d} fascicles x {elements:2d} elements {solver:10s}: {row['status']}, {row['newton']} Newton, "
              f"{row['per_iteration']:.2f} s/iteration, {row['memory_mb']:.0f} MB, wall {wall:.1f} s",
              flush=True)
        if best is None or (row["status"] == "completed" and row["per_iteration"] < best["per_iteration"]):
            best = row
    return best


def fit(rows: list, key: str) -> float:
    """Exponent p of ``key`` ∝ unknowns^p over the completed rows (nan with fewer than two)."""
    ok = [r for r in rows if r["status"] == "completed" and r[key] > 0]
    if len(ok) < 2:
        return float("nan")
    return float(np.polyfit(np.log([r["unknowns"] for r in ok]), np.log([r[key] for r in ok]), 1)[0])


def table(rows: list) -> str:
    """Markdown table of the rows (and the probes' difference to the direct solver)."""
    ref = {(r["count"], r.get("elements", 16)): r for r in rows
           if r["solver"] == "direct" and r["status"] == "completed"}
    lines = ["| fascicles | elements | unknowns | multipliers | solver | Newton | s / Newton it. | "
             "linear s / it. | peak memory [MB] | vs direct |",
             "|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        d = ref.get((r["count"], r.get("elements", 16)))
        diff = ""
        if d is not None and r is not d and r["status"] == "completed":
            a, b = np.array(r["probes"]), np.array(d["probes"])
            diff = f"{np.abs(a - b).max() / np.abs(b).max():.1e}"
        status = "" if r["status"] == "completed" else f" ({r['status']})"
        lines.append(f"| {r['count']} | {r.get('elements', 16)} | {r['unknowns']:,} | {r['multipliers']:,} | "
                     f"{r['solver']}{status} | {r['newton']} | "
                     f"{r['per_iteration']:.2f} | {r['linear_per_iteration']:.2f} | "
                     f"{r['memory_mb']:.0f} | {diff} |")
    return "\n".join(lines)


def chart(rows: list, path: str) -> None:
    """Time per Newton iteration and peak memory against unknowns, log–log, one line per solver
    with its fitted exponent in the legend."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from ancf_petsc.viz.charts import readable_log_axis
    fig = Figure(figsize=(10.0, 4.6))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2)
    for ax, key, ylabel in ((axes[0], "per_iteration", "wall time per Newton iteration [s]"),
                            (axes[1], "memory_mb", "peak memory of the process [MB]")):
        for solver, marker in (("direct", "o"), ("fieldsplit", "s")):
            ok = [r for r in rows if r["solver"] == solver and r["status"] == "completed"]
            if not ok:
                continue
            x = np.array([r["unknowns"] for r in ok], dtype=float)
            y = np.array([r[key] for r in ok], dtype=float)
            ax.loglog(x, y, marker=marker, label=f"{LABELS[solver]}: ∝ N^{fit(ok, key):.2f}")
            for r, xi, yi in zip(ok, x, y):
                ax.annotate(str(r["count"]), (xi, yi), textcoords="offset points", xytext=(4, -10),
                            fontsize=8)
        ax.set_xlabel("unknowns N (beam DOFs + contact multipliers)")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
        readable_log_axis(ax.xaxis)
        readable_log_axis(ax.yaxis)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), fontsize=8, frameon=False)
    fig.suptitle("Twisted hexagonal bundles, 16 elements per fascicle, one rank "
                 "(labels: fascicles)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--counts", type=int, nargs="+", default=[7, 19, 37, 61, 91])
    ap.add_argument("--elements", type=int, nargs="+", default=[16], help="elements per fascicle")
    ap.add_argument("--solvers", nargs="+", default=["direct", "fieldsplit"], choices=list(LABELS))
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "bench_growth"))
    ap.add_argument("--chart", default=os.path.join(ROOT, "docs", "figures", "growth.png"))
    ap.add_argument("--repeat", type=int, default=1, help="runs per configuration (fastest kept)")
    ap.add_argument("--from-json", help="redraw the table and chart from a bench_growth.json")
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    if a.from_json:
        rows = json.load(open(a.from_json))
    else:
        print(f"[growth] {os.cpu_count()} cores; load average {os.getloadavg()[0]:.2f}", flush=True)
        rows = [run_one(n, s, a.out, a.repeat, e) for e in a.elements for n in a.counts for s in a.solvers]
        with open(os.path.join(a.out, "bench_growth.json"), "w") as fh:
            json.dump(rows, fh, indent=1)
    print()
    print(table(rows))
    print()
    for s in (a.solvers if len(a.elements) == 1 else []):
        print(f"{s}: time per Newton iteration ∝ N^{fit([r for r in rows if r['solver'] == s], 'per_iteration'):.2f}, "
              f"linear solver ∝ N^{fit([r for r in rows if r['solver'] == s], 'linear_per_iteration'):.2f}, "
              f"memory ∝ N^{fit([r for r in rows if r['solver'] == s], 'memory_mb'):.2f}")
    if a.chart and len(a.elements) == 1:
        os.makedirs(os.path.dirname(a.chart), exist_ok=True)
        chart(rows, a.chart)
        print(f"chart: {a.chart}")
    return 0
