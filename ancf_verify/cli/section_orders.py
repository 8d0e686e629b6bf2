"""The section order as a rung (issue 42): 3363, 33103 and 33153 measured against beam theory, the
committed 3D solids and each other (ancf_verify.studies.section_orders; one markdown table per part)."""
from __future__ import annotations

import argparse
import time

from ancf_verify.studies.section_orders import PARTS


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split()), allow_abbrev=False)
    ap.add_argument("parts", nargs="*", help=f"some of {', '.join(PARTS)} (default: all)")
    args = ap.parse_args(argv)
    unknown = [p for p in args.parts if p not in PARTS]
    if unknown:
        ap.error(f"unknown part {unknown[0]!r}; parts: {', '.join(PARTS)}")
    from mpi4py import MPI  # noqa: F401
    import petsc4py
    petsc4py.init([])
    for name in args.parts or list(PARTS):
        t0 = time.perf_counter()
        print(f"\n## {name}  ({time.strftime('%Y-%m-%d')})\n", flush=True)
        PARTS[name]()
        print(f"\n({time.perf_counter() - t0:.0f} s)", flush=True)
    return 0
