#!/usr/bin/env python3
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
import copy
import math
import os
import sys
import tempfile
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402

import verify_solid as vs  # noqa: E402
import verify_solid_fibres as vsf  # noqa: E402

CSV_NAME = "solid_soft_matrix.csv"
BLOCK = "solid_soft_matrix"
WRITER = "scripts/verify_solid_soft_matrix.py"
MU = 107.2e3
BULK_RATIO = 49.67
MATERIAL = {"model": "goh", "mu": MU, "bulk_modulus": BULK_RATIO * MU, "k1": 75.351e6, "k2": 23.926,
            "kappa": 0.0, "fibres": {"follow": "twist"}}
#: total end force [N]: the largest Ē of the 8-element traction beam in the bar's middle half is
#: 3.2 % (``--beam-only --force F``: 2.4 % at 100 N, 4.0 % at 300 N)
FORCE = 200.0
ELEMENTS = (4, 8)
H = (2.83e-3, 2e-3, 1.41e-3, 1e-3)     # solid mesh sizes [m]; the finest alone takes ~20 min
LOADS = {"traction_force": "end traction", "force": "point force on r"}
LOCKINGS = {vsf.ANCF: "none", vsf.ANCF_MIXED: "mixed"}
MIDDLE = (0.25, 0.75)              # the bar's middle half, fractions of L
EXTRA = ["fibre_strain_min", "fibre_strain_max", "ux_mean_m", "ux_fit0_m", "ux_span_m"]


def make_case(force: float = FORCE) -> vs.Case:
    """The soft-matrix bar at total end force ``force``."""
    return vs.Case("goh_soft_alex", "GOH alex set, helical fibres", copy.deepcopy(vsf.SECTION),
                   copy.deepcopy(MATERIAL), (force, 0.0, 0.0), h=H, h_quick=H, length=vsf.LENGTH,
                   twist_deg=vsf.TWIST, twist_axis=(0.0, 0.0), steps=vsf.STEPS)


def model_name(locking: str, load: str) -> str:
    return f"ANCF, {LOADS[load]}, locking: {locking}"


def ancf_measures(case: vs.Case, elements: int, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Ē = a0 · C a0 − 1 at the Gauss points (elements, points), the end section's mean displacement
    Σ_k m̄_k Δq_k (m̄_k = ∫ m_k dA / A, the traction's weights) and the span of u_x over the solid's
    end-face sample points (SolidProbe's), state q."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from ancf_petsc.physics.element3363 import section_monomials
    from ancf_petsc.physics.kernels import deformation_gradient
    model = build_model(parse_config(vs.ancf_config(case, elements, 2, tempfile.mkdtemp()), base_dir=vs.CONFIGS))
    b = model.beams[0]
    local = np.arange(elements)
    G, _, material = model.element_data(b, local)[0]
    F = deformation_gradient(q[b.connectivity[local]][:, :, list(b.vectors)].reshape(len(local), -1, 3), G)
    Fa = np.einsum("...ij,...j->...i", F, material.a0[0])
    m = section_monomials(b.section.points[:, 0], b.section.points[:, 1])[0]
    mean = b.section.weights @ m / b.section.weights.sum()
    ux = section_monomials(*(vsf.SAMPLE_SCALE * b.section.points).T)[0] @ (q[-1, :, 0] - model.q0[-1, :, 0])
    return np.einsum("...i,...i->...", Fa, Fa) - 1.0, mean @ (q[-1] - model.q0[-1]), float(ux.max() - ux.min())


def run_beam(case: vs.Case, elements: int, tmp: str, model: str, load: str) -> dict:
    """One beam run (verify_solid_fibres.run_ancf) with its load, model name, Ē range over the
    middle half and per element, and the end face's mean displacement."""
    r = vsf.run_ancf(case, elements, tmp, model, load)
    E, u_mean, span = ancf_measures(case, elements, r.pop("q"))
    mid = E[round(MIDDLE[0] * elements):round(MIDDLE[1] * elements)]
    r.update(model=model_name(LOCKINGS[model], load), E=(float(mid.min()), float(mid.max())), u_mean=u_mean,
             span=span, fit0=float(r["u"][0]), E_elements=np.stack([E.min(axis=1), E.max(axis=1)], axis=1))
    return r


class SoftProbe(vsf.SolidProbe):
    """verify_solid_fibres.SolidProbe and, at the last level, the range of Ē over the solid's
    degree-2 quadrature points in the middle half, the end face's mean displacement ∫ u dA / A,
    and the span and quadratic-fit constant of u_x on the end face (``end_face_fit``)."""

    def __init__(self, case: vs.Case, sec, msh):
        super().__init__(case, sec, msh)
        from ancf_petsc.physics.element3363 import section_monomials
        self.m = section_monomials(*(vsf.SAMPLE_SCALE * sec.points).T)[0]

    def end_face_fit(self, u) -> tuple[float, float]:
        """u_x on the end section's sample points (the last station): the constant of its
        weighted least-squares fit by the 3363 section monomials, and its span max − min."""
        n = len(self.w)
        ux = u.eval(self.pts[-n:], self.cells[-n:])[:, 0]
        sw = np.sqrt(self.w)
        c = np.linalg.lstsq(sw[:, None] * self.m, sw * ux, rcond=None)[0]
        return float(c[0]), float(ux.max() - ux.min())

    def __call__(self, u, ds_end) -> dict:
        out = super().__call__(u, ds_end)
        if self.level == len(self.case.steps):
            import basix
            import ufl
            from dolfinx import fem
            pts, _ = basix.make_quadrature(basix.CellType.tetrahedron, 2)
            X = ufl.SpatialCoordinate(self.msh)
            F = ufl.Identity(3) + ufl.grad(u)
            a0 = vsf.fibre_field(self.case, X)
            cells = np.arange(self.msh.topology.index_map(3).size_local, dtype=np.int32)
            x = fem.Expression(X[0], pts).eval(cells).ravel()
            E = fem.Expression(ufl.dot(F * a0, F * a0) - 1.0, pts).eval(cells).ravel()
            inside = (x > MIDDLE[0] * self.case.length) & (x < MIDDLE[1] * self.case.length)
            out["E"] = (float(E[inside].min()), float(E[inside].max()))
            dA = ds_end(degree=6)
            A = fem.assemble_scalar(fem.form(1.0 * dA))
            out["u_mean"] = np.array([fem.assemble_scalar(fem.form(u[i] * dA)) / A for i in range(3)])
            out["fit0"], out["span"] = self.end_face_fit(u)
        return out


class ProfileProbe(SoftProbe):
    """SoftProbe that, at the last level, prints u_x along the end face's semi-axes (local y, z
    at 0, 0.095, ..., 0.95 of the semi-axis), at x = L/2 and x = L: the ``--profile`` diagnosis."""

    def __call__(self, u, ds_end) -> dict:
        out = super().__call__(u, ds_end)
        if self.level == len(self.case.steps):
            from dolfinx import geometry
            from ancf_petsc.physics.geometry import place
            tree = geometry.BoundingBoxTree(self.msh, 3, padding=0.1 * vsf.SECTION["semi_axes"][1])
            for axis, P in semi_axis_points().items():
                for xf in (0.5, 1.0 - 1e-12):
                    pts = place(np.full(len(P), xf * self.case.length), P, self.case.length, self.case.twist_deg,
                                self.case.twist_axis)
                    cells = np.array([vsf.owning_cell(self.msh, tree, p) for p in pts], dtype=np.int32)
                    print(f"[profile] solid x/L = {xf:.2f}, {axis}: " +
                          " ".join(f"{1e3 * v:.4f}" for v in u.eval(pts, cells)[:, 0]), flush=True)
        return out


def semi_axis_points() -> dict:
    """Local section points along the semi-axes y and z at 0, 0.095, ..., 0.95 of their length."""
    t = np.linspace(0.0, 0.95, 11)
    a, b = vsf.SECTION["semi_axes"]
    return {"y": np.stack([a * t, 0 * t], axis=1), "z": np.stack([0 * t, b * t], axis=1)}


def profile(case: vs.Case, h: float, tmp: str) -> None:
    """u_x [mm] along the end face's semi-axes: the 8-element traction beams (their quadratic
    section field) and the solid on the mesh of size h [mm]."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from ancf_petsc.physics.element3363 import section_monomials
    q0 = build_model(parse_config(vs.ancf_config(case, 8, 2, tmp), base_dir=vs.CONFIGS)).q0
    for model in LOCKINGS:
        q = vsf.run_ancf(case, 8, tmp, model, "traction_force")["q"]
        for axis, P in semi_axis_points().items():
            ux = section_monomials(P[:, 0], P[:, 1])[0] @ (q[-1, :, 0] - q0[-1, :, 0])
            print(f"[profile] {model_name(LOCKINGS[model], 'traction_force')} x/L = 1.00, {axis}: " +
                  " ".join(f"{1e3 * v:.4f}" for v in ux), flush=True)
    vs._import_stack()
    vsf.run_solid(case, vs.ancf_section(case), 1e-3 * h, 2, probe=ProfileProbe)


def rows_of(case: vs.Case, runs: list) -> list[dict]:
    """verify_solid_fibres' CSV rows with the Ē range, face mean and fit on each run's last end
    row, and (beam runs) one row per element (kind "strain": its Ē range)."""
    rows = []
    for r in runs:
        rr = vsf.csv_rows(case, "goh_twist", BULK_RATIO, [r])
        last = [d for d in rr if d["kind"] == "end"][-1]
        last.update(fibre_strain_min=f"{r['E'][0]:.5e}", fibre_strain_max=f"{r['E'][1]:.5e}",
                    ux_mean_m=f"{r['u_mean'][0]:.9e}", ux_fit0_m=f"{r['fit0']:.9e}", ux_span_m=f"{r['span']:.9e}")
        n = len(r.get("E_elements", []))
        rr += [{**{k: v for k, v in last.items() if k in vsf.COLUMNS[:9]}, "kind": "strain",
                "load_N": last["load_N"], "x_m": f"{(k + 0.5) * case.length / n:.6g}",
                "fibre_strain_min": f"{e[0]:.5e}", "fibre_strain_max": f"{e[1]:.5e}"}
               for k, e in enumerate(r.get("E_elements", []))]
        rows += rr
    return rows


def evaluate(rows: list[dict]) -> dict:
    """{"ref_u", "unc_u", "ref_rot", "unc_rot", "how", "beam": [run], "solid": [run]} from the CSV
    rows (Richardson of the solid meshes; errors of every run against it)."""
    runs: dict = {}
    for d in rows:
        r = runs.setdefault((d["model"], d["resolution"]), {"model": d["model"], "res": d["resolution"],
                                                             "dofs": int(d["dofs"]), "its": int(d["newton_its"]),
                                                             "along": [], "strain": []})
        if d["kind"] == "strain":
            r["strain"].append((float(d["fibre_strain_min"]), float(d["fibre_strain_max"])))
        elif d["kind"] == "end":
            r.update(u=np.array([float(d[f"u{c}_m"]) for c in "xyz"]), rot=float(d["rot_deg"]))
            if d.get("fibre_strain_min"):
                r["E"] = (float(d["fibre_strain_min"]), float(d["fibre_strain_max"]))
                r["ux_mean"] = float(d["ux_mean_m"])
                r["fit0"], r["span"] = (float(d[k]) if d.get(k) else math.nan for k in ("ux_fit0_m", "ux_span_m"))
        else:
            r["along"].append(float(d["rot_deg"]))
    solid = sorted((r for r in runs.values() if not r["model"].startswith("ANCF")), key=lambda r: r["dofs"])
    beam = [r for r in runs.values() if r["model"].startswith("ANCF")]
    ref_u, unc_u, how = vs.richardson(solid)
    ref_r, unc_r, how_r = vs.richardson([{"u": np.array([r["rot"]]), "dofs": r["dofs"]} for r in solid])
    ref_m, unc_m, how_m = vs.richardson([{"u": np.array([r["ux_mean"]]), "dofs": r["dofs"]} for r in solid])
    out = {"ref_u": ref_u, "unc_u": unc_u, "ref_rot": float(ref_r[0]), "unc_rot": unc_r, "how": how,
           "how_rot": how_r, "ref_mean": float(ref_m[0]), "unc_mean": unc_m, "how_mean": how_m,
           "beam": beam, "solid": solid}
    for r in beam + solid:
        r["du"] = r["u"][0] / ref_u[0] - 1.0
        r["dmean"] = r["ux_mean"] / out["ref_mean"] - 1.0
        r["err_u"] = float(np.linalg.norm(r["u"] - ref_u) / np.linalg.norm(ref_u))
        r["drot"] = r["rot"] / out["ref_rot"] - 1.0
    return out


def _e(r: dict) -> str:
    return f"{100 * r['E'][0]:+.2f} … {100 * r['E'][1]:+.2f}" if "E" in r else ""


def _mm(x: float) -> str:
    return "" if math.isnan(x) else f"{1e3 * x:.4f}"


def render_block(rows: list[dict]) -> str:
    """The docs block: every run against the solid's reference, then the rotation along x."""
    ev = evaluate(rows)
    mesh = ", ".join(r["res"].removeprefix("h ").removesuffix(" mm") for r in ev["solid"])
    m = MATERIAL
    lines = [f"Bar of the check above (ellipse 12 x 8 mm, L = {1e3 * vsf.LENGTH:g} mm, ψ = {vsf.TWIST:g}°, root "
             f"clamped, helical fibres); GOH set alex: μ = {m['mu'] / 1e3:g} kPa, k1 = {m['k1'] / 1e6:g} MPa, "
             f"k2 = {m['k2']:g}, κ = {m['kappa']:g}, K = {BULK_RATIO:g} μ; end force {FORCE:g} N in "
             f"{len(vsf.STEPS)} levels. Solid: P2 tetrahedra, h = {mesh} mm, uniform dead end traction; reference: "
             f"u {ev['how']}; rotation {ev['how_rot']} (uncertainty: distance from the finest mesh, "
             f"u {100 * ev['unc_u']:.2f} %, rotation {100 * ev['unc_rot']:.2f} %, face mean "
             f"{100 * ev['unc_mean']:.2f} %; face mean: {ev['how_mean']}). u_x: the end-section centroid's; face mean: "
             "∫ u_x dA / A over the end face (ANCF: Σ m̄_k Δq_k); end face u_x sampled at the section rule's points x "
             f"{vsf.SAMPLE_SCALE:g}: span max − min, and the constant of its weighted least-squares fit by the 3363 "
             "section monomials 1, y, z, y²/2, z²/2, yz (ANCF: r_x itself). Ē = I4 − 1 over the middle half "
             "L/4 < X < 3L/4.", "",
             "| model | resolution | Newton its | u_x [mm] | u_x / solid − 1 | \\|u − u_ref\\| / \\|u_ref\\| | "
             "face-mean u_x [mm] | / solid − 1 | rotation [°] | rotation / solid − 1 | Ē range, middle half [%] | "
             "end face u_x: span [mm] | quadratic-fit constant [mm] |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
             f"| solid, reference | | | {1e3 * ev['ref_u'][0]:.4f} | | | {1e3 * ev['ref_mean']:.4f} | | "
             f"{ev['ref_rot']:+.3f} | | | | |"]
    for r in ev["solid"] + sorted(ev["beam"], key=lambda r: (r["model"], r["dofs"])):
        lines.append(f"| {r['model']} | {r['res']} | {r['its']} | {1e3 * r['u'][0]:.4f} | {100 * r['du']:+.2f} % | "
                     f"{100 * r['err_u']:.2f} % | {1e3 * r['ux_mean']:.4f} | {100 * r['dmean']:+.2f} % | "
                     f"{r['rot']:+.3f} | {100 * r['drot']:+.2f} % | {_e(r)} | {_mm(r['span'])} | {_mm(r['fit0'])} |")
    fine = max(ev["beam"], key=lambda r: r["dofs"])["res"]
    cols = sorted((r for r in ev["beam"] if r["res"] == fine), key=lambda r: r["model"]) + ev["solid"][-1:]
    lines += ["", f"Section rotation [°] along the bar at {FORCE:g} N (ANCF {fine}; finest solid):", "",
              "| x/L | " + " | ".join(r["model"].removeprefix("ANCF, ") for r in cols) + " |",
              "|---:|" + "---:|" * len(cols)]
    for i in range(vsf.STATIONS):
        lines.append(f"| {(i + 1) / vsf.STATIONS:.3f} | " + " | ".join(f"{r['along'][i]:+.3f}" for r in cols) + " |")
    cols = cols[:-1]
    lines += ["", f"Ē range [%] over each element's Gauss points at {FORCE:g} N (ANCF {fine}):", "",
              "| element centre x/L | " + " | ".join(r["model"].removeprefix("ANCF, ") for r in cols) + " |",
              "|---:|" + "---:|" * len(cols)]
    n = len(cols[0]["strain"])
    for i in range(n):
        lines.append(f"| {(i + 0.5) / n:.4f} | " + " | ".join(
            f"{100 * r['strain'][i][0]:+.2f} … {100 * r['strain'][i][1]:+.2f}" for r in cols) + " |")
    return "\n".join(lines)


def replace_block(text: str, block: str) -> str:
    """``text`` with the marked block ``solid_soft_matrix`` replaced by ``block``."""
    return vsf.replace_block(text, block, BLOCK, WRITER)


def write_doc(doc: str, rows: list[dict]) -> None:
    vsf.write_block(doc, render_block(rows), BLOCK, WRITER)


def beam_runs(case: vs.Case, tmp: str) -> list[dict]:
    return [run_beam(case, n, tmp, model, load) for load in LOADS for model in LOCKINGS for n in ELEMENTS]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join(vsf.ROOT, "docs"), help="directory of the CSV")
    ap.add_argument("--doc", default=vsf.DOC, help="the page with the marked block (default docs/fibres.md)")
    ap.add_argument("--replot", action="store_true", help="the block from <out>/solid_soft_matrix.csv")
    ap.add_argument("--ancf-only", action="store_true", help="ANCF again, the CSV's solid rows kept (no dolfinx)")
    ap.add_argument("--force", type=float, default=FORCE, help="end force [N] (other than 200: beam only)")
    ap.add_argument("--beam-only", action="store_true", help="the beam runs, printed; nothing written")
    ap.add_argument("--more-solid", action="store_true", help="keep the CSV's rows, add solid meshes --h")
    ap.add_argument("--profile", type=float, metavar="H",
                    help="print u_x along the end face's semi-axes: beams and the solid of mesh size H [mm]")
    ap.add_argument("--quad-degree", type=int, default=2, help="solid quadrature degree (default 2)")
    ap.add_argument("--h", type=float, nargs="+", default=[1e3 * h for h in H], help="solid mesh sizes [mm]")
    args = ap.parse_args(argv)
    path = os.path.join(args.out, CSV_NAME)
    if args.replot:
        write_doc(args.doc, vsf.read_csv(path))
        return 0
    case = make_case(args.force)
    if args.profile:
        with tempfile.TemporaryDirectory(prefix="verify_solid_soft_") as tmp:
            profile(case, args.profile, tmp)
        return 0
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="verify_solid_soft_") as tmp:
        beams = beam_runs(case, tmp)
        for r in beams:
            print(f"[ANCF] {r['model']} {r['res']}: {r['its']} its, u_x {1e3 * r['u'][0]:.4f} mm, "
                  f"rotation {r['rot']:+.3f} deg, Ē {_e(r)} %, face-mean u_x {1e3 * r['u_mean'][0]:.4f} mm", flush=True)
        if args.beam_only or args.force != FORCE:
            return 0
        if args.more_solid:
            vs._import_stack()
            sec = vs.ancf_section(case)
            solids = [vsf.run_solid(case, sec, 1e-3 * h, args.quad_degree, probe=SoftProbe) for h in args.h]
            rows = vsf.read_csv(path) + rows_of(case, solids)
        elif args.ancf_only:
            rows = rows_of(case, beams) + [d for d in vsf.read_csv(path) if not d["model"].startswith("ANCF")]
        else:
            vs._import_stack()
            sec, solids = vs.ancf_section(case), []
            for h in args.h:
                solids.append(vsf.run_solid(case, sec, 1e-3 * h, args.quad_degree, probe=SoftProbe))
                r = solids[-1]
                print(f"[solid] {r['res']}: {r['dofs']} DOFs, {r['wall']:.1f} s, {r['its']} its, u_x "
                      f"{1e3 * r['u'][0]:.4f} mm, rotation {r['rot']:+.3f} deg, Ē {_e(r)} %, face-mean u_x "
                      f"{1e3 * r['u_mean'][0]:.4f} mm, fibre field "
                      f"{r['field_err']:.1e}", flush=True)
            rows = rows_of(case, beams + solids)
    vsf.write_csv(path, rows, vsf.COLUMNS + EXTRA)
    write_doc(args.doc, rows)
    print(render_block(rows))
    print(f"\n[verify-solid-soft-matrix] {time.perf_counter() - t_start:.0f} s; wrote {path} and the block "
          f"{BLOCK} of {args.doc}")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except vs.SolidError as exc:
        print(f"verify_solid_soft_matrix: {exc}", file=sys.stderr)
        sys.exit(1)
    except Exception as exc:   # a failed solve or mesh: one line, non-zero
        print(f"verify_solid_soft_matrix: {type(exc).__name__}: {exc}", file=sys.stderr)
        sys.exit(1)
