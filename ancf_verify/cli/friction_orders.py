"""The section orders against the friction solid (issue 42): tables and the inf-sup study.

The beam columns are those of ``scripts/verify_solid_friction.py --element <element>`` (rows
"ANCF <element> 2pt" of docs/solid_friction.csv, e.g.
``--psi 45 --no-solid --merge --no-selftest --no-checks --ancf-augmentations default --profiles ""
--element 33103 --elements 4,8,16 --ancf-spaces "default;quadratic across;cubic across"``); this
command prints their tables against the finest locally refined solid (docs/interface.md,
"Orders 3 and 4 against the friction solid") and, with ``--infsup``, measures the inf-sup
constant of each pressure space across on each order (friction.infsup) into
docs/solid_friction_infsup.csv.

    python scripts/friction_orders.py                       # the tables from the CSVs
    python scripts/friction_orders.py --infsup              # the inf-sup study (dense, minutes), then the tables
"""
from __future__ import annotations

import argparse
import os
import tempfile

from ancf_verify.friction.orders import (INFSUP_CSV, infsup_md, per_level_md, read_infsup, summary_md,
    write_infsup)
from ancf_verify.friction.rows import read_csv
from ancf_verify.paths import ROOT


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--infsup", action="store_true", help="measure the inf-sup constants first")
    ap.add_argument("--elements", default="4,8,16", help="elements per subtendon of the inf-sup study")
    ap.add_argument("--orders", default="3363,33103,33153", help="the elements of the inf-sup study")
    ap.add_argument("--spaces", default="default;quadratic across;cubic across", help="pressure spaces (';')")
    ap.add_argument("--csv", default=os.path.join(ROOT, "docs", "solid_friction.csv"))
    args = ap.parse_args(argv)
    if args.infsup:
        from ancf_verify.friction.infsup import infsup
        from ancf_verify.stack import import_stack
        import_stack()
        out = []
        with tempfile.TemporaryDirectory(prefix="infsup_") as tmp:
            for el in args.orders.split(","):
                for sp in [s.strip() for s in args.spaces.split(";") if s.strip()]:
                    for ne in [int(e) for e in args.elements.split(",")]:
                        r = infsup(el, ne, None if sp == "default" else sp, tmp)
                        print(f"[infsup] {el} {ne} el. {sp}: " + ", ".join(f"{k} {v:.3e}" for k, v in r.items()
                                                                          if isinstance(v, float)), flush=True)
                        out.append(r)
        write_infsup(out)
    rows = read_csv(args.csv)
    print("\n".join(summary_md(rows, 45.0)) + "\n")
    print("\n".join(per_level_md(rows, 45.0)) + "\n")
    if os.path.exists(INFSUP_CSV):
        print("\n".join(infsup_md(read_infsup())))
    return 0
