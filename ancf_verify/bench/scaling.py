"""Strong scaling and linear solvers on the 37-fascicle bundle (issues 4 and 16).

Runs ``configs/bundle_hex37.yaml`` (37 twisted hexagonal fascicles, 16 elements each, 21 978 DOFs,
90 sliding interfaces, METIS partition, two load levels) with ``ancf-solve`` under mpirun and
prints, per run, the time of each phase (element kernels + insertion, contact projection +
assembly, linear solve = KSPSolve + PCSetUp: PETSc events of the -log_view stages, rank 0), Newton
and Krylov work, and the speed-up and parallel efficiency of 2 ranks over 1, both on the wall
clock of the whole command (mpirun, interpreter start-up and imports included) and on the run
itself (set-up + load stepping + output, as ancf-solve reports it).  Every timed configuration is
run ``--repeat`` times and the fastest is kept.  One table compares linear solvers: the
fascicle-parallel solver (``solver.linear: fieldsplit``, linalg/fieldsplit.py; what ``auto`` picks
here), MUMPS LDLᵀ of the whole Jacobian (``solver.linear: direct``), the same refactored every
third Newton iteration inside GMRES, MUMPS LU, and GMRES with block Jacobi (ILU), ASM (overlap 1,
ILU) and GAMG with the rigid-body near null space.  Every run's probes are compared with the
first run.  Each run's full -log_view is kept in <out>/<run>/log_view.txt.

The machine's own ceiling comes last (``--no-ceiling`` skips it): the first solver's 1-rank
run alone and two copies of it side by side, interleaved.  Two copies share the cores' caches,
memory bandwidth and clock as two ranks do, without any communication or imbalance, so
2 × alone / side by side is the most a 2-rank run can gain on this machine; the 2-rank speed-up
is also printed as a share of it.

``--messages`` instead runs both solvers of ``solver.linear`` at 2, 3 and 4 ranks
(oversubscribed on a small machine: the counts do not depend on it) and tabulates PETSc's MPI
message counts, volumes and reductions from -log_view: in all, per Newton iteration, and for
the events that send them.  MUMPS's own messages (inside the factorisations and solves) are
not in PETSc's log.

Usage: python scripts/bench_scaling.py [--config configs/bundle_hex37.yaml] [--steps 0.5 1.0]
                                       [--out results/bench_scaling] [--quick] [--repeat 2]
                                       [--messages [--ranks 2 3 4]] [--no-ceiling]
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

from ancf_verify import paths
from ancf_petsc.linalg.log_view import read_log_view  # noqa: E402

ROOT = paths.ROOT
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
KRYLOV = ["-ksp_type", "gmres", "-ksp_rtol", "1e-8", "-ksp_max_it", "300", "-ksp_gmres_restart", "300"]
#: name → PETSc options, or a config ``solver.linear`` value (str)
SOLVERS = {
    "fieldsplit": "fieldsplit",
    "mumps-ldlt": "direct",
    "mumps-ldlt-lagged": ["-ksp_type", "gmres", "-ksp_rtol", "1e-9", "-pc_type", "cholesky",
                          "-pc_factor_mat_solver_type", "mumps", "-snes_lag_preconditioner", "3"],
    "mumps-lu": ["-ksp_type", "preonly", "-pc_type", "lu", "-pc_factor_mat_solver_type", "mumps"],
    "gmres+bjacobi(ilu)": KRYLOV + ["-pc_type", "bjacobi", "-sub_pc_type", "ilu"],
    "gmres+asm(ilu)": KRYLOV + ["-pc_type", "asm", "-pc_asm_overlap", "1", "-sub_pc_type", "ilu"],
    "gmres+gamg(rbm)": KRYLOV + ["-pc_type", "gamg", "-pc_gamg_threshold", "0.01"],
}
#: the solvers timed at 1 and 2 ranks (the others only at 2, where they fail)
SCALED = ("fieldsplit", "mumps-ldlt", "mumps-ldlt-lagged", "mumps-lu")


def command(name: str, ranks: int, opts, base: dict, out: str) -> tuple[list, str]:
    """(the mpirun command line, its output directory) of one run: ``opts`` is a list of PETSc
    options or a ``solver.linear`` value."""
    d = os.path.join(out, name)
    os.makedirs(d, exist_ok=True)
    raw = dict(base, output={"dir": d, "vtk": False})
    if isinstance(opts, str):
        raw["solver"] = dict(base.get("solver", {}), linear=opts)
        opts = []
    cfg = os.path.join(d, "config.yaml")
    with open(cfg, "w") as fh:
        yaml.safe_dump(raw, fh, sort_keys=False)
    exe = os.path.join(ROOT, ".venv", "bin", "ancf-solve")
    return (["mpirun", "--oversubscribe", "-n", str(ranks), exe, cfg,
             "-log_view", f":{os.path.join(d, 'log_view.txt')}", "-ksp_converged_reason"] + opts, d)


def run(name: str, ranks: int, opts, base: dict, out: str, repeat: int = 1) -> dict:
    """Solve ``base`` with ``ranks`` ranks ``repeat`` times; the fastest run's figures."""
    cmd, d = command(name, ranks, opts, base, out)
    best = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True, env=ENV, cwd=ROOT)
        wall = time.perf_counter() - t0
        with open(os.path.join(d, "log.txt"), "w") as fh:
            fh.write(p.stdout + p.stderr)
        s = json.load(open(os.path.join(d, "summary.json")))
        t = s.get("timings", {})
        ksp_its = [int(line.split()[-1]) for line in p.stdout.splitlines()
                   if "Linear solve converged" in line and line.split()[-1].isdigit()]
        row = {"name": name, "ranks": ranks, "status": s["status"], "wall": wall,
               "total": t.get("total", np.nan), "setup": t.get("setup", np.nan),
               "output": t.get("output", np.nan),
               "elements": t.get("element_kernels", 0.0) + t.get("element_assembly", 0.0),
               "contact": t.get("contact_projection", 0.0) + t.get("contact_assembly", 0.0),
               "linear": t.get("linear_solve", np.nan), "newton": s.get("newton_iterations", 0),
               "krylov": int(np.sum(ksp_its)) if ksp_its else 0, "summary": s,
               "failed_linear": p.stdout.count("Linear solve did not converge"),
               "log_view": os.path.join(d, "log_view.txt")}
        print(f"[bench] {name}: {row['status']}, wall {wall:.2f} s, run {row['total']:.2f} s", flush=True)
        if best is None or (row["status"] == "completed" and row["wall"] < best["wall"]):
            best = row
        if row["status"] != "completed":
            break
    return best


def machine_ceiling(opts, base: dict, out: str, repeat: int) -> dict:
    """The most any 2-rank run of ``base`` could gain on this machine: the 1-rank run alone and
    two copies of it side by side (no communication, perfect balance; the two share the cores'
    caches, memory bandwidth and clock as two ranks do), ``repeat`` times interleaved, fastest
    kept.  Ceiling = 2 × alone / side by side."""
    def timed(names):
        cmds = [command(n, 1, opts, base, out) for n in names]
        for c, _ in cmds:                   # mpirun binds each job's rank to core 0 otherwise
            c[1:1] = ["--bind-to", "none"]
        t0 = time.perf_counter()
        procs = [subprocess.Popen(c, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENV, cwd=ROOT)
                 for c, _ in cmds]
        walls = []
        for p in procs:
            p.wait()
            walls.append(time.perf_counter() - t0)
        runs = [json.load(open(os.path.join(d, "summary.json")))["timings"]["total"] for _, d in cmds]
        return max(walls), max(runs)
    alone, pair = [], []
    for _ in range(repeat):
        alone.append(timed(["ceiling_alone"]))
        pair.append(timed(["ceiling_a", "ceiling_b"]))
        print(f"[bench] ceiling: alone wall {alone[-1][0]:.2f} s run {alone[-1][1]:.2f} s; side by side "
              f"wall {pair[-1][0]:.2f} s run {pair[-1][1]:.2f} s", flush=True)
    a_wall, a_run = min(w for w, _ in alone), min(r for _, r in alone)
    p_wall, p_run = min(w for w, _ in pair), min(r for _, r in pair)
    return {"alone_wall": a_wall, "alone_run": a_run, "pair_wall": p_wall, "pair_run": p_run,
            "wall": 2 * a_wall / p_wall, "run": 2 * a_run / p_run}


def probe_error(a: dict, ref: dict) -> float:
    if a["status"] != "completed" or ref["status"] != "completed":
        return np.nan

    def table(s):
        return np.array([st["probes"][k]["displacement"] for st in s["steps"] for k in sorted(st["probes"])])
    ta, tr = table(a["summary"]), table(ref["summary"])
    return float(np.abs(ta - tr).max() / np.abs(tr).max()) if ta.shape == tr.shape else np.nan


#: the -log_view events that send PETSc's messages (the others nest them): the Jacobian's and
#: S's off-rank entries (MatAssemblyBegin), vector scatters (the contact exchange, the
#: multiplier gathers, the matrix-vector products), fascicle blocks with off-rank multiplier
#: rows (MatCreateSubMats) and PetscSF set-ups
SENDERS = ("MatAssemblyBegin", "VecScatterBegin", "MatCreateSubMats", "SFSetUp")


def messages_table(base: dict, out: str, ranks: list[int]) -> list[dict]:
    """Both solvers of ``solver.linear`` at ``ranks``: PETSc's MPI traffic (printed, returned)."""
    rows = []
    for name in ("fieldsplit", "mumps-ldlt"):
        for n in ranks:
            r = run(f"{name}_messages_n{n}", n, SOLVERS[name], base, out)
            if r["status"] != "completed":
                continue
            m = read_log_view(r["log_view"])
            rows.append({"name": name, "ranks": n, "newton": r["newton"], **m})
    print("\nPETSc MPI traffic (all ranks; MUMPS's own messages not included)")
    hdr = (f"{'solver':12s} {'ranks':>5s} {'Newton':>6s} {'messages':>9s} {'MB':>8s} {'reductions':>10s} "
           f"{'msg/it':>7s} {'MB/it':>7s} {'red/it':>7s}  largest senders (MB)")
    print(hdr)
    print("-" * len(hdr))
    for r in rows:
        t, it = r["total"], max(r["newton"], 1)
        top = sorted(((k, v) for k, v in r["events"].items() if k in SENDERS),
                     key=lambda kv: -kv[1]["bytes"])
        tops = ", ".join(f"{k} {v['bytes'] / 1e6:.1f}" for k, v in top if v["bytes"] > 0)
        print(f"{r['name']:12s} {r['ranks']:5d} {r['newton']:6d} {t['messages']:9.0f} {t['bytes'] / 1e6:8.1f} "
              f"{t['reductions']:10.0f} {t['messages'] / it:7.0f} {t['bytes'] / 1e6 / it:7.2f} "
              f"{t['reductions'] / it:7.0f}  {tops}")
    with open(os.path.join(out, "bench_messages.json"), "w") as fh:
        json.dump(rows, fh, indent=1)
    return rows


def print_runs(rows: list[dict], scaled) -> None:
    """The phase-time table of the runs and the 1 → 2 rank speed-up of each scaled solver."""
    ref = rows[0]
    print(f"\nDOFs {ref['summary'].get('dofs')}.  Phase times [s] (rank 0; elements = kernels + "
          "insertion, contact = projection + assembly, linear = KSPSolve + PCSetUp; wall = the "
          "whole mpirun command, run = set-up + load stepping + output)")
    hdr = (f"{'run':24s} {'status':9s} {'wall':>6s} {'run':>6s} {'setup':>6s} {'elements':>8s} "
           f"{'contact':>8s} {'linear':>7s} {'Newton':>6s} {'Krylov':>6s} {'vs first':>9s}")
    print(hdr)
    print("-" * len(hdr))
    for r in rows:
        print(f"{r['name']:24s} {r['status']:9s} {r['wall']:6.1f} {r['total']:6.2f} {r['setup']:6.2f} "
              f"{r['elements']:8.2f} {r['contact']:8.2f} {r['linear']:7.2f} {r['newton']:6d} "
              f"{r['krylov']:6d} {probe_error(r, ref):9.1e}")
    for name in scaled:
        n1, n2 = (next(r for r in rows if r["name"] == f"{name}_n{n}") for n in (1, 2))
        if n1["status"] != "completed" or n2["status"] != "completed":
            continue
        s_wall, s_run = n1["wall"] / n2["wall"], n1["total"] / n2["total"]
        print(f"\n{name}, 1 -> 2 ranks: speed-up {s_wall:.2f}x wall ({s_wall / 2:.0%} efficiency), "
              f"{s_run:.2f}x run ({s_run / 2:.0%}); per phase: elements "
              f"{n1['elements'] / max(n2['elements'], 1e-9):.2f}x, contact "
              f"{n1['contact'] / max(n2['contact'], 1e-9):.2f}x, linear {n1['linear'] / max(n2['linear'], 1e-9):.2f}x")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--config", default=os.path.join(ROOT, "configs", "bundle_hex37.yaml"))
    ap.add_argument("--steps", type=float, nargs="+", default=None)
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "bench_scaling"))
    ap.add_argument("--quick", action="store_true", help="only the two solver.linear choices")
    ap.add_argument("--repeat", type=int, default=2, help="runs per timed configuration (fastest kept)")
    ap.add_argument("--messages", action="store_true", help="MPI traffic of both solvers at --ranks")
    ap.add_argument("--ranks", type=int, nargs="+", default=[2, 3, 4])
    ap.add_argument("--no-ceiling", action="store_true",
                    help="skip the machine's ceiling (two 1-rank runs side by side)")
    a = ap.parse_args(argv)
    base = yaml.safe_load(open(a.config))
    if a.steps:
        base["steps"] = a.steps
    base.setdefault("solver", {})["max_cutbacks"] = 1       # a failing solver stops early
    print(f"[bench] {base['name']}: steps {base['steps']}, {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.2f}")
    if a.messages:
        messages_table(base, a.out, a.ranks)
        return 0
    scaled = SCALED[:2] if a.quick else SCALED
    rows = [run(f"{name}_n{n}", n, SOLVERS[name], base, a.out, a.repeat) for name in scaled for n in (1, 2)]
    if not a.quick:
        for name in SOLVERS:
            if name not in SCALED:
                rows.append(run(f"{name}_n2", 2, SOLVERS[name], base, a.out))
    print_runs(rows, scaled)
    ceiling = None if a.no_ceiling else machine_ceiling(SOLVERS[scaled[0]], base, a.out, a.repeat)
    if ceiling:
        n1, n2 = (next(r for r in rows if r["name"] == f"{scaled[0]}_n{n}") for n in (1, 2))
        print(f"\nmachine ceiling ({scaled[0]} on 1 rank, two copies side by side against one alone, "
              f"best of {a.repeat}): run {ceiling['pair_run']:.2f} s against {ceiling['alone_run']:.2f} s, "
              f"wall {ceiling['pair_wall']:.2f} s against {ceiling['alone_wall']:.2f} s: no 2-rank run "
              f"can beat {ceiling['run']:.2f}x run, {ceiling['wall']:.2f}x wall here; {scaled[0]} reaches "
              f"{n1['total'] / n2['total'] / ceiling['run']:.0%} of it (run), "
              f"{n1['wall'] / n2['wall'] / ceiling['wall']:.0%} (wall)")
    print(f"\npartition at 2 ranks: {rows[1]['summary']['partition']}")
    print(f"exchange at 2 ranks: {rows[1]['summary'].get('exchange')}")
    with open(os.path.join(a.out, "bench_scaling.json"), "w") as fh:
        json.dump({"runs": [{k: v for k, v in r.items() if k != "summary"} for r in rows],
                   "ceiling": ceiling}, fh, indent=1)
    return 0
