"""scripts/stride_mesh_study.py: how many elements the walking stride needs. Per contact law, the
stride on a ladder of meshes: frames per second of solve, Newton iterations, and each kind of
output's worst error over the frames against the law's finest mesh (workflows/stride_mesh.py)."""
from __future__ import annotations

import argparse
import csv
import os
import sys

from ancf_petsc.workflows.stride_mesh import LAWS, markdown, run_ladder, with_errors

from .cli import at_least


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="stride_mesh_study", description=__doc__.split("\n\n")[0])
    ap.add_argument("--laws", default=",".join(LAWS), help=f"comma-separated, of {', '.join(LAWS)}")
    ap.add_argument("--elements", default="2,4,8,16", help="elements per beam, comma-separated (the last "
                                                           "the reference)")
    ap.add_argument("--twist", type=float, default=45.0)
    ap.add_argument("--bias", default="uniform", choices=("gastrocnemius", "uniform", "soleus"))
    ap.add_argument("--solver", default=os.path.join(os.path.dirname(sys.executable), "ancf-solve"))
    ap.add_argument("--work", default="results/stride_mesh")
    ap.add_argument("--csv", help="write the rows here")
    ap.add_argument("--figure", help="write the error-against-speed figure here (PNG)")
    args = ap.parse_args(argv)
    laws = args.laws.split(",")
    bad = [x for x in laws if x not in LAWS]
    if bad:
        ap.error(f"--laws: unknown {', '.join(bad)}; expected of {', '.join(LAWS)}")
    try:
        elements = sorted({at_least(1)(x) for x in args.elements.split(",")})
    except argparse.ArgumentTypeError as exc:
        ap.error(f"--elements: {exc}")
    if len(elements) < 2:
        ap.error("--elements: give at least two meshes (the finest is the reference)")
    rows = []
    for name in laws:
        law_rows, series = run_ladder(LAWS[name], elements, [args.solver], args.work, args.twist, args.bias)
        rows += with_errors(law_rows, series)
        for r in law_rows:
            print(f"{r['law']:12s} {r['elements']:3d} elements: {r['status']}, {r['frames_per_s']:.1f} frames/s "
                  f"(solve), {r['iterations']} Newton iterations, {r['frames_cut_back']} frames cut back",
                  flush=True)
    print(markdown(rows))
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    if args.figure:
        from ancf_petsc.viz.stride_mesh import plot_stride_mesh       # matplotlib only when asked
        plot_stride_mesh(rows, args.figure)
    return 0
