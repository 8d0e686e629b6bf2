"""A pretwisted bar with helical GOH fibres: ANCF 3363 against a 3D solid (issue 26, ``make verify-solid``).

The bar of scripts/verify_solid.py (clamped root, uniform dead end traction F/A, every solid
mesh node mapped through the ANCF pretwist map ``place``), now with the fibre-reinforced law of
ancf_petsc/physics/goh.py written again in UFL:

    Ψ = μ/2 (J^(-2/3) I₁ − 3) + K/2 (J − 1)² + k1/(2 k2) (exp(k2 Ē²) − 1)   where Ē > 0,
    Ē = κ (I₁ − 3) + (1 − 3κ)(I4 − 1),   I4 = a0 · C a0   (I₁, I4 of C: not split).

The solid's fibre field a0 is an expression of the reference position X (evaluated at the
quadrature points, no interpolation): the unit tangent of the pretwist's material line through X,

    follow: twist   a0 ∝ (1, −τ (Z − a_z), τ (Y − a_y)),   τ = ψ / L,   a = twist axis,
    follow: axis    a0 = (1, 0, 0),

written here from the map X(x, P) = (x, a + R(τx)(P − a)), independently of
ancf_petsc/physics/fibres.py; the script checks the two fields agree at the solid's quadrature
points before it solves (``fibre field check``).

Quantities: the displacement of the end-section centroid (ANCF: r of the last node; solid: u at
the reference centroid) and the rotation of the end section about x (untwist < 0): the polar angle
of the in-plane (y, z) part M of the section's deformation gradient.  ANCF: M = A A0⁻¹ with
A = [r_y r_z] of the last node.  Solid: M = T S⁻¹ from the least-squares linear fit of the
deformed end face, S = ∫ s sᵀ dA, T = ∫ (x − x̄) sᵀ dA (s = in-plane position from the face
centroid).  For a section whose third moments vanish (an ellipse about its centroid) the fit of the
3363 element's quadratic section field is exactly [r_y r_z], so both measure the same thing.

Cases: three laws (GOH with helical fibres; the controls GOH with fibres along x and the matrix
alone) x three matrix compressibilities K/μ = 50, 8.34, 2.17; ANCF at 4, 8, 16 elements without and
with the element's volumetric-locking remedy ``locking: mixed`` (ancf_petsc/physics/mixed.py), and at
8, 16 elements with the volumetric term on a degree-2 section rule (``BeamSpec.volumetric_degree``: a
locking diagnosis, not a model option); the solid on three or four meshes.

Reference: Richardson extrapolation of the finest three solid meshes (verify_solid.richardson),
separately for the displacement and for the rotation; errors |u − u_ref| / |u_ref| and
|θ − θ_ref| / |θ_ref|.  Writes docs/solid_fibres.csv, the marked block ``solid_fibres`` of
docs/fibres.md and docs/figures/solid_fibres.png.

Usage: python scripts/verify_solid_fibres.py [--quick] [--out docs]
       python scripts/verify_solid_fibres.py --replot      # block + figure from the CSV (no dolfinx)
       python scripts/verify_solid_fibres.py --ancf-only   # ANCF runs again, the CSV's solid rows kept
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time

from ancf_verify.bars.cases import ancf_section
from ancf_verify.cli import out_dir
from ancf_verify.fibres.beams import ancf_runs
from ancf_verify.fibres.cases import (ANCF_MIXED, ANCF_MODELS, BLOCK, BULK_RATIOS, CSV_NAME, ELEMENTS,
    FIGURE, LAWS, make_case)
from ancf_verify.fibres.report import csv_rows, page_for, read_csv, render_block, write_csv, write_outputs
from ancf_verify.fibres.solid import run_solid
from ancf_verify.stack import import_stack


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="coarse meshes, K/mu = 50 only (smoke run)")
    ap.add_argument("--out", help="directory of the CSV and figures/ (default docs/; with --quick results/verify_solid_fibres_quick/)")
    ap.add_argument("--doc", default=None, help="the page with the marked block (default docs/fibres.md with --out docs, else a copy of it in --out)")
    ap.add_argument("--quad-degree", type=int, default=2, help="solid quadrature degree (default 2)")
    ap.add_argument("--replot", action="store_true", help="block and figure from <out>/solid_fibres.csv")
    ap.add_argument("--ancf-only", action="store_true",
                    help="run the ANCF models again and keep the solid rows of <out>/solid_fibres.csv (no dolfinx)")
    args = ap.parse_args(argv)
    args.out = out_dir(args.out, args.quick, "verify_solid_fibres")
    if args.replot:
        write_outputs(args.out, read_csv(os.path.join(args.out, CSV_NAME)), page_for(args.out, args.doc))
        return 0
    solid_rows = [d for d in read_csv(os.path.join(args.out, CSV_NAME)) if d["model"] not in ANCF_MODELS] \
        if args.ancf_only else None
    if not args.ancf_only:
        import_stack()
    t_start = time.perf_counter()
    rows = []
    ratios = BULK_RATIOS[:1] if args.quick else BULK_RATIOS
    with tempfile.TemporaryDirectory(prefix="verify_solid_fibres_") as tmp:
        for ratio in ratios:
            for law in LAWS:
                case = make_case(law, ratio, args.quick)
                runs = ancf_runs(case, tmp)
                if solid_rows is not None:
                    rows += csv_rows(case, law.key, ratio, runs) + [d for d in solid_rows if d["case"] == case.key]
                    continue
                sec = ancf_section(case)
                for h in case.h:
                    runs.append(run_solid(case, sec, h, args.quad_degree))
                    r, a, m = runs[-1], runs[len(ELEMENTS) - 1], runs[2 * len(ELEMENTS) - 1]
                    print(f"[solid] {case.key} {r['res']}: {r['dofs']} DOFs, {r['wall']:.1f} s, {r['its']} its, "
                          f"u_x {1e3 * r['u'][0]:.4f} mm, rotation {r['rot']:+.4f} deg "
                          f"(ANCF {ELEMENTS[-1]} el.: {1e3 * a['u'][0]:.4f} mm, {a['rot']:+.4f} deg; "
                          f"{ANCF_MIXED}: {1e3 * m['u'][0]:.4f} mm, {m['rot']:+.4f} deg)", flush=True)
                rows += csv_rows(case, law.key, ratio, runs)
    os.makedirs(args.out, exist_ok=True)
    write_csv(os.path.join(args.out, CSV_NAME), rows)
    args.doc = page_for(args.out, args.doc)
    write_outputs(args.out, rows, args.doc)
    print(render_block(rows))
    print(f"\n[verify-solid-fibres] {time.perf_counter() - t_start:.0f} s; wrote {args.out}/{CSV_NAME}, "
          f"{FIGURE} and the block {BLOCK} of {args.doc}")
    return 0
