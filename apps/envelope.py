"""scripts/bench_envelope.py: the gait envelope's grids (workflows/envelope.py) with this tree's
ancf-solve and optionally another's (--before), a line per cell and one against the targets."""
from __future__ import annotations

import argparse
import csv
import os
import sys

from ancf_petsc.config.specs import TANGENTS
from ancf_petsc.workflows.envelope import BIASES, GRIDS, TWISTS, grid, run_cells
from ancf_petsc.workflows.envelope_summary import cell_key, not_completed, summary_line


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="bench_envelope", description=__doc__.split("\n\n")[0])
    ap.add_argument("--grid", default="core", choices=list(GRIDS))
    ap.add_argument("--twists", default=",".join(str(t) for t in TWISTS), help="degrees, comma-separated")
    ap.add_argument("--biases", default=",".join(BIASES))
    ap.add_argument("--elements", type=int, default=4)
    ap.add_argument("--predictor", choices=("secant", "tangent", "none"), help="solver.predictor of every cell")
    ap.add_argument("--tangent", choices=TANGENTS, help="solver.tangent of every cell")
    ap.add_argument("--augmentation", type=float,
                    help="contact.tangential.augmentation of every friction cell")
    ap.add_argument("--band-step", type=float, help="solver.band_step of every cell (docs/running.md)")
    ap.add_argument("--section-update", choices=("linear", "rotation"),
                    help="solver.section_update of every cell (docs/running.md)")
    ap.add_argument("--pressure-axial", type=int, help="contact.projection.axial of every cell (docs/contact.md)")
    ap.add_argument("--solver", default=os.path.join(os.path.dirname(sys.executable), "ancf-solve"))
    ap.add_argument("--before", help="another ancf-solve to run the same cells with (before/after)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--work", default="results/envelope")
    ap.add_argument("--csv", help="write the rows here")
    ap.add_argument("--failed-in", help="a CSV of the same grid: run only its cells that did not complete")
    args = ap.parse_args(argv)
    cells = grid(args.grid, [float(t) for t in args.twists.split(",")], args.biases.split(","), args.elements,
                 predictor=args.predictor, tangent=args.tangent, augmentation=args.augmentation,
                 band_step=args.band_step, section_update=args.section_update,
                 pressure_axial=args.pressure_axial)
    if args.failed_in:
        if not os.path.isfile(args.failed_in):
            ap.error(f"--failed-in {args.failed_in}: no such file (a CSV written by --csv)")
        failed = not_completed(args.failed_in)
        cells = [c for c in cells if cell_key(c) in failed]
    solvers = {"after": [args.solver], **({"before": [args.before]} if args.before else {})}
    rows = run_cells(cells, solvers, args.work, args.jobs, lambda line: print(line, flush=True))
    if args.csv and rows:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    for tag in solvers:
        print(summary_line(rows, tag))
    return 0
