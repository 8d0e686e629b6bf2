"""Projection of the fascicle-parallel solver to 64 ranks and a 1000-fascicle scene (issue 16).

A model of one Newton iteration on P ranks for n fascicles with M contact multipliers, every
coefficient measured on this machine, every assumption printed:

    T(n, P) = a ⌈n / P⌉  +  S(M_r)  +  Σ(n_Γ, P)  +  T_comm(n, P)

* a: the work that belongs to one fascicle (its elements, contact points, dense factor, Schur
  block and the block solves of every GMRES iteration), fitted as T₁ − S = a n over the one-rank
  runs of scripts/bench_growth.py (7 … 91 fascicles).
* S(M) = c M^p: one sequential MUMPS factorisation of a multiplier Schur complement and its
  solves ("ANCF Schur factor" + "ANCF Schur solve" in -log_view), fitted over the same runs
  (on one rank that is all of S).  On P ranks every rank factors its own S^r
  (linalg/substructure.py) of M_r = (M + n_Γ) / P multipliers, all ranks at once.
* n_Γ = κ M √(P / n): the multipliers on the cut between the ranks' patches of fascicles (a
  compact patch's perimeter over its area), κ from the measured 2-rank cut of 37 fascicles.
* Σ(n_Γ, P): the interface system.  Up to 2 000 cut multipliers dense on every rank, measured
  at 2 ranks; beyond that MUMPS on the distributed Σ, taken as c n_Γ^p / P^α_Σ: the S fit (Σ
  is denser than S, so this is optimistic) with α_Σ the parallel efficiency MUMPS showed on the
  whole distributed S (``--sigma-alpha``, 0.11 measured before the substructuring; the
  assumption that most limits the projection).
* T_comm: PETSc's messages, volumes and reductions per Newton iteration measured at 2, 3 and 4
  ranks (scripts/bench_scaling.py --messages): messages per rank taken at their 4-rank value
  (a rank of a two-dimensional fascicle partition talks to a bounded number of neighbours),
  bytes per rank scaled with the perimeter of a rank's patch of fascicles (√(n/P)), reductions
  per iteration as measured, each log₂P latencies.  Network: ``--latency`` and ``--bandwidth``
  (default 2 µs and 10 GB/s, an InfiniBand cluster).  MUMPS's own messages are not in PETSc's
  log; they are inside α_Σ.

Usage: python scripts/project_scaling.py [--growth results/bench_growth]
                                         [--scaling results/bench_scaling] [--sigma-alpha 0.11]
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys

import numpy as np

from ancf_verify import paths

ROOT = paths.ROOT
from ancf_petsc.linalg.log_view import read_log_view  # noqa: E402

S_EVENTS = ("ANCF Schur factor", "ANCF Schur solve")


def s_time(log: str) -> float:
    """Seconds in the multiplier Schur complement's factorisation and solves (slowest rank)."""
    ev = read_log_view(log)["events"]
    return sum(ev.get(k, {}).get("time", 0.0) for k in S_EVENTS)


def growth_fits(growth_dir: str) -> dict:
    """a (s per fascicle per iteration), c and p of S(M) = c M^p, and the multipliers per
    fascicle, from the fieldsplit rows of bench_growth.json."""
    rows = [r for r in json.load(open(os.path.join(growth_dir, "bench_growth.json")))
            if r["solver"] == "fieldsplit" and r["status"] == "completed"]
    n = np.array([r["count"] for r in rows], float)
    M = np.array([r["multipliers"] for r in rows], float)
    its = np.array([r["newton"] for r in rows], float)
    T1 = np.array([r["per_iteration"] for r in rows])
    S = np.array([s_time(os.path.join(growth_dir, f"hex{r['count']}_e{r['elements']}_fieldsplit",
                                      "log_view.txt")) for r in rows]) / its
    a = float(np.linalg.lstsq(n[:, None], T1 - S, rcond=None)[0][0])
    p, logc = np.polyfit(np.log(M), np.log(S), 1)
    return {"a": a, "c": float(np.exp(logc)), "p": float(p), "m_per_fascicle": float(np.mean(M / n)),
            "rows": [(int(k), int(m), t, s) for k, m, t, s in zip(n, M, T1, S)]}


def substructure_split(scaling_dir: str) -> dict:
    """The S parts at 1 and 2 ranks on 37 fascicles (bench_scaling.py --quick), the cut's size
    and the interface's share at 2 ranks (from the fieldsplit summary and -log_view)."""
    t = [s_time(os.path.join(scaling_dir, f"fieldsplit_n{k}", "log_view.txt")) for k in (1, 2)]
    s2 = json.load(open(os.path.join(scaling_dir, "fieldsplit_n2", "summary.json")))
    ls = s2["linear_solver"]
    ev = read_log_view(os.path.join(scaling_dir, "fieldsplit_n2", "log_view.txt"))["events"]
    M, cut, n = ls["multipliers"], ls["cut_multipliers"], len(s2["elements_per_beam"])
    return {"s1": t[0], "s2": t[1], "multipliers": M, "cut": cut,
            "fascicles": n, "kappa": cut / M / math.sqrt(2 / n),
            "sigma_dense": ev.get("ANCF Schur interface", {}).get("time", 0.0) / s2["newton_iterations"]}


def comm_model(scaling_dir: str) -> dict:
    """Messages and bytes per rank and reductions, per Newton iteration, at 4 ranks (37 fascicles)."""
    rows = [r for r in json.load(open(os.path.join(scaling_dir, "bench_messages.json")))
            if r["name"] == "fieldsplit"]
    by = {r["ranks"]: r for r in rows}
    r4 = by[max(by)]
    it, P = max(r4["newton"], 1), r4["ranks"]
    return {"ranks": P, "fascicles": 37,
            "messages": r4["total"]["messages"] / P / it, "bytes": r4["total"]["bytes"] / P / it,
            "reductions": r4["total"]["reductions"] / it,
            "measured": {k: (v["total"]["messages"] / max(v["newton"], 1),
                             v["total"]["bytes"] / max(v["newton"], 1),
                             v["total"]["reductions"] / max(v["newton"], 1)) for k, v in sorted(by.items())}}


def iteration_time(n: int, P: int, fit: dict, sub: dict, sigma_alpha: float, comm: dict,
                   lat: float, bw: float) -> dict:
    M = fit["m_per_fascicle"] * n
    work = fit["a"] * math.ceil(n / P)
    cut = 0.0 if P == 1 else min(M, sub["kappa"] * M * math.sqrt(P / n))
    schur = fit["c"] * ((M + cut) / P) ** fit["p"]
    if P == 1:
        sigma = 0.0
    elif cut <= 2000:                                   # dense on every rank, as measured
        sigma = sub["sigma_dense"] * (cut / sub["cut"]) ** 3
    else:
        sigma = fit["c"] * cut ** fit["p"] / P ** sigma_alpha
    t_comm = 0.0
    if P > 1:
        patch = math.sqrt((n / P) / (comm["fascicles"] / comm["ranks"]))
        t_comm = (comm["messages"] * lat + comm["bytes"] * patch / bw
                  + comm["reductions"] * math.log2(P) * lat)
    total = work + schur + sigma + t_comm
    return {"work": work, "schur": schur, "sigma": sigma, "cut": cut, "comm": t_comm, "total": total}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="project_scaling.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("--growth", default=os.path.join(ROOT, "results", "bench_growth"))
    ap.add_argument("--scaling", default=os.path.join(ROOT, "results", "bench_scaling"))
    ap.add_argument("--fascicles", type=int, default=1027, help="strong-scaling scene (19 rings)")
    ap.add_argument("--per-rank", type=int, default=16, help="fascicles per rank, weak scaling")
    ap.add_argument("--latency", type=float, default=2e-6, help="s per message")
    ap.add_argument("--bandwidth", type=float, default=10e9, help="bytes per s")
    ap.add_argument("--sigma-alpha", type=float, default=0.11,
                    help="MUMPS's parallel efficiency on the distributed interface system")
    a = ap.parse_args(argv)
    try:
        fit = growth_fits(a.growth)
    except FileNotFoundError as exc:
        ap.error(f"--growth: {exc.filename}: no such file (run scripts/bench_growth.py first)")
    try:
        sub, comm = substructure_split(a.scaling), comm_model(a.scaling)
    except FileNotFoundError as exc:
        ap.error(f"--scaling: {exc.filename}: no such file (run scripts/bench_scaling.py --quick "
                 "and --messages first)")
    print("Measured (one Newton iteration):")
    for k, m, t, s in fit["rows"]:
        print(f"  {k:4d} fascicles, {m:6d} multipliers: {t:6.2f} s, of which Schur factor+solves {s:5.2f} s")
    print(f"  per-fascicle work a = {fit['a'] * 1e3:.1f} ms; S(M) = {fit['c']:.2e} M^{fit['p']:.2f} s; "
          f"{fit['m_per_fascicle']:.0f} multipliers per fascicle")
    print(f"  Schur parts on {sub['fascicles']} fascicles: {sub['s1']:.2f} s (1 rank) -> {sub['s2']:.2f} s "
          f"(2 ranks, {sub['cut']} of {sub['multipliers']} multipliers on the cut: kappa = "
          f"{sub['kappa']:.2f}; dense interface {sub['sigma_dense'] * 1e3:.1f} ms per iteration)")
    print("  PETSc traffic per Newton iteration (37 fascicles; messages, MB, reductions): " + ", ".join(
        f"{P} ranks {m:.0f} / {b / 1e6:.2f} / {r:.0f}" for P, (m, b, r) in comm["measured"].items()))
    print(f"  network assumed: {a.latency * 1e6:.1f} us latency, {a.bandwidth / 1e9:.0f} GB/s")
    ranks = [1, 2, 4, 8, 16, 32, 64]
    for label, al in ((f"MUMPS on the distributed interface as on the distributed S before: "
                       f"alpha = {a.sigma_alpha:.2f}", a.sigma_alpha),
                      ("if MUMPS scaled the interface as P^0.5 (an assumption, not measured)", 0.5),
                      ("if the interface scaled perfectly (alpha = 1, the bound)", 1.0)):
        strong_and_weak(a, fit, sub, al, comm, ranks, label)
    return 0


def strong_and_weak(a, fit: dict, sub: dict, alpha: float, comm: dict, ranks: list, label: str) -> None:
    """Print the strong- and weak-scaling tables for one efficiency of the interface's MUMPS."""
    def t(n, P):
        return iteration_time(n, P, fit, sub, alpha, comm, a.latency, a.bandwidth)
    print(f"\n#### {label}\n")
    print(f"Strong scaling, {a.fascicles} fascicles x 16 elements "
          f"({a.fascicles * 17 * 18:,} beam DOFs, {fit['m_per_fascicle'] * a.fascicles:,.0f} multipliers), "
          "projected seconds per Newton iteration:\n")
    print("| ranks | fascicle work | Schur per rank | cut | interface | PETSc messages | total | speed-up | efficiency |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    t1 = t(a.fascicles, 1)["total"]
    for P in ranks:
        r = t(a.fascicles, P)
        print(f"| {P} | {r['work']:.2f} | {r['schur']:.2f} | {r['cut']:,.0f} | {r['sigma']:.2f} | "
              f"{r['comm']:.3f} | {r['total']:.2f} | {t1 / r['total']:.1f}x | {t1 / r['total'] / P:.0%} |")
    print(f"\nWeak scaling, {a.per_rank} fascicles per rank, projected seconds per Newton iteration:\n")
    print("| ranks | fascicles | multipliers | fascicle work | Schur per rank | cut | interface | PETSc messages | total | efficiency |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    base = t(a.per_rank, 1)["total"]
    for P in ranks:
        n = a.per_rank * P
        r = t(n, P)
        print(f"| {P} | {n} | {fit['m_per_fascicle'] * n:,.0f} | {r['work']:.2f} | {r['schur']:.2f} | "
              f"{r['cut']:,.0f} | {r['sigma']:.2f} | {r['comm']:.3f} | {r['total']:.2f} | {base / r['total']:.0%} |")
