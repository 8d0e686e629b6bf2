"""A soft-matrix GOH bar against the 3D solid: end traction and point force on r (issue 26).

The pretwisted bar of scripts/verify_solid_fibres.py (ellipse 12 x 8 mm on the twist axis,
L = 50 mm, ψ = 180°, root clamped, helical fibres ``follow: twist``) with the published GOH set
"alex" (configs/achilles_type3_psi45_goh_alex.yaml): μ = 107.2 kPa, k1 = 75.351 MPa,
k2 = 23.926, κ = 0, K = 49.67 μ, so k1/μ ≈ 700.  The solid (P2 tetrahedra, the same UFL law and
fibre field, verify_solid_fibres.run_solid) is pulled by a uniform dead end traction F/A.  The
beam (3363, 2 axial Gauss points) is loaded either the same way (``traction_force``) or, as the
paper loads its subtendons, by the point force F on the position vector r of the last node
(``force``), with ``locking: none`` and ``mixed``, at 4 and 8 elements.

Quantities: the end-section centroid's displacement and the end section's rotation about x
(verify_solid_fibres: ANCF from r_y, r_z of the last node; the solid from the least-squares fit of
its end face), the rotation along x, the end face's mean u_x (the displacement a uniform traction
works on), the span of u_x over the end face and the constant of its quadratic fit, and the range
of the fibre strain Ē = I4 − 1 over the middle half of the bar, L/4 < X < 3L/4 (ANCF: its Gauss
points there, and per element; solid: its degree-2 quadrature points there).  Reference:
Richardson extrapolation of the solid's finest three meshes (verify_solid.richardson; the finest
mesh where the changes do not shrink).  Writes docs/solid_soft_matrix.csv and the marked block
``solid_soft_matrix`` of docs/fibres.md.

Usage: python scripts/verify_solid_soft_matrix.py [--out docs]
       python scripts/verify_solid_soft_matrix.py --replot      # the block from the CSV (no dolfinx)
       python scripts/verify_solid_soft_matrix.py --ancf-only   # ANCF runs again, the CSV's solid rows kept
       python scripts/verify_solid_soft_matrix.py --profile 2   # u_x across the end face: beams, solid h 2 mm
       python scripts/verify_solid_soft_matrix.py --more-solid --h 1.0   # one more solid mesh into the CSV
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time

from ancf_verify.bars.cases import ancf_section
from ancf_verify.cli import Parser, size
from ancf_verify.fibres.report import COLUMNS, page_for, read_csv, write_csv
from ancf_verify.fibres.solid import run_solid
from ancf_verify.paths import ROOT
from ancf_verify.soft_matrix.beams import beam_runs
from ancf_verify.soft_matrix.cases import BLOCK, CSV_NAME, EXTRA, FORCE, H, make_case
from ancf_verify.soft_matrix.report import fmt_e, render_block, write_doc
from ancf_verify.soft_matrix.solid import SoftProbe, profile, rows_of
from ancf_verify.stack import import_stack


def size_mm(text: str) -> float:
    """A mesh size in mm, as this command takes them: under 0.1 mm is a size in m given by mistake
    (the other solid commands take m), whose mesh gmsh would build for hours."""
    value = size(text)
    if value < 0.1:
        raise argparse.ArgumentTypeError(f"mesh sizes are in mm here (the other solid commands take m), "
                                          f"e.g. 2 for 2 mm; got {text!r}")
    return value


def _prepare_out(ap: argparse.ArgumentParser, args: argparse.Namespace, path: str) -> None:
    """Make --out before anything is solved (the CSV is written at the end: a new --out failed
    there, after the solid's 26 minutes) and refuse a merge into a CSV that is not there."""
    if args.profile or args.beam_only or args.force != FORCE:
        return                                    # nothing written
    if (args.ancf_only or args.more_solid) and not os.path.isfile(path):
        ap.error(f"--{'ancf-only' if args.ancf_only else 'more-solid'} merges into {path}, which does not "
                 "exist: give --out a directory holding solid_soft_matrix.csv")
    try:
        os.makedirs(args.out, exist_ok=True)
    except OSError as exc:
        ap.error(f"--out: cannot make {args.out!r} ({exc.strerror})")


def main(argv=None) -> int:
    ap = Parser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "docs"), help="directory of the CSV")
    ap.add_argument("--doc", default=None, help="the page with the marked block (default docs/fibres.md with --out docs, else a copy of it in --out)")
    ap.add_argument("--replot", action="store_true", help="the block from <out>/solid_soft_matrix.csv")
    ap.add_argument("--ancf-only", action="store_true", help="ANCF again, the CSV's solid rows kept (no dolfinx)")
    ap.add_argument("--force", type=float, default=FORCE, help="end force [N] (other than 200: beam only)")
    ap.add_argument("--beam-only", action="store_true", help="the beam runs, printed; nothing written")
    ap.add_argument("--more-solid", action="store_true", help="keep the CSV's rows, add solid meshes --h")
    ap.add_argument("--profile", type=size_mm, metavar="H",
                    help="print u_x along the end face's semi-axes: beams and the solid of mesh size H [mm]")
    ap.add_argument("--quad-degree", type=int, default=2, help="solid quadrature degree (default 2)")
    ap.add_argument("--h", type=size_mm, nargs="+", default=[1e3 * h for h in H], help="solid mesh sizes [mm]")
    args = ap.parse_args(argv)
    path = os.path.join(args.out, CSV_NAME)
    if args.replot:
        write_doc(page_for(args.out, args.doc), read_csv(path))
        return 0
    _prepare_out(ap, args, path)
    case = make_case(args.force)
    if args.profile or not (args.beam_only or args.force != FORCE or args.ancf_only):
        import_stack()             # a missing dolfinx is said before the beams run, not after
    if args.profile:
        with tempfile.TemporaryDirectory(prefix="verify_solid_soft_") as tmp:
            profile(case, args.profile, tmp)
        return 0
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="verify_solid_soft_") as tmp:
        beams = beam_runs(case, tmp)
        for r in beams:
            print(f"[ANCF] {r['model']} {r['res']}: {r['its']} its, u_x {1e3 * r['u'][0]:.4f} mm, "
                  f"rotation {r['rot']:+.3f} deg, Ē {fmt_e(r)} %, face-mean u_x {1e3 * r['u_mean'][0]:.4f} mm", flush=True)
        if args.beam_only or args.force != FORCE:
            return 0
        if args.more_solid:
            sec = ancf_section(case)
            solids = [run_solid(case, sec, 1e-3 * h, args.quad_degree, probe=SoftProbe) for h in args.h]
            rows = read_csv(path) + rows_of(case, solids)
        elif args.ancf_only:
            rows = rows_of(case, beams) + [d for d in read_csv(path) if not d["model"].startswith("ANCF")]
        else:
            sec, solids = ancf_section(case), []
            for h in args.h:
                solids.append(run_solid(case, sec, 1e-3 * h, args.quad_degree, probe=SoftProbe))
                r = solids[-1]
                print(f"[solid] {r['res']}: {r['dofs']} DOFs, {r['wall']:.1f} s, {r['its']} its, u_x "
                      f"{1e3 * r['u'][0]:.4f} mm, rotation {r['rot']:+.3f} deg, Ē {fmt_e(r)} %, face-mean u_x "
                      f"{1e3 * r['u_mean'][0]:.4f} mm, fibre field "
                      f"{r['field_err']:.1e}", flush=True)
            rows = rows_of(case, beams + solids)
    write_csv(path, rows, COLUMNS + EXTRA)
    args.doc = page_for(args.out, args.doc)
    write_doc(args.doc, rows)
    print(render_block(rows))
    print(f"\n[verify-solid-soft-matrix] {time.perf_counter() - t_start:.0f} s; wrote {path} and the block "
          f"{BLOCK} of {args.doc}")
    return 0
