"""Every 3D-solid reference in one table: its meshes, its mesh convergence and the beams' error
against it at 2 / 4 / 8 / 16 elements (``make verify-solid``).

First each committed reference is re-solved on its coarsest mesh and compared with its CSV, and
the contact solids' own checks run (ancf_verify.checks: a few minutes on one core); ``--quick``
skips them and only reads the CSVs.  The references themselves (hours) are made by the commands
of docs/verification.md, "3D solids".

Usage: python scripts/verify_solid_summary.py [--quick] [--docs DIR]
"""
from __future__ import annotations

import os
import time

from ancf_verify.cli import Parser
from ancf_verify.paths import DOCS
from ancf_verify.summary import references, table


def main(argv: list[str] | None = None) -> int:
    ap = Parser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="only the table from the committed CSVs (no solving)")
    ap.add_argument("--docs", default=DOCS, help="directory of the CSVs (default docs/)")
    args = ap.parse_args(argv)
    refs = references(args.docs) if os.path.isdir(args.docs) else []
    if not refs:
        ap.error(f"--docs: no reference CSV (solid_comparison.csv, solid_contact.csv, ...) in {args.docs!r}; "
                 "give the directory that holds them (default docs/)")
    t0 = time.perf_counter()
    failed = []
    if not args.quick:
        from ancf_verify.checks import every_check
        failed = [c for c in every_check(docs=args.docs) if not c.ok]
    print(table(refs))
    print(f"\n[verify-solid] {time.perf_counter() - t0:.0f} s; beams: relative error of the ANCF 3363 beams "
          "(2 axial points) against the solid reference, worst over the load levels where several; "
          "mesh convergence: the reference's relative uncertainty from its meshes")
    if failed:
        print(f"[verify-solid] {len(failed)} check(s) failed: " + "; ".join(c.name for c in failed))
        return 1
    return 0
