#!/usr/bin/env python3
"""Element-kernel throughput (Gauss points per second, one core) and whole-run wall times.

Prints the residual-only and residual+tangent rates for the neo-Hookean and SVK kernels on a
realistic element block, the split of one tangent evaluation into its parts, and the wall time
of the verification problems.  Target (issue 2): >= 200 000 tangent evaluations per second; the GOH kernel (issue 26, fibres along
the pretwisted material lines, stretched so that every fibre is in tension) >= 70 % of neo-Hookean's;
the cost of ``locking: mixed`` (issue 26) against each law without it.
Usage: OPENBLAS_NUM_THREADS=1 python scripts/bench_kernel.py [--elements 64] [--repeat 20]
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from ancf_petsc.physics import element3363 as el, kernels
from ancf_petsc.physics.cubature import gauss_legendre
from ancf_petsc.physics.geometry import reference_nodal_vectors
from ancf_petsc.physics.fibres import fibre_directions
from ancf_petsc.physics.goh import GOH
from ancf_petsc.physics.materials import NeoHookean, StVenantKirchhoff
from ancf_petsc.physics.mixed import ProjectedDilatation, pressure_basis
from ancf_petsc.physics.section import make_ellipse
from ancf_petsc.workflows.timing import best_times


def block(n_el: int, degree: int, axial: int, goh: GOH | None = None):
    sec = make_ellipse((0.004, 0.0025), (0.003, 0.0), degree)
    xa, wa = gauss_legendre(axial)
    xi, y, z = el.tensor_points(xa, sec.points)
    _, dN = el.shape_functions(xi, y, z)
    wq = np.repeat(wa, len(sec.weights)) * np.tile(sec.weights, axial)
    x = np.linspace(0.0, 0.07, 2 * n_el + 1)
    q0 = reference_nodal_vectors(x, sec.centroid, 0.07, 45.0, (0.0, 0.0))
    conn = np.stack([2 * np.arange(n_el), 2 * np.arange(n_el) + 1, 2 * np.arange(n_el) + 2], 1)
    q0e = q0[conn].reshape(n_el, 18, 3)
    G, det = el.reference_gradients(q0e, dN)
    rng = np.random.default_rng(0)
    # a physical state (det F > 0, every fibre in tension): 5 % axial stretch plus noise of 0.1 %
    # of the element length on r and 0.1 % on the gradient vectors (NaNs would time other paths)
    scale = np.where(np.arange(18) % 6 == 0, x[2] - x[0], 1.0)[None, :, None]
    qe = q0e * np.array([1.05, 1.0, 1.0]) + 1e-3 * rng.standard_normal(q0e.shape) * scale
    if goh is None:
        return qe, G, det * wq[None]
    xg = x[0:-1:2, None] + 0.5 * (xi[None, :] + 1.0) * (x[2] - x[0])
    P = np.broadcast_to(sec.centroid + np.column_stack([y, z]), xg.shape + (2,)).reshape(-1, 2)
    a0 = fibre_directions(xg.ravel(), P, 0.07, 45.0, (0.0, 0.0), sec.centroid)
    return qe, G, det * wq[None], goh.with_directions(a0.reshape((1,) + xg.shape + (3,)))


def projected(law, degree: int, axial: int, w: np.ndarray) -> ProjectedDilatation:
    """``law`` with ``locking: mixed`` on the points of ``block`` (its weights w bound)."""
    sec = make_ellipse((0.004, 0.0025), (0.003, 0.0), degree)
    xa, wa = gauss_legendre(axial)
    _, y, z = el.tensor_points(xa, sec.points)
    wq = np.repeat(wa, len(sec.weights)) * np.tile(sec.weights, axial)
    return ProjectedDilatation(law, pressure_basis(np.column_stack([y, z]), wq, axial)).on(w)


def rate(fn, n_gp: int, repeat: int) -> float:
    fn()
    t = time.perf_counter()
    for _ in range(repeat):
        fn()
    return n_gp * repeat / (time.perf_counter() - t)


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False)
    ap.add_argument("--elements", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--skip-runs", action="store_true")
    args = ap.parse_args()
    print(f"# element kernel throughput, 1 core (OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']})")
    print(f"{'material':14s} {'GP/elem':>8s} {'residual GP/s':>15s} {'res+tangent GP/s':>17s}  target 200000")
    law = GOH(1e6, 5e7, 2e6, 5.0, 0.1)
    for mat in (NeoHookean(1e6, 5e7), StVenantKirchhoff(3e6, 0.3), law):
        for degree, axial in ((4, 3), (6, 3), (8, 3)):
            qe, G, w, *bound = block(args.elements, degree, axial, law if mat is law else None)
            m = bound[0] if bound else mat
            n = w.size
            r1 = rate(lambda: kernels.internal_force(qe, G, w, m), n, args.repeat)
            r2 = rate(lambda: kernels.internal_force_and_tangent(qe, G, w, m), n, args.repeat)
            flag = "ok" if r2 >= 2e5 else "BELOW TARGET"
            print(f"{mat.name:14s} {w.shape[1]:8d} {r1:15,.0f} {r2:17,.0f}  {flag}")
    print("\n# GOH / neo-Hookean throughput (same element, same points; target >= 70 %): best of "
          f"{args.repeat} interleaved calls each, robust on a shared machine")
    nh = NeoHookean(1e6, 5e7)
    for degree in (4, 6, 8):
        qe, G, w, bound = block(args.elements, degree, 3, law)
        out = []
        for fn in (kernels.internal_force, kernels.internal_force_and_tangent):
            a, b = best_times([lambda: fn(qe, G, w, bound), lambda: fn(qe, G, w, nh)], args.repeat)
            out.append(b / a)
        print(f"  degree {degree} ({w.shape[1]} GP/elem): residual {out[0]:6.1%}   "
              f"residual+tangent {out[1]:6.1%}")
    print("\n# locking: mixed / none (same law, element and points; the volumetric term on the dilatation "
          "projected per axial station, physics/mixed.py): time per call, best of "
          f"{args.repeat} interleaved calls each")
    for degree, axial in ((4, 2), (6, 2), (6, 3), (8, 3)):
        for name, mat in (("neo-hookean", nh), ("goh", law)):
            qe, G, w, *bound = block(args.elements, degree, axial, law if mat is law else None)
            plain = bound[0] if bound else mat
            mixed = projected(plain, degree, axial, w)
            out = []
            for fn in (kernels.internal_force, kernels.internal_force_and_tangent):
                a, b = best_times([lambda: fn(qe, G, w, mixed), lambda: fn(qe, G, w, plain)], args.repeat)
                out.append((a, b))
            print(f"  {name:12s} degree {degree} x {axial} axial ({w.shape[1]} GP/elem): residual "
                  f"{1e3 * out[0][0]:6.2f} / {1e3 * out[0][1]:6.2f} ms = {out[0][0] / out[0][1]:5.2f}x   "
                  f"residual+tangent {1e3 * out[1][0]:6.2f} / {1e3 * out[1][1]:6.2f} ms = {out[1][0] / out[1][1]:5.2f}x")
    # split of one neo-Hookean tangent evaluation
    qe, G, w = block(args.elements, 6, 3)
    mat = NeoHookean(1e6, 5e7)
    n = w.size
    F = kernels.deformation_gradient(qe, G)
    P, J, terms = mat.stress_and_tangent(F)
    parts = {
        "deformation gradient F": lambda: kernels.deformation_gradient(qe, G),
        "material P and tangent terms": lambda: mat.stress_and_tangent(F),
        "tangent contraction (GEMMs)": lambda: kernels.contract_tangent(terms, G, w),
    }
    print("\n# split of a neo-Hookean residual+tangent evaluation (microseconds per Gauss point)")
    total = 0.0
    for name, fn in parts.items():
        us = 1e6 / rate(fn, n, args.repeat)
        total += us
        print(f"  {name:32s} {us:7.3f}")
    print(f"  {'sum':32s} {total:7.3f}   ({1e6 / total:,.0f} GP/s)")
    if args.skip_runs:
        return
    print("\n# whole-run wall time of the verification problems (ancf-solve, 1 rank, no VTK)")
    exe = os.path.join(ROOT, ".venv", "bin", "ancf-solve")
    for cfg in ("uniaxial_neohookean", "elastica_svk", "pretwisted_bar"):
        t = time.perf_counter()
        p = subprocess.run([exe, os.path.join(ROOT, "configs", cfg + ".yaml"), "--quiet",
                            "--output-dir", f"/tmp/ancf-bench-{cfg}"], capture_output=True, text=True)
        dt = time.perf_counter() - t
        print(f"  {cfg:22s} {dt:6.2f} s  (exit {p.returncode})")


if __name__ == "__main__":
    main()
