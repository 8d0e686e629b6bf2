"""scripts/bench_stride.py: frames per second of the walking stride by elements, contact law and
material, this tree's ancf-solve (one load history) beside another's (each frame its own run from
rest), in alternating turns (workflows/stride_bench.py); with --tolerances, frames per second
against the answers' change as the absolute tolerance grows."""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

from ancf_petsc.workflows.envelope import GOH, NEO, EnvelopeCell
from ancf_petsc.workflows.stride_bench import (StrideCase, after, before, option_pairs, parse_options,
                                                tolerance_sweep)


def cases(twist: float, bias: str) -> list[StrideCase]:
    out = []
    for elements in (4, 8):
        for law, mu in (("sliding", 0.0), ("unilateral", 0.0), ("sliding", 0.3)):
            name = f"neo-Hookean {law}{f' mu {mu:g}' if mu else ''} {elements} el."
            out.append(StrideCase(name, EnvelopeCell(NEO, twist, bias, law, mu, elements, stride=True)))
    amir = [g for g in GOH if g.endswith("_amir.yaml")][0]
    out.append(StrideCase("GOH amir (its own law) 4 el.", EnvelopeCell(amir, twist, bias, None, 0.0, 4, stride=True)))
    return out


def tolerances(args, factors: list[float]) -> int:
    """Per case and factor of the absolute tolerance: Newton iterations, frames/s of solve (median
    over the repeats) and the largest relative change of the probes and the differential
    displacements over the stride against the run's own tolerance."""
    print(f"{'case':32s} {'atol factor':>11s} {'atol [N]':>9s} {'Newton':>7s} {'frames/s (solve)':>17s} "
          f"{'probes change':>14s} {'differential change':>20s}")
    for case in cases(args.twist, args.bias):
        if args.only and args.only not in case.label:
            continue
        runs = [tolerance_sweep(case, [args.solver], args.work, factors) for _ in range(args.repeats)]
        for k, row in enumerate(runs[-1]):
            if row["status"] == "crashed":
                print(f"{case.label:32s} {row['factor']:11g}  crashed", flush=True)
                continue
            fps = np.median([r[k].get("per_solve", 0.0) for r in runs])
            print(f"{case.label:32s} {row['factor']:11g} {row['atol']:9.1e} {row['iterations']:7d} {fps:17.1f} "
                  f"{row['changes'][0]:14.1e} {row['changes'][1]:20.1e}  {row['status']}", flush=True)
    return 0


def versus_options(args, petsc: dict) -> int:
    """Per case: this tree in turns without and with ``petsc`` options (``--vs-petsc``)."""
    text = ",".join(f"{k}={v}" for k, v in petsc.items())
    print(f"{'case':32s} {'frames/s (solve)':>17s} {'with ' + text:>24s} {'ratio (pairs)':>22s} "
          f"{'linear solve [s]':>17s} {'with':>7s}  Newton, with")
    for case in cases(args.twist, args.bias):
        if args.only and args.only not in case.label:
            continue
        r = option_pairs(case, [args.solver], args.work, petsc, args.repeats)
        a, b = r["without"], r["with"]
        print(f"{case.label:32s} {a['per_solve']:17.1f} {b['per_solve']:24.1f} "
              f"{r['ratio'][0]:8.3f} ({r['ratio'][1]:.2f}-{r['ratio'][2]:.2f}) "
              f"{a['linear_solve']:17.3f} {b['linear_solve']:7.3f}  {a['iterations']}, {b['iterations']}"
              f"  {'/'.join(a['statuses'])}, {'/'.join(b['statuses'])}", flush=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="bench_stride", description=__doc__.split("\n\n")[0])
    ap.add_argument("--solver", default=os.path.join(os.path.dirname(sys.executable), "ancf-solve"))
    ap.add_argument("--before", help="an ancf-solve without load histories (e.g. 38a07d3's)")
    ap.add_argument("--twist", type=float, default=45.0)
    ap.add_argument("--bias", default="uniform")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--sample", type=int, default=10, help="frames of the stride the before side solves")
    ap.add_argument("--work", default="results/bench_stride")
    ap.add_argument("--only", help="cases whose label contains this")
    ap.add_argument("--tolerances", help="factors of the run's own absolute tolerance, e.g. 1,10,100,1000: "
                                         "frames/s against the answers' change (speed against accuracy)")
    ap.add_argument("--vs-petsc", help="PETSc options, e.g. mat_mumps_icntl_6=3: this tree in turns "
                                       "without and with them in the config (a control's before/after)")
    args = ap.parse_args(argv)
    labels = [c.label for c in cases(args.twist, args.bias)]
    if args.only and not any(args.only in label for label in labels):
        ap.error(f"--only: no case's label contains {args.only!r}; cases: {'; '.join(labels)}")
    if args.vs_petsc:
        try:
            petsc = parse_options(args.vs_petsc)
        except ValueError as exc:
            ap.error(f"--vs-petsc: {exc}")
        return versus_options(args, petsc)
    if args.tolerances:
        return tolerances(args, [float(f) for f in args.tolerances.split(",")])
    print(f"{'case':40s} {'frames/s (solve)':>17s} {'frames/s (wall)':>16s} {'Newton/frame':>12s}"
          + ("  before: frames/s (wall), Newton/frame, ratio" if args.before else ""))
    for case in cases(args.twist, args.bias):
        if args.only and args.only not in case.label:
            continue
        a, b = [], []
        for _ in range(args.repeats):
            a.append(after(case, [args.solver], args.work))
            if args.before:
                b.append(before(case, [args.before], args.work, args.sample))
        solve = np.median([r.get("per_solve", 0.0) for r in a])
        wall = np.median([r.get("per_wall", 0.0) for r in a])
        per = a[-1].get("iterations", 0) / max(a[-1]["frames"], 1)
        line = f"{case.label:40s} {solve:17.1f} {wall:16.1f} {per:12.2f}  {a[-1]['status']}"
        if b:
            bw = np.median([r["per_wall"] for r in b])
            line += (f"  {bw:8.2f}, {b[-1]['median_iterations']:.0f}, {b[-1]['completed']}/{b[-1]['frames']} "
                     f"frames completed; after/before (wall) {wall / bw:.0f}x")
        print(line, flush=True)
    return 0
