"""The gait envelope (issue 38): the three subtendons over twist × bias × law × material × mesh,
with Newton iterations, cut-backs and failures per cell, for this tree's ancf-solve and optionally
another's side by side (``--before``).  The cells are workflows/envelope.py's.

    python scripts/bench_envelope.py --grid core --jobs 2
    python scripts/bench_envelope.py --grid core --before /work/base38/.venv/bin/ancf-solve
"""
from __future__ import annotations

import argparse
import csv
import os
import sys
from concurrent.futures import ThreadPoolExecutor

from ancf_petsc.workflows.envelope import BIASES, EnvelopeCell, run_cell

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NEO = os.path.join(HERE, "configs", "achilles_type3_psi45.yaml")
GOH = [os.path.join(HERE, "configs", f"achilles_type3_psi45_goh{s}.yaml")
       for s in ("", "_alex", "_amir", "_optimized_see", "_solver_default", "_tendon_model")]
TWISTS = tuple(range(0, 181, 15))


def grid(name: str, twists, biases, elements: int) -> list[EnvelopeCell]:
    """The cells of a named grid."""
    cells = []
    if name == "core":
        cells = [EnvelopeCell(NEO, t, b, law, elements=elements)
                 for law in ("sliding", "unilateral") for t in twists for b in biases]
    elif name == "friction":
        cells = [EnvelopeCell(NEO, t, b, "sliding", mu, elements=elements)
                 for mu in (0.1, 0.3, 0.5) for t in twists for b in biases]
    elif name == "goh":
        cells = [EnvelopeCell(base, t, b, None, elements=elements)
                 for base in GOH for t in twists for b in biases]
    return cells


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", default="core", choices=("core", "friction", "goh"))
    ap.add_argument("--twists", default=",".join(str(t) for t in TWISTS))
    ap.add_argument("--biases", default=",".join(BIASES))
    ap.add_argument("--elements", type=int, default=4)
    ap.add_argument("--solver", default=os.path.join(os.path.dirname(sys.executable), "ancf-solve"))
    ap.add_argument("--before", help="another ancf-solve to run the same cells with (before/after)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--work", default="results/envelope")
    ap.add_argument("--csv", help="write the rows here")
    args = ap.parse_args(argv)
    cells = grid(args.grid, [float(t) for t in args.twists.split(",")], args.biases.split(","), args.elements)
    solvers = [("after", [args.solver])] + ([("before", [args.before])] if args.before else [])
    jobs = [(tag, cmd, c) for c in cells for tag, cmd in solvers]
    rows = []

    def one(job):
        tag, cmd, cell = job
        res = run_cell(cell, cmd, os.path.join(args.work, tag))
        row = dict(res.row(), solver=tag)
        print(f"{tag:6s} {cell.name:60s} {res.status:10s} last {res.last_level:6g} N  Newton "
              f"{res.iterations:4d} (to 1.2 kN {res.iterations_to_1200:4d})  cut-backs {res.cutbacks:2d}  "
              f"{res.wall_time:6.1f} s  {res.message[:100]}", flush=True)
        return row

    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        rows = list(pool.map(one, jobs))
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    for tag, _ in solvers:
        mine = [r for r in rows if r["solver"] == tag]
        bad = [r for r in mine if r["status"] != "completed"]
        over = [r for r in mine if r["twist"] <= 90 and (r["iterations_to_1200"] > 60 or r["cutbacks_to_1200"])]
        print(f"[{tag}] {len(mine)} cells: {len(bad)} not completed, {len(over)} at twist <= 90 over "
              "60 Newton iterations or with a cut-back to 1.2 kN")
    return 0


if __name__ == "__main__":
    sys.exit(main())
