"""ANCF 3363 beams against 3D solid elements: accuracy and wall time (``make verify-solid``).

The same bars are solved twice, serially on one core:

* **ANCF**: ancf_petsc in-process (``parse_config`` + ``run_model``), 1-16 elements, 3 and 2
  axial Gauss points;
* **solid**: quadratic tetrahedra (gmsh 4.8) with FEniCSx/dolfinx 0.5.2 on the same PETSc 3.18.
  The straight prism is meshed by extruding the section along x; every mesh node (mid-edge
  nodes included, the geometry is P2) is then mapped through the ANCF pretwist map
  ``ancf_petsc.physics.geometry.place``, so both models share one reference geometry.  The energy is
  the ANCF neo-Hookean law Ψ = μ/2 (J^(-2/3) I1 − 3) + K/2 (J − 1)², the root face x = 0 is
  clamped (ANCF ``fix: clamped``) and the face x = L carries the uniform dead traction F/A
  (ANCF ``traction_force``).  Newton uses MUMPS LDLᵀ, as the ANCF default does.

Quantity of interest: the displacement of the end-section centroid (ANCF: r of the last node;
solid: u at the reference centroid a + R(ψ)(c − a) of the face x = L).  The converged solid
answer is the Richardson extrapolation of the finest three meshes (effective size h ∝ DOFs^-1/3,
order fitted), or the finest mesh (uncertainty: its last change) when their changes do not
shrink; the relative error of any run is |u − u_ref| / |u_ref|.

Wall times are best-of-N ``time.perf_counter`` spans in this process, after imports and with
the form JIT cache warm: ANCF = parse + build + solve (+ writing results.h5, VTK off); solid =
function space + forms + load stepping + point evaluation; the solid's meshing (gmsh + dolfinx
mesh + twist map) is reported separately and is not in its wall time.

Writes docs/solid_comparison.csv, docs/solid_comparison.md, docs/figures/solid_vs_ancf.png.
Usage: python scripts/verify_solid.py [--quick] [--out docs] [--cases tension,bending,...]
       python scripts/verify_solid.py --replot     # redraw the figure from docs/solid_comparison.csv
"""
from __future__ import annotations

import copy
import os
import tempfile
import time

import numpy as np

from ancf_verify.bars.cases import CASES, Case, ancf_section, run_ancf
from ancf_verify.bars.mesh import solid_mesh
from ancf_verify.bars.report import (fmt_u, goal_lines, limit_lines, plot, render_md, replot, summary_table,
    table, write_csv)
from ancf_verify.bars.solid import run_solid, solve_solid
from ancf_verify.cli import Parser, count, out_dir
from ancf_verify.convergence import goal, richardson
from ancf_verify.paths import DOCS
from ancf_verify.stack import import_stack


# --------------------------------------------------------------------------------------------
def run_case(case: Case, args, tmp: str) -> tuple:
    """All ANCF and solid runs of one case, the reference, errors and the goal check."""
    sec = ancf_section(case)
    elements = (1, 2, 4, 8) if args.quick else (1, 2, 4, 8, 16)
    rows = [run_ancf(case, ne, ap, args.ancf_repeats, tmp) for ap in (3, 2) for ne in elements]
    solids = []
    for h in (case.h_quick if args.quick else case.h):
        s = run_solid(case, sec, h, args.solid_repeats, args.max_repeat_time, args.quad_degree)
        solids.append(s)
        print(f"[solid] {case.key} {s['res']}: {s['dofs']} DOFs, {s['wall']:.2f} s (+ mesh {s['mesh']:.2f} s), "
              f"{s['its']} Newton its, u = {fmt_u(s['u'])} mm", flush=True)
    rows += solids
    ref, unc, how = richardson(solids)
    for r in rows:
        r["err"] = float(np.linalg.norm(r["u"] - ref) / np.linalg.norm(ref))
    case.notes.append(f"ANCF section area {sec.area * 1e6:.4f} mm^2; solid end-face area "
                      f"{solids[-1]['face_area'] * 1e6:.4f} mm^2 (finest mesh)")
    return case, rows, ref, unc, how, goal(rows)


def main(argv=None) -> int:
    ap = Parser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="coarser set (smoke run)")
    ap.add_argument("--out", help="output directory (default docs/; with --quick results/verify_solid_quick/)")
    ap.add_argument("--cases", default=",".join(c.key for c in CASES), help="comma-separated case keys")
    ap.add_argument("--ancf-repeats", type=count, default=3)
    ap.add_argument("--solid-repeats", type=count, default=2)
    ap.add_argument("--max-repeat-time", type=float, default=60.0,
                    help="do not repeat a solid solve that took longer than this [s]")
    ap.add_argument("--quad-degree", type=count, default=2, help="solid quadrature degree (default 2)")
    ap.add_argument("--replot", action="store_true",
                    help="only redraw figures/solid_vs_ancf.png from <out>/solid_comparison.csv")
    args = ap.parse_args(argv)
    args.out = out_dir(args.out, args.quick, "verify_solid")
    if args.replot:
        if not os.path.exists(os.path.join(args.out, "solid_comparison.csv")):
            ap.error(f"--replot: no solid_comparison.csv in --out {args.out!r}; give the directory of a run's CSV")
        os.makedirs(os.path.join(args.out, "figures"), exist_ok=True)
        replot(os.path.join(args.out, "solid_comparison.csv"),
               os.path.join(args.out, "figures", "solid_vs_ancf.png"))
        return 0
    if args.quick:
        args.ancf_repeats, args.solid_repeats = min(args.ancf_repeats, 2), 1
    wanted = [k.strip() for k in args.cases.split(",") if k.strip()]
    unknown = set(wanted) - {c.key for c in CASES}
    if unknown or not wanted:
        what = f"unknown case(s) {', '.join(sorted(unknown))}" if unknown else "no case"
        ap.error(f"--cases: {what}; choose from "
                 f"{', '.join(c.key for c in CASES)}; got {args.cases!r}")
    if len(set(wanted)) < len(CASES) and os.path.realpath(args.out) == os.path.realpath(DOCS):
        ap.error(f"--cases: a run into docs/ writes solid_comparison.csv and .md with its cases alone (the "
                 f"committed references of the others would go); give --out DIR; got {args.cases!r}")
    import_stack()
    t_start = time.perf_counter()
    figdir = os.path.join(args.out, "figures")
    os.makedirs(figdir, exist_ok=True)
    results, md = {}, []
    first = next(c for c in CASES if c.key in wanted)        # JIT-compile the forms, untimed
    sec = ancf_section(first)
    solve_solid(first, sec, solid_mesh(first, sec, first.h[0]), args.quad_degree)
    with tempfile.TemporaryDirectory(prefix="verify_solid_") as tmp:
        for case in (copy.deepcopy(c) for c in CASES if c.key in wanted):
            t0 = time.perf_counter()
            results[case.key] = run_case(case, args, tmp)
            _, rows, ref, unc, how, g = results[case.key]
            lines = table(case, rows, ref, unc, how) + [""] + goal_lines(g) + limit_lines(rows, ref)
            print("\n".join(lines) + f"({time.perf_counter() - t0:.0f} s for this case)\n", flush=True)
            md += lines + [f"_{n}._" for n in case.notes] + [""]
    write_csv(os.path.join(args.out, "solid_comparison.csv"), results)
    plot(os.path.join(figdir, "solid_vs_ancf.png"), results)
    total = time.perf_counter() - t_start
    summary = summary_table(results)
    with open(os.path.join(args.out, "solid_comparison.md"), "w") as fh:
        fh.write(render_md(args, summary, md, total))
    print("\n".join(summary))
    print(f"\n[verify-solid] {total:.0f} s; wrote {args.out}/solid_comparison.md, solid_comparison.csv, "
          f"figures/solid_vs_ancf.png")
    return 0
