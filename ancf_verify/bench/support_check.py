"""Set-up cost of the support check (``ancf_petsc/solving/supports.py``) against the scene size:
twisted hexagonal bundles of 7 to 91 fascicles (``configs/bundle_hex37.yaml`` with
``bundle.count`` changed, 16 elements each), one rank, best of ``--repeat``.  Prints the check's
time, the share of its one Jacobian assembly and the colours it needed, then the fitted exponent.

    python scripts/bench_support_check.py [--counts 7 19 37 61 91] [--repeat 2]

Before the check worked per colour it took 0.049 / 0.366 / 1.276 / 3.281 / 8.050 s here (commit
9c19f6b, one product per beam and mode: N^1.99); docs/parallel.md has both rows.
"""
from __future__ import annotations

import argparse
import copy
import os
import sys
import time

import numpy as np
import yaml

from ancf_verify import paths

ROOT = paths.ROOT


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--counts", type=int, nargs="+", default=[7, 19, 37, 61, 91])
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args(argv)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    import petsc4py
    petsc4py.init([sys.argv[0]])
    from petsc4py import PETSc
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.contact import build_contact
    from ancf_petsc.model.build import build_model
    from ancf_petsc.parallel.partition import make_layout
    from ancf_petsc.petsc.problem import Problem
    from ancf_petsc.solving.supports import beam_colours, free_rigid_motions
    with open(os.path.join(ROOT, "configs", "bundle_hex37.yaml")) as fh:
        base = yaml.safe_load(fh)
    print("| fascicles | check [s] | one Jacobian [s] | colours | free motions |")
    print("|---:|---:|---:|---:|---|")
    rows = []
    for count in args.counts:
        raw = copy.deepcopy(base)
        raw["bundle"].update(count=count, elements=16)
        spec = parse_config(raw, base_dir=os.path.join(ROOT, "configs"))
        model = build_model(spec)
        contact = build_contact(model, spec.contact, lambda *_: None)
        P = Problem(model, make_layout(model, "blocks", 1, 0, contact), PETSc.COMM_WORLD, contact, "sbaij")
        best = min(_timed(free_rigid_motions, P) for _ in range(args.repeat))
        t_jac = min(_timed(lambda p: p.jacobian(None, p.q0, p.J, p.J), P) for _ in range(args.repeat))
        colours = int(beam_colours(len(model.beams), [(i.a.index, i.b.index) for i in contact.interfaces]).max()) + 1
        print(f"| {count} | {best:.3f} | {t_jac:.3f} | {colours} | {free_rigid_motions(P) or 'none'} |", flush=True)
        rows.append((count, best))
        P.destroy()
    if len(rows) > 1:
        n, t = np.log([r[0] for r in rows]), np.log([r[1] for r in rows])
        print(f"\ntime of the check ∝ N^{np.polyfit(n, t, 1)[0]:.2f}")
    return 0


def _timed(fn, arg) -> float:
    t0 = time.perf_counter()
    fn(arg)
    return time.perf_counter() - t0
