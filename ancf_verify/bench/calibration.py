"""Calibration throughput (issue 28): solves of the Achilles column per minute, and the twin.

Prints, for Table 1's ψ = 0 column (configs/achilles_type3_psi0.yaml, 13 levels to 400 N):

1. **process**: one ``ancf-solve`` process per column (interpreter start-up, imports, set-up,
   solve, output): what a sweep pays per run;
2. **in-process, rebuilt**: ``run_model`` per column in one process (model, contact, matrix and
   solver built each time, results written): what ``ancf-study`` pays;
3. **reused**: ``SampleSolver``, the run built once and its material laws changed in place
   (matrix pattern, symbolic factorisation and contact set-up kept), each column load-stepped
   from the reference; checked against fresh builds;
4. **warm-started**: every sample of the Table 1 fit (configs/fits/table1_psi0_mu.yaml, trf, the
   fit phase only), each level started from the library's prediction; by start kind, with the
   symbolic factorisations counted and the optimum solved cold again to check that warm starts
   change no answer beyond the solver's tolerance;
5. **ranks**: a fixed workload (two generations of differential evolution: the same samples on
   any number of ranks) under ``mpirun -n 1`` and ``-n 2``, and the machine's ceiling measured as
   scripts/bench_scaling.py does: two copies of the 1-rank run side by side; then the trf fit's
   time to its optimum on 1 and 2 ranks;
6. ``--twin N``: the full-size synthetic twin (N noise draws; docs/calibration.md);
   ``--optimisers``: trf against differential evolution on the twin and the Table 1 fit.

Rates are per minute of wall time and per minute of CPU time (a shared machine inflates wall
times; CPU time is the per-core figure).  Every figure is the median of ``--repeat`` runs.
Results also go to <out>/bench.json.

Usage: python scripts/bench_calibration.py [--out results/bench_calibration] [--repeat 3]
                                           [--skip-ranks] [--twin 20]
"""
from __future__ import annotations

import argparse
import copy
import json
import os
import subprocess
import sys
import time
from dataclasses import replace

import numpy as np

from ancf_verify import paths

ROOT = paths.ROOT
CONFIG = os.path.join(ROOT, "configs", "achilles_type3_psi0.yaml")
FIT = os.path.join(ROOT, "configs", "fits", "table1_psi0_mu.yaml")
TWIN = os.path.join(ROOT, "configs", "fits", "twin_achilles_mu.yaml")
BAR_TWIN = os.path.join(ROOT, "configs", "fits", "bar_twin.yaml")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
BIN = os.path.join(ROOT, ".venv", "bin")


def rate(seconds: float) -> float:
    return 60.0 / seconds if seconds > 0 else float("nan")


def line(name: str, wall: float, cpu: float | None, extra: str = "") -> dict:
    c = f", CPU {cpu:.3f} s ({rate(cpu):.0f}/min)" if cpu is not None else ""
    print(f"[bench] {name:34s} {wall:.3f} s per column ({rate(wall):.0f}/min wall){c}{extra}", flush=True)
    return {"wall": wall, "cpu": cpu, "per_min_wall": rate(wall), "per_min_cpu": rate(cpu) if cpu else None}


def process_runs(out: str, repeat: int) -> dict:
    walls = []
    for k in range(repeat):
        t = time.perf_counter()
        subprocess.run([os.path.join(BIN, "ancf-solve"), CONFIG, "--quiet", "--output-dir",
                        os.path.join(out, f"process_{k}")], check=True, env=ENV, capture_output=True)
        walls.append(time.perf_counter() - t)
    return line("process (ancf-solve per column)", float(np.median(walls)), None)


def scaled_specs(raw: dict, factors) -> list:
    from ancf_petsc.config import parse_config
    specs = []
    for f in factors:
        r = copy.deepcopy(raw)
        for b in r["beams"]:
            b["material"]["mu"] = float(b["material"]["mu"]) * f
        r["output"] = {"dir": "unused", "vtk": False}
        specs.append(parse_config(r, base_dir=os.path.dirname(CONFIG)))
    return specs


def rebuilt_runs(raw: dict, out: str, repeat: int) -> dict:
    from ancf_petsc.solving.run import run_model, serial_comm
    walls, cpus = [], []
    for k, spec in enumerate(scaled_specs(raw, 1.0 + 0.01 * np.arange(repeat))):
        spec.output.dir = os.path.join(out, f"rebuilt_{k}")
        t, c = time.perf_counter(), time.process_time()
        res = run_model(spec, serial_comm(), log=lambda *_: None)
        walls.append(time.perf_counter() - t)
        cpus.append(time.process_time() - c)
        assert res.status == "completed", res.message
    return line("in-process, rebuilt (run_model)", float(np.median(walls)), float(np.median(cpus)))


def reused_runs(raw: dict, repeat: int) -> dict:
    """Cold columns on one reused run; the answers against fresh SampleSolvers."""
    from ancf_petsc.solving.samples import SampleSolver
    specs = scaled_specs(raw, 1.0 + 0.013 * np.arange(repeat + 1))
    solver = SampleSolver()
    solver.solve(specs[0])                        # the build, not timed
    outs = [solver.solve(s) for s in specs[1:]]
    solver.destroy()
    worst = 0.0
    for s, o in zip(specs[1:2], outs[:1]):
        fresh = SampleSolver()
        ref = fresh.solve(s)
        fresh.destroy()
        worst = max(worst, float(np.abs(ref.displacements["soleus"] - o.displacements["soleus"]).max()))
    r = line("reused run, cold from reference", float(np.median([o.wall_time for o in outs])),
             float(np.median([o.cpu_time for o in outs])), f"; vs a fresh build: max |du| {worst:.1e} m")
    r["vs_fresh"] = worst
    return r


def warm_fit(out: str) -> dict:
    """The Table 1 fit (fit phase only) in this process: every sample, by start kind."""
    from ancf_petsc.config import parse_config
    from ancf_petsc.linalg import logging
    from ancf_petsc.solving.samples import SampleSolver
    from ancf_petsc.workflows.calibration import load_fit
    from ancf_petsc.workflows.calibration.calibrate import run_calibration
    spec = load_fit(FIT)
    spec.identifiability.profiles = False
    spec.output = os.path.join(out, "warm_fit")
    sym0, num0 = logging.event_count("MatCholFctrSym"), logging.event_count("MatCholFctrNum")
    res = run_calibration(spec, fresh=True, say=lambda *_: None)
    sym, num = logging.event_count("MatCholFctrSym") - sym0, logging.event_count("MatCholFctrNum") - num0
    from ancf_petsc.workflows.calibration.log import SampleLog
    samples = SampleLog(spec.output, spec).samples
    out_rows = {}
    for kind in ("cold", "nearest", "affine", "all"):
        sel = [s for s in samples if kind in ("all", s.start)]
        if sel:
            w = float(np.mean([s.wall_time for s in sel]))
            c = float(np.mean([s.cpu_time for s in sel]))
            its = float(np.mean([s.newton_iterations for s in sel]))
            out_rows[kind] = line(f"warm fit: {kind} ({len(sel)} samples)", w, c,
                                  f"; {its:.1f} Newton its per column, "
                                  f"{sum(s.fallbacks for s in sel)} fallback levels")
    print(f"[bench] symbolic factorisations in the fit: {sym} (numeric {num}) for {len(samples)} samples")
    solver = SampleSolver()                 # the optimum again, cold: the answer of warm starts
    o = solver.solve(parse_config(spec.config(res.best.parameters.values()), base_dir=spec.model_dir))
    solver.destroy()
    cold = o.displacements["soleus"][:, 0]
    diff = float(np.max(np.abs(cold - np.asarray(res.best.model["soleus_elongation"]))))
    print(f"[bench] the optimum solved cold: max |elongation difference| against its warm start "
          f"{diff:.1e} m ({diff / np.max(np.abs(cold)):.1e} relative)")
    return {"rows": out_rows, "symbolic": sym, "numeric": num, "warm_vs_cold": diff,
            "samples": len(samples), "parameters": res.best.parameters}


def fit_file(out: str, name: str, **changes) -> str:
    """A copy of the Table 1 fit file with absolute paths and ``changes`` (top-level keys)."""
    from ancf_petsc import yamlio
    doc = yamlio.load(open(FIT).read())
    doc["model"] = CONFIG
    for d in doc["data"]:
        d["file"] = os.path.normpath(os.path.join(os.path.dirname(FIT), d["file"]))
    doc.update(changes)
    path = os.path.join(out, f"{name}.yaml")
    import yaml
    with open(path, "w") as fh:
        yaml.safe_dump(doc, fh, sort_keys=False)
    return path


def fit_command(path: str, ranks: int, out: str) -> list[str]:
    return ["mpirun", "--oversubscribe", "-n", str(ranks), os.path.join(BIN, "ancf-fit"), path,
            "--fresh", "--quiet", "--out", out]


def timed(cmds: list[list[str]]) -> float:
    t = time.perf_counter()
    procs = [subprocess.Popen(c, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE) for c in cmds]
    for p in procs:
        _, err = p.communicate()
        assert p.returncode == 0, err.decode()
    return time.perf_counter() - t


def ranks_runs(out: str, repeat: int) -> dict:
    de = fit_file(out, "de_workload", optimizer={"method": "differential_evolution", "popsize": 4,
                                                  "generations": 1, "polish": False, "seed": 1},
                  identifiability={"profiles": False})
    trf = fit_file(out, "trf_fit", identifiability={"profiles": False})
    one, two, pair, t1, t2 = [], [], [], [], []
    for k in range(repeat):
        one.append(timed([fit_command(de, 1, os.path.join(out, "de1"))]))
        two.append(timed([fit_command(de, 2, os.path.join(out, "de2"))]))
        pair.append(timed([fit_command(de, 1, os.path.join(out, f"de_pair{i}")) for i in (0, 1)]))
        t1.append(timed([fit_command(trf, 1, os.path.join(out, "trf1"))]))
        t2.append(timed([fit_command(trf, 2, os.path.join(out, "trf2"))]))
    n = json.load(open(os.path.join(out, "de1", "fit.json")))["throughput"]["samples"]
    one, two, pair = (float(np.median(x)) for x in (one, two, pair))
    speedup, ceiling = one / two, 2.0 * one / pair
    s1 = json.load(open(os.path.join(out, "trf1", "fit.json")))
    s2 = json.load(open(os.path.join(out, "trf2", "fit.json")))
    print(f"[bench] ranks: a fixed workload of {n} samples (differential evolution, 2 generations): "
          f"1 rank {one:.1f} s ({60 * n / one:.0f} samples/min), 2 ranks {two:.1f} s "
          f"({60 * n / two:.0f}/min): speed-up {speedup:.2f}; ceiling (two 1-rank copies side by side) "
          f"{ceiling:.2f}: {speedup / ceiling:.0%} of it")
    p1 = np.array(list(s1["best_sample"]["parameters"].values()))
    p2 = np.array(list(s2["best_sample"]["parameters"].values()))
    print(f"[bench] the trf fit: 1 rank {np.median(t1):.1f} s ({s1['throughput']['samples']} samples), "
          f"2 ranks {np.median(t2):.1f} s ({s2['throughput']['samples']} samples, trial points "
          f"speculatively with their finite differences); optima differ by "
          f"{np.max(np.abs(p1 / p2 - 1)):.1e} (relative)")
    return {"workload_samples": n, "one": one, "two": two, "pair": pair, "speedup": speedup,
            "ceiling": ceiling, "trf_one": float(np.median(t1)), "trf_two": float(np.median(t2)),
            "trf_samples": [s1["throughput"]["samples"], s2["throughput"]["samples"]],
            "trf_rel_difference": float(np.max(np.abs(p1 / p2 - 1)))}


def twin(out: str, draws: int, path: str = TWIN, factors=(1.3, 0.8, 1.25)) -> dict:
    """A synthetic twin: ``draws`` noise draws of the data of ``path`` (the full-size one by
    default, its truth the fit file's starts, each fit started ``factors`` away; the small one
    with ``--bar-twin``: truth 1.2 / 3.6 MPa, started from the fit file's starts)."""
    from ancf_petsc.workflows.calibration import load_fit
    from ancf_petsc.workflows.calibration.calibrate import run_calibration
    from ancf_petsc.workflows.calibration.parameters import to_u
    from ancf_petsc.workflows.calibration.twin import coverage, draw, exact_data, with_data
    spec = load_fit(path)
    spec.identifiability.profiles = False
    true = np.array([p.start for p in spec.parameters]) if factors else np.array([1.2e6, 3.6e6])
    exact = exact_data(spec, true)
    rng = np.random.default_rng(0)
    fitted, se, scaled, t0, samples = [], [], [], time.perf_counter(), 0     # scaled: (t95, floored)
    for k in range(draws):
        s = with_data(spec, draw(spec, exact, rng), os.path.join(out, "twin", str(k)))
        if factors:                                            # start away from the truth
            s.parameters = [replace(p, start=p.start * x) for p, x in zip(spec.parameters, factors)]
        res = run_calibration(s, fresh=True, say=lambda *_: None)
        fitted.append(res.fit.u)
        se.append(res.uncertainty.se_u)
        scaled.append((res.uncertainty.t95, res.uncertainty.floored))
        samples += res.throughput["samples"]
        if factors or k < 3:
            print(f"[bench] twin draw {k}: " + ", ".join(f"{p.name} {p.value:.4g} ± {p.se:.2g}"
                                                       for p in res.parameters), flush=True)
    u_true = to_u(spec.parameters, true)
    t95, floored = (np.array(x) for x in zip(*scaled))     # per draw: Student's t or 1.96 (s² = 1)
    within, within1 = (coverage(u_true, np.array(fitted), np.array(se), k) for k in (t95[:, None], 1.0))
    wall = time.perf_counter() - t0
    z = (np.array(fitted) - u_true) / np.array(se)
    print(f"[bench] twin: z-scores (fitted - true) / SE: mean {np.round(z.mean(axis=0), 3).tolist()}, "
          f"standard deviation {np.round(z.std(axis=0), 3).tolist()}; first 20 draws within 95 %: "
          f"{within[:20].sum(axis=0).tolist()}")
    print(f"[bench] twin: {draws} draws, {samples} samples in {wall:.0f} s; true value within the 95 % "
          f"interval (t {min(t95):.2f}-{max(t95):.2f}, {sum(floored)} at s² = 1) per parameter {within.sum(axis=0).tolist()}"
          f" of {draws}, all at once {int(within.all(axis=1).sum())}; within 1 SE {within1.sum(axis=0).tolist()}")
    return {"draws": draws, "within95": within.sum(axis=0).tolist(), "z_std": z.std(axis=0).tolist(), "within1se": within1.sum(axis=0).tolist(),
            "joint95": int(within.all(axis=1).sum()), "samples": samples, "wall": wall}


def optimisers(out: str) -> dict:
    """trf against differential evolution (+ trf polish) on two fits: the full-size twin (one
    noise draw, starts 30 % / -20 % / 25 % off) and the Table 1 fit; samples and final cost."""
    from ancf_petsc.workflows.calibration import load_fit
    from ancf_petsc.workflows.calibration.calibrate import run_calibration
    from ancf_petsc.workflows.calibration.twin import draw, exact_data, with_data
    rows = {}
    twin_spec = load_fit(TWIN)
    exact = exact_data(twin_spec, [p.start for p in twin_spec.parameters])
    twin_spec = with_data(twin_spec, draw(twin_spec, exact, np.random.default_rng(0)))
    twin_spec.parameters = [replace(p, start=p.start * x)
                            for p, x in zip(twin_spec.parameters, (1.3, 0.8, 1.25))]
    for name, spec in (("twin", twin_spec), ("table1", load_fit(FIT))):
        spec.identifiability.profiles = False
        for method in ("trf", "differential_evolution"):
            spec.optimizer.method = method
            spec.optimizer.popsize, spec.optimizer.generations = 5, 20
            spec.output = os.path.join(out, f"opt_{name}_{method}")
            t = time.process_time()
            res = run_calibration(spec, fresh=True, say=lambda *_: None)
            cpu = time.process_time() - t
            n = res.throughput["samples"]
            rows[f"{name}/{method}"] = {"samples": n, "cost": res.best.cost, "cpu": cpu,
                                        "values": list(res.best.parameters.values())}
            print(f"[bench] optimiser {name:7s} {method:22s}: {n:4d} samples, cost {res.best.cost:.6g}, "
                  f"CPU {cpu:.0f} s; " + ", ".join(f"{v:.5g}" for v in res.best.parameters.values()), flush=True)
    return rows


def write_twin_data() -> str:
    """configs/data/twin_achilles_mu.csv: the twin's exact data, made by the program at the
    paper's moduli (the twin fit file's starts)."""
    from ancf_petsc.workflows.calibration import load_fit
    from ancf_petsc.workflows.calibration.twin import exact_data
    path = os.path.join(ROOT, "configs", "data", "twin_achilles_mu.csv")
    head = ("# Synthetic twin data (docs/calibration.md): the paper's psi = 0 column solved by this program at\n"
            "# mu = 103.1 / 143.2 / 226.7 MPa (configs/achilles_type3_psi0.yaml); no noise (the benchmark adds it).\n"
            "# Written by: python scripts/bench_calibration.py --write-twin-data\n")
    levels = [10, 20, 30, 40, 45, 60, 80, 90, 100, 150, 200, 300, 400]
    if not os.path.exists(path):                     # the fit file needs the levels to load
        with open(path, "w") as fh:
            fh.write(head + "load_N,soleus_x_mm,lateral_y_mm,medial_y_mm\n"
                     + "".join(f"{x},0,0,0\n" for x in levels))
    spec = load_fit(TWIN)
    exact = exact_data(spec, [p.start for p in spec.parameters])
    with open(path, "w") as fh:
        fh.write(head + "load_N,soleus_x_mm,lateral_y_mm,medial_y_mm\n")
        for k, x in enumerate(levels):
            fh.write(f"{x},{exact['soleus_elongation'][k] * 1e3:.9f},{exact['lateral_gastrocnemius_y'][k] * 1e3:.9f},"
                     f"{exact['medial_gastrocnemius_y'][k] * 1e3:.9f}\n")
    print(f"[bench] wrote {path}")
    return path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "bench_calibration"))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--skip-ranks", action="store_true")
    ap.add_argument("--twin", type=int, default=0, help="noise draws of the full-size twin (0: none)")
    ap.add_argument("--write-twin-data", action="store_true", help="write the twin's data file and stop")
    ap.add_argument("--only-twin", action="store_true", help="the twin alone (with --twin N)")
    ap.add_argument("--optimisers", action="store_true", help="trf against differential evolution, then stop")
    ap.add_argument("--only-ranks", action="store_true", help="the 1 against 2 ranks part alone")
    ap.add_argument("--bar-twin", type=int, default=0, help="the small twin's draws (configs/fits/bar_twin.yaml), then stop")
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    os.environ.update({k: v for k, v in ENV.items() if k.startswith(("OPENBLAS", "OMP"))})
    import petsc4py
    petsc4py.init([])
    from ancf_petsc import yamlio
    if a.write_twin_data:
        write_twin_data()
        return 0
    raw = yamlio.load(open(CONFIG).read())
    print(f"[bench] {time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    if a.only_ranks:
        with open(os.path.join(a.out, "ranks.json"), "w") as fh:
            json.dump(ranks_runs(a.out, a.repeat), fh, indent=1, default=float)
        return 0
    if a.bar_twin:
        with open(os.path.join(a.out, "bar_twin.json"), "w") as fh:
            json.dump(twin(a.out, a.bar_twin, BAR_TWIN, None), fh, indent=1, default=float)
        return 0
    if a.optimisers:
        with open(os.path.join(a.out, "optimisers.json"), "w") as fh:
            json.dump(optimisers(a.out), fh, indent=1, default=float)
        return 0
    if a.only_twin:
        res = {"twin": twin(a.out, a.twin)}
        with open(os.path.join(a.out, "twin.json"), "w") as fh:
            json.dump(res, fh, indent=1, default=float)
        return 0
    res = {"date": time.strftime("%Y-%m-%d"), "load": os.getloadavg()[0],
           "process": process_runs(a.out, a.repeat), "rebuilt": rebuilt_runs(raw, a.out, a.repeat),
           "reused": reused_runs(raw, max(a.repeat, 5)), "warm": warm_fit(a.out)}
    if not a.skip_ranks:
        res["ranks"] = ranks_runs(a.out, a.repeat)
    if a.twin:
        res["twin"] = twin(a.out, a.twin)
    with open(os.path.join(a.out, "bench.json"), "w") as fh:
        json.dump(res, fh, indent=1, default=float)
    return 0
