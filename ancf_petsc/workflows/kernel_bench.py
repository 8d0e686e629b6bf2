"""Element-kernel throughput (Gauss points per second, one core) and whole-run wall times
(``scripts/bench_kernel.py``, ``make bench``; docs/parallel.md, docs/fibres.md).

Prints the compiled kernels (physics/element_kernels.pyx, issue 40) beside the numpy kernels
(``ANCF_NATIVE=0``) for neo-Hookean and GOH with their ratio; the residual-only and
residual+tangent rates of each law on a realistic element block (target (issue 2): >= 200 000
tangent evaluations per second; issue 40: >= 1.5 M GP/s for neo-Hookean and GOH on 3363); GOH
against neo-Hookean (issue 26: fibres along the pretwisted material lines, stretched so that
every fibre is in tension, >= 70 %); the cost of ``locking: mixed`` against each law without it;
the split of one numpy neo-Hookean evaluation; and the wall time of the verification problems.
"""
from __future__ import annotations

import argparse
import contextlib
import os
import subprocess
import time

# one core: OpenBLAS reads this when numpy loads it (a plain import of the package loads no numpy)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from .. import native  # noqa: E402
from ..physics import element3363 as el, kernels  # noqa: E402
from ..physics.cubature import gauss_legendre  # noqa: E402
from ..physics.fibres import fibre_directions  # noqa: E402
from ..physics.geometry import reference_nodal_vectors  # noqa: E402
from ..physics.goh import GOH  # noqa: E402
from ..physics.materials import NeoHookean, StVenantKirchhoff  # noqa: E402
from ..physics.mixed import ProjectedDilatation, pressure_basis  # noqa: E402
from ..physics.section import make_ellipse  # noqa: E402
from .timing import best_times  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def block(n_el: int, degree: int, axial: int, goh: GOH | None = None):
    """qe, G, w (and the GOH law bound to its fibres) of ``n_el`` elements 3363 of a pretwisted
    elliptic beam; G stored shape-function-major as ``Model.element_data`` stores it."""
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
    G = np.ascontiguousarray(G.transpose(0, 2, 1, 3)).transpose(0, 2, 1, 3)
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


@contextlib.contextmanager
def numpy_kernels():
    """The numpy kernels for the calls inside (``ANCF_NATIVE=0``, read at every call)."""
    old = os.environ.get("ANCF_NATIVE")
    os.environ["ANCF_NATIVE"] = "0"
    try:
        yield
    finally:
        if old is None:
            del os.environ["ANCF_NATIVE"]
        else:
            os.environ["ANCF_NATIVE"] = old


def compiled_vs_numpy(elements: int, repeat: int) -> None:
    """Compiled and numpy rates side by side (best of ``repeat`` interleaved calls each)."""
    print(f"# compiled ({native.status(kernels.COMPILED)}) / numpy kernels, element 3363, best of "
          f"{repeat} interleaved calls each [M GP/s]")
    print(f"{'law':12s} {'GP/elem':>8s} {'residual':>27s} {'residual+tangent':>27s}")
    law = GOH(1e6, 5e7, 2e6, 5.0, 0.1)
    for mat in (NeoHookean(1e6, 5e7), law):
        for degree in (4, 6, 8):
            qe, G, w, *bound = block(elements, degree, 3, law if mat is law else None)
            m = bound[0] if bound else mat
            cells = []
            for fn in (kernels.internal_force, kernels.internal_force_and_tangent):
                def slow(fn=fn):
                    with numpy_kernels():
                        fn(qe, G, w, m)
                fast, ref = best_times([lambda fn=fn: fn(qe, G, w, m), slow], repeat)
                cells.append(f"{w.size / fast / 1e6:6.2f} / {w.size / ref / 1e6:5.2f} = {ref / fast:5.1f}x")
            print(f"{mat.name:12s} {w.shape[1]:8d} {cells[0]:>27s} {cells[1]:>27s}")


def throughput(elements: int, repeat: int) -> None:
    print(f"\n# element kernel throughput, 1 core (OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')})")
    print(f"{'material':14s} {'GP/elem':>8s} {'residual GP/s':>15s} {'res+tangent GP/s':>17s}  target 200000")
    law = GOH(1e6, 5e7, 2e6, 5.0, 0.1)
    for mat in (NeoHookean(1e6, 5e7), StVenantKirchhoff(3e6, 0.3), law):
        for degree, axial in ((4, 3), (6, 3), (8, 3)):
            qe, G, w, *bound = block(elements, degree, axial, law if mat is law else None)
            m = bound[0] if bound else mat
            n = w.size
            r1 = rate(lambda: kernels.internal_force(qe, G, w, m), n, repeat)
            r2 = rate(lambda: kernels.internal_force_and_tangent(qe, G, w, m), n, repeat)
            flag = "ok" if r2 >= 2e5 else "BELOW TARGET"
            print(f"{mat.name:14s} {w.shape[1]:8d} {r1:15,.0f} {r2:17,.0f}  {flag}")
    print("\n# GOH / neo-Hookean throughput (same element, same points; target >= 70 %): best of "
          f"{repeat} interleaved calls each, robust on a shared machine")
    nh = NeoHookean(1e6, 5e7)
    for degree in (4, 6, 8):
        qe, G, w, bound = block(elements, degree, 3, law)
        out = []
        for fn in (kernels.internal_force, kernels.internal_force_and_tangent):
            a, b = best_times([lambda: fn(qe, G, w, bound), lambda: fn(qe, G, w, nh)], repeat)
            out.append(b / a)
        print(f"  degree {degree} ({w.shape[1]} GP/elem): residual {out[0]:6.1%}   "
              f"residual+tangent {out[1]:6.1%}")


def mixed_cost(elements: int, repeat: int) -> None:
    print("\n# locking: mixed / none (same law, element and points; the volumetric term on the dilatation "
          "projected per axial station, physics/mixed.py): time per call, best of "
          f"{repeat} interleaved calls each")
    nh, law = NeoHookean(1e6, 5e7), GOH(1e6, 5e7, 2e6, 5.0, 0.1)
    for degree, axial in ((4, 2), (6, 2), (6, 3), (8, 3)):
        for name, mat in (("neo-hookean", nh), ("goh", law)):
            qe, G, w, *bound = block(elements, degree, axial, law if mat is law else None)
            plain = bound[0] if bound else mat
            mixed = projected(plain, degree, axial, w)
            out = []
            for fn in (kernels.internal_force, kernels.internal_force_and_tangent):
                a, b = best_times([lambda: fn(qe, G, w, mixed), lambda: fn(qe, G, w, plain)], repeat)
                out.append((a, b))
            print(f"  {name:12s} degree {degree} x {axial} axial ({w.shape[1]} GP/elem): residual "
                  f"{1e3 * out[0][0]:6.2f} / {1e3 * out[0][1]:6.2f} ms = {out[0][0] / out[0][1]:5.2f}x   "
                  f"residual+tangent {1e3 * out[1][0]:6.2f} / {1e3 * out[1][1]:6.2f} ms = {out[1][0] / out[1][1]:5.2f}x")


def numpy_split(elements: int, repeat: int) -> None:
    """The parts of one numpy neo-Hookean residual+tangent evaluation."""
    qe, G, w = block(elements, 6, 3)
    mat = NeoHookean(1e6, 5e7)
    F = kernels.deformation_gradient(qe, G)
    _, _, terms = mat.stress_and_tangent(F)
    parts = {"deformation gradient F": lambda: kernels.deformation_gradient(qe, G),
             "material P and tangent terms": lambda: mat.stress_and_tangent(F),
             "tangent contraction (GEMMs)": lambda: kernels.contract_tangent(terms, G, w)}
    print("\n# split of a numpy neo-Hookean residual+tangent evaluation (microseconds per Gauss point)")
    total = 0.0
    for name, fn in parts.items():
        us = 1e6 / rate(fn, w.size, repeat)
        total += us
        print(f"  {name:32s} {us:7.3f}")
    print(f"  {'sum':32s} {total:7.3f}   ({1e6 / total:,.0f} GP/s)")


def runs() -> None:
    print("\n# whole-run wall time of the verification problems (ancf-solve, 1 rank, no VTK)")
    exe = os.path.join(ROOT, ".venv", "bin", "ancf-solve")
    for cfg in ("uniaxial_neohookean", "elastica_svk", "pretwisted_bar"):
        t = time.perf_counter()
        p = subprocess.run([exe, os.path.join(ROOT, "configs", cfg + ".yaml"), "--quiet",
                            "--output-dir", f"/tmp/ancf-bench-{cfg}"], capture_output=True, text=True)
        print(f"  {cfg:22s} {time.perf_counter() - t:6.2f} s  (exit {p.returncode})")


def main(argv: list[str] | None = None) -> int:
    """Usage: OPENBLAS_NUM_THREADS=1 python scripts/bench_kernel.py [--elements 64] [--repeat 20]
    [--skip-runs] [--compiled-only]"""
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--elements", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--skip-runs", action="store_true")
    ap.add_argument("--compiled-only", action="store_true", help="only the compiled / numpy table")
    args = ap.parse_args(argv)
    compiled_vs_numpy(args.elements, args.repeat)
    if args.compiled_only:
        return 0
    throughput(args.elements, args.repeat)
    mixed_cost(args.elements, args.repeat)
    numpy_split(args.elements, args.repeat)
    if not args.skip_runs:
        runs()
    return 0
