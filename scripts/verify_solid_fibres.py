#!/usr/bin/env python3
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
8, 16 elements with the volumetric term on a degree-2 section rule (``reduced_volumetric_rule``: a
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
import contextlib
import copy
import csv
import math
import os
import sys
import tempfile
import time
from dataclasses import dataclass

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, ROOT)
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402

import verify_solid as vs  # noqa: E402

CSV_NAME = "solid_fibres.csv"
DOC = os.path.join(ROOT, "docs", "fibres.md")
FIGURE = os.path.join("figures", "solid_fibres.png")
BLOCK = "solid_fibres"

SECTION = {"shape": "ellipse", "semi_axes": [0.006, 0.004], "cubature_degree": 6}
MU = 1.0e6
FIBRES = {"k1": 2.0e6, "k2": 5.0, "kappa": 0.0}
LENGTH, TWIST, FORCE = 0.05, 180.0, 20.0
STEPS = (0.25, 0.5, 0.75, 1.0)
ELEMENTS = (4, 8, 16)
STATIONS = 8                       # rotation along x at x = k L / 8 (nodes of every ANCF mesh)
OUTSIDE_TOL = 0.03                 # largest violation of a point's reference coordinates accepted
SAMPLE_SCALE = 0.95                # solid sections sampled at the section rule's points x 0.95
H = (2.83e-3, 2e-3, 1.41e-3)       # solid mesh sizes [m], coarse to fine
H_INCOMPRESSIBLE = (1e-3,)         # one more at the largest K/mu (P2 tets converge slowly there)
H_QUICK = (4e-3, 2.83e-3, 2e-3)
#: matrix bulk modulus over mu: the tests' nearly incompressible matrix (nu = 0.49), the Achilles
#: columns' (0.86 GPa / 103.1 MPa, nu = 0.44) and a compressible one (nu = 0.3)
BULK_RATIOS = (50.0, 8.34, 2.1667)
#: section rule degree of the volumetric term in the locking diagnosis (``reduced_volumetric_rule``)
VOLUMETRIC_DEGREE = 2
ANCF, ANCF_VOL = "ANCF", f"ANCF, K/2 (J-1)^2 on a degree-{VOLUMETRIC_DEGREE} section rule"
#: the remedy: ``locking: mixed`` (ancf_petsc/physics/mixed.py)
ANCF_MIXED = "ANCF, locking: mixed"
ANCF_MODELS = (ANCF, ANCF_VOL, ANCF_MIXED)


@dataclass
class Law:
    """One material of the study: its key, label and the ANCF material dict (matrix K/mu aside)."""
    key: str
    label: str
    material: dict


LAWS = [Law("goh_twist", "GOH, helical fibres (along the pretwist's material lines)",
            {"model": "goh", "mu": MU, **FIBRES, "fibres": {"follow": "twist"}}),
        Law("goh_axis", "GOH, fibres along x (control)",
            {"model": "goh", "mu": MU, **FIBRES, "fibres": {"follow": "axis"}}),
        Law("neo_hookean", "neo-Hookean matrix alone (control)", {"model": "neo-hookean", "mu": MU})]


def case_key(law: str, ratio: float) -> str:
    return f"{law}_K{ratio:g}"


def make_case(law: Law, ratio: float, quick: bool = False) -> vs.Case:
    """The bar of ``law`` with bulk modulus ratio * mu as a verify_solid Case (section centred
    on the twist axis, fibres with the matrix)."""
    mat = {**copy.deepcopy(law.material), "bulk_modulus": ratio * MU}
    h = H_QUICK if quick else (H + H_INCOMPRESSIBLE if ratio == max(BULK_RATIOS) else H)
    return vs.Case(case_key(law.key, ratio), law.label, copy.deepcopy(SECTION), mat, (FORCE, 0.0, 0.0),
                   h=h, h_quick=H_QUICK, length=LENGTH, twist_deg=TWIST,
                   twist_axis=(0.0, 0.0), steps=STEPS)


def rim_inclination_deg() -> float:
    """Fibre inclination atan(ρ ψ / L) at the end of the section's major semi-axis."""
    return math.degrees(math.atan(max(SECTION["semi_axes"]) * math.radians(TWIST) / LENGTH))


# --------------------------------------------------------------------------------------------
# ANCF
# --------------------------------------------------------------------------------------------
def polar_angle_deg(M: np.ndarray) -> float:
    """Rotation angle of the polar decomposition of a 2x2 M, positive about +x."""
    return math.degrees(math.atan2(M[1, 0] - M[0, 1], M[0, 0] + M[1, 1]))


def section_rotation_deg(q: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """Rotation about x of the sections at nodes (n, 6, 3): polar angle of A A0⁻¹, A = in-plane
    part of [r_y r_z]."""
    A, A0 = q[:, 1:3, 1:3].transpose(0, 2, 1), q0[:, 1:3, 1:3].transpose(0, 2, 1)
    return np.array([polar_angle_deg(M) for M in np.matmul(A, np.linalg.inv(A0))])


def ancf_volumetric_share(raw: dict, q: np.ndarray) -> float:
    """Share of the volumetric energy K/2 (J − 1)² (``locking: mixed``: K/2 (θ − 1)², θ the
    projected dilatation) in the strain energy at nodal vectors q, over the beam's own Gauss points."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from ancf_petsc.physics.kernels import deformation_gradient
    model = build_model(parse_config(raw, base_dir=vs.CONFIGS))
    b = model.beams[0]
    local = np.arange(b.n_elements)
    G, w, material = model.element_data(b, local)[0]
    F = deformation_gradient(q[b.connectivity][:, :, list(b.vectors)].reshape(len(local), -1, 3), G)
    J = material.dilatation(F) if hasattr(material, "dilatation") else np.linalg.det(F)
    return float(np.sum(w * 0.5 * raw["beams"][0]["material"]["bulk_modulus"] * (J - 1.0) ** 2)
                 / np.sum(w * material.energy(F)))


@contextlib.contextmanager
def reduced_volumetric_rule(degree: int = VOLUMETRIC_DEGREE):
    """Locking diagnosis, not a model option: while active, every beam's strain energy is its
    law without the volumetric term on the full rule plus K/2 (J − 1)² on the elliptic section
    rule of ``degree`` (same axial points): selective reduced integration over the section.
    It relaxes the pointwise J = 1 constraints the quadratic section field cannot meet."""
    from ancf_petsc.model.beams import Beam
    from ancf_petsc.physics import element3363 as el
    from ancf_petsc.physics.cubature import ellipse_rule, gauss_legendre
    from ancf_petsc.physics.goh import GOH
    from ancf_petsc.physics.materials import NeoHookean
    full = Beam.parts

    def parts(beam):
        m = beam.material
        pts, w = ellipse_rule(*beam.section.shape_params["semi_axes"], degree)
        xa, wa = gauss_legendre(beam.axial_points)
        _, dN = el.shape_functions(*el.tensor_points(xa, pts), beam.vectors)
        matrix = GOH(m.mu, 0.0, m.k1, m.k2, m.kappa, m.fibres).with_directions(beam.fibres) \
            if isinstance(m, GOH) else NeoHookean(m.mu, 0.0)
        return [(beam.dN, beam.wq, matrix),
                (dN, np.repeat(wa, len(w)) * np.tile(w, len(xa)), NeoHookean(0.0, m.K))]

    Beam.parts = parts
    try:
        yield
    finally:
        Beam.parts = full


def run_ancf(case: vs.Case, elements: int, tmp: str, model: str = ANCF, load: str = "traction_force") -> dict:
    """ANCF 3363, 2 axial Gauss points: end-centroid displacement and end-section rotation at
    every level; at the last, the rotation at the stations and the volumetric energy share
    (``model`` ANCF_VOL: under ``reduced_volumetric_rule``, no share; ANCF_MIXED: ``locking: mixed``).
    ``load``: the end load's config key, ``traction_force`` (the solid's) or ``force`` (on r)."""
    with reduced_volumetric_rule() if model == ANCF_VOL else contextlib.nullcontext():
        return _run_ancf(case, elements, tmp, model, load)


def _run_ancf(case: vs.Case, elements: int, tmp: str, model: str, load: str) -> dict:
    import h5py
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    out_dir = os.path.join(tmp, f"{case.key}_{elements}_{ANCF_MODELS.index(model):d}_{load}")
    raw = vs.ancf_config(case, elements, 2, out_dir)
    raw["loads"][0] = {"beam": "bar", "node": "last", load: list(case.force)}
    if model == ANCF_MIXED:
        raw["beams"][0]["locking"] = "mixed"
    t0 = time.perf_counter()
    res = run_model(parse_config(raw, base_dir=vs.CONFIGS), log=lambda *_: None)
    wall = time.perf_counter() - t0
    if res.status != "completed":
        raise vs.SolidError(f"ANCF {case.key} {elements} el. failed: {res.message}")
    with h5py.File(os.path.join(out_dir, "results.h5"), "r") as h5:
        q0 = h5["model/reference_nodal_vectors"][:]
        x = h5["model/beams/bar/x_nodes"][:]
        qs = [h5[f"steps/step_{k:04d}/nodal_vectors"][:] for k in range(1, len(case.steps) + 1)]
    every = (len(x) - 1) // STATIONS
    levels = [{"load": lvl * case.force[0], "u": q[-1, 0] - q0[-1, 0], "rot": section_rotation_deg(q[-1:], q0[-1:])[0]}
              for lvl, q in zip(case.steps, qs)]
    levels[-1]["along"] = section_rotation_deg(qs[-1][every::every], q0[every::every])
    if model != ANCF_VOL:
        levels[-1]["vol_share"] = ancf_volumetric_share(raw, qs[-1])
    return {**levels[-1], "model": model, "res": f"{elements} el.",
            "dofs": int(res.summary["dofs"]),
            "its": int(sum(st["iterations"] for st in res.summary["steps"])), "wall": wall,
            "levels": levels, "field_err": float("nan"), "q": qs[-1]}


# --------------------------------------------------------------------------------------------
# Solid
# --------------------------------------------------------------------------------------------
def fibre_field(case: vs.Case, X):
    """UFL unit fibre direction at reference position X: the material line's tangent (twist)
    or x (axis)."""
    import ufl
    if case.material["fibres"]["follow"] == "axis":
        return ufl.as_vector([1.0, 0.0, 0.0])
    tau = math.radians(case.twist_deg) / case.length
    ay, az = case.twist_axis
    t = ufl.as_vector([1.0, -tau * (X[2] - az), tau * (X[1] - ay)])
    return t / ufl.sqrt(ufl.dot(t, t))


def goh_energy(case: vs.Case, msh, F):
    """The energy density of ``case`` in UFL: neo-Hookean, or GOH = neo-Hookean +
    k1/(2 k2)(exp(k2 Ē²) − 1) for Ē ≥ 0 (the tension side's tangent at Ē = 0, as the beam's)."""
    import ufl
    m = case.material
    if m["model"] != "goh":
        return vs.neo_hookean(case, msh, F)
    a0 = fibre_field(case, ufl.SpatialCoordinate(msh))
    C = F.T * F
    kappa = m["kappa"]
    E = kappa * (ufl.tr(C) - 3) + (1 - 3 * kappa) * (ufl.dot(a0, C * a0) - 1)
    Ep = ufl.conditional(ufl.ge(E, 0.0), E, 0.0)
    return vs.neo_hookean(case, msh, F) + m["k1"] / (2 * m["k2"]) * (ufl.exp(m["k2"] * Ep ** 2) - 1)


def check_fibre_field(case: vs.Case, sec, msh) -> float:
    """Largest |a0_solid − a0_ANCF| over the solid's quadrature points (degree 2): the UFL field
    against ancf_petsc.physics.fibres.fibre_directions at the same reference points."""
    import basix
    import ufl
    from dolfinx import fem
    from ancf_petsc.physics.fibres import fibre_directions
    from ancf_petsc.physics.geometry import rotation, twist_angle
    pts, _ = basix.make_quadrature(basix.CellType.tetrahedron, 2)
    X = ufl.SpatialCoordinate(msh)
    cells = np.arange(msh.topology.index_map(3).size_local, dtype=np.int32)
    x = fem.Expression(X, pts).eval(cells).reshape(-1, 3)
    a0 = fibre_field(case, X)                # a constant (axis) has no mesh to evaluate on
    a = fem.Expression(a0, pts).eval(cells).reshape(-1, 3) if a0.ufl_domain() else np.tile([1.0, 0.0, 0.0], (len(x), 1))
    axis = np.asarray(case.twist_axis)
    P = axis + np.einsum("nji,nj->ni", rotation(twist_angle(x[:, 0], case.length, case.twist_deg)),
                         x[:, 1:] - axis)                                     # back to x = 0
    f = case.material["fibres"]
    ref = fibre_directions(x[:, 0], P, case.length, case.twist_deg, axis, sec.centroid, f["follow"])[0]
    return float(np.abs(a - ref).max())


def fitted_rotation_deg(X: np.ndarray, x: np.ndarray, w: np.ndarray) -> float:
    """Rotation of the weighted least-squares linear fit x ≈ x̄ + M (X − X̄) of in-plane points."""
    s = X - w @ X / w.sum()
    d = x - w @ x / w.sum()
    return polar_angle_deg((w[:, None] * d).T @ s @ np.linalg.inv((w[:, None] * s).T @ s))


def owning_cell(msh, tree, p: np.ndarray) -> int:
    """The cell of the curved (P2) mesh that holds point p: of the cells whose bounding box holds
    it (padded: the boxes are the vertices'), the one whose pull-back of p is least outside the
    reference tetrahedron (dolfinx 0.5's convex-hull test can fail to converge for curved cells).
    On the coarsest twisted meshes a point can be up to ~1 % of a cell outside every cell's
    exact P2 map (the map of a strongly curved cell is not one-to-one near its faces): it is
    then evaluated in the nearest cell (the P2 field continued by 1 %)."""
    from dolfinx import geometry
    best, cell = math.inf, -1
    for c in geometry.compute_collisions(tree, p[None, :]).links(0):
        nodes = msh.geometry.x[msh.geometry.dofmap.links(c)]
        try:
            X = msh.geometry.cmap.pull_back(p[None, :], nodes)[0]
        except RuntimeError:
            continue
        outside = max(0.0, -X.min(), X.sum() - 1.0)
        if outside < best:
            best, cell = outside, int(c)
    if cell < 0 or best > OUTSIDE_TOL:
        raise vs.SolidError(f"point {p} not found in the solid mesh (closest: {best:.3g} outside a cell)")
    return cell


class SolidProbe:
    """What the solid reports at each level: the end face's rotation (integrals over the face,
    quadrature degree 6), at the last level also the rotation of the sections x = k L / 8
    (fit over the ANCF section rule's points scaled by 0.95 about the centroid, evaluated in the
    mesh) and the volumetric share."""

    def __init__(self, case: vs.Case, sec, msh):
        from dolfinx import geometry
        from ancf_petsc.physics.geometry import place
        self.case, self.msh, self.w = case, msh, sec.weights
        xs = np.repeat(np.arange(1, STATIONS + 1) * case.length / STATIONS, len(sec.weights))
        xs = np.minimum(xs, case.length * (1 - 1e-12))
        inner = SAMPLE_SCALE * sec.points      # the rim points may lie outside a coarse P2 boundary
        self.pts = place(xs, sec.centroid + np.tile(inner, (STATIONS, 1)), case.length,
                         case.twist_deg, case.twist_axis)
        tree = geometry.BoundingBoxTree(msh, 3, padding=0.1 * SECTION["semi_axes"][1])
        self.cells = np.array([owning_cell(msh, tree, p) for p in self.pts], dtype=np.int32)
        self.level = 0

    def __call__(self, u, ds_end) -> dict:
        import ufl
        from dolfinx import fem
        dA = ds_end(degree=6)
        X = ufl.SpatialCoordinate(self.msh)
        x = X + u

        def integral(e):
            return fem.assemble_scalar(fem.form(e * dA))

        A = integral(1.0)
        Xc = [integral(X[i]) / A for i in (1, 2)]
        xc = [integral(x[i]) / A for i in (1, 2)]
        s = [X[1] - Xc[0], X[2] - Xc[1]]
        S = np.array([[integral(si * sj) for sj in s] for si in s])
        T = np.array([[integral((x[i + 1] - xc[i]) * sj) for sj in s] for i in range(2)])
        out = {"rot": polar_angle_deg(T @ np.linalg.inv(S))}
        self.level += 1
        if self.level == len(self.case.steps):
            d = u.eval(self.pts, self.cells)
            n = len(self.w)
            out["along"] = np.array([fitted_rotation_deg(self.pts[k * n:(k + 1) * n, 1:],
                                                         self.pts[k * n:(k + 1) * n, 1:] + d[k * n:(k + 1) * n, 1:],
                                                         self.w) for k in range(STATIONS)])
            F = ufl.Identity(3) + ufl.grad(u)
            dx = ufl.Measure("dx", domain=self.msh, metadata={"quadrature_degree": 4})
            vol = fem.assemble_scalar(fem.form(0.5 * self.case.material["bulk_modulus"] * (ufl.det(F) - 1) ** 2 * dx))
            out["vol_share"] = vol / fem.assemble_scalar(fem.form(goh_energy(self.case, self.msh, F) * dx))
        return out


def run_solid(case: vs.Case, sec, h: float, quad_degree: int, probe=SolidProbe) -> dict:
    """Mesh, check the fibre field, solve; end displacement and rotation at every level (and
    what ``probe(case, sec, msh)``, a SolidProbe, reports)."""
    t0 = time.perf_counter()
    msh = vs.solid_mesh(case, sec, h)
    t_mesh = time.perf_counter() - t0
    field_err = check_fibre_field(case, sec, msh) if case.material["model"] == "goh" else float("nan")
    t0 = time.perf_counter()
    out = vs.solve_solid(case, sec, msh, quad_degree, energy=goh_energy, post=probe(case, sec, msh))
    for lv in out["levels"]:
        lv["load"] *= case.force[0]
    out.update(model="solid P2 tet", res=f"h {h * 1e3:.2f} mm", wall=time.perf_counter() - t0,
               mesh=t_mesh, field_err=field_err)
    return out


# --------------------------------------------------------------------------------------------
# CSV: one row per run and level (kind "end": the end section) and, at the last level, per
# station x = k L / 8 (kind "along": the section rotation there)
# --------------------------------------------------------------------------------------------
COLUMNS = ["case", "law", "bulk_ratio", "model", "resolution", "dofs", "wall_s", "solid_mesh_s",
           "newton_its", "kind", "load_N", "x_m", "ux_m", "uy_m", "uz_m", "rot_deg", "vol_share",
           "fibre_field_err"]


def csv_rows(case: vs.Case, law: str, ratio: float, runs: list) -> list[dict]:
    """The CSV rows of one case's runs."""
    out = []
    for r in runs:
        base = {"case": case.key, "law": law, "bulk_ratio": f"{ratio:g}", "model": r["model"],
                "resolution": r["res"], "dofs": r["dofs"], "wall_s": f"{r['wall']:.4f}",
                "solid_mesh_s": "" if math.isnan(r.get("mesh", math.nan)) else f"{r['mesh']:.4f}",
                "newton_its": r["its"],
                "fibre_field_err": "" if math.isnan(r["field_err"]) else f"{r['field_err']:.3e}"}
        for lv in r["levels"]:
            out.append({**base, "kind": "end", "load_N": f"{lv['load']:g}", "x_m": f"{case.length:g}",
                        **{f"u{c}_m": f"{v:.9e}" for c, v in zip("xyz", lv["u"])},
                        "rot_deg": f"{lv['rot']:.7f}",
                        "vol_share": f"{lv['vol_share']:.5e}" if "vol_share" in lv else ""})
        for k, rot in enumerate(r["levels"][-1]["along"]):
            out.append({**base, "kind": "along", "load_N": f"{r['levels'][-1]['load']:g}",
                        "x_m": f"{(k + 1) * case.length / STATIONS:.6g}", "ux_m": "", "uy_m": "",
                        "uz_m": "", "rot_deg": f"{rot:.7f}", "vol_share": ""})
    return out


def write_csv(path: str, rows: list[dict], columns: list[str] = COLUMNS) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=columns)
        w.writeheader()
        w.writerows(rows)


def read_csv(path: str) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


# --------------------------------------------------------------------------------------------
# Evaluation (from the CSV rows only, so that the committed CSV regenerates the docs)
# --------------------------------------------------------------------------------------------
def runs_of(rows: list[dict]) -> dict:
    """{case: {"law", "ratio", "ancf": [run], "solid": [run coarse to fine]}}; a run holds its
    final end displacement u, rotation, volumetric share, rotation along x and per-level values."""
    out: dict = {}
    for d in rows:
        c = out.setdefault(d["case"], {"law": d["law"], "ratio": float(d["bulk_ratio"]), "runs": {}})
        r = c["runs"].setdefault((d["model"], d["resolution"]), {
            "model": d["model"], "res": d["resolution"], "dofs": int(d["dofs"]), "wall": float(d["wall_s"]),
            "its": int(d["newton_its"]), "field_err": float(d["fibre_field_err"] or "nan"),
            "loads": [], "rots": [], "along": [], "x": []})
        if d["kind"] == "end":
            r["loads"].append(float(d["load_N"]))
            r["rots"].append(float(d["rot_deg"]))
            r["u"] = np.array([float(d[f"u{c}_m"]) for c in "xyz"])
            r["rot"] = float(d["rot_deg"])
            if d["vol_share"]:
                r["vol_share"] = float(d["vol_share"])
        else:
            r["x"].append(float(d["x_m"]))
            r["along"].append(float(d["rot_deg"]))
    for c in out.values():
        runs = list(c.pop("runs").values())
        c["ancf"] = [r for r in runs if r["model"] == ANCF]
        c["vol"] = [r for r in runs if r["model"] == ANCF_VOL]
        c["mixed"] = [r for r in runs if r["model"] == ANCF_MIXED]
        c["solid"] = sorted((r for r in runs if r["model"] not in ANCF_MODELS), key=lambda r: r["dofs"])
        ref_u, unc_u, _ = vs.richardson(c["solid"])
        ref_r, unc_r, _ = vs.richardson([{"u": np.array([r["rot"]]), "dofs": r["dofs"]} for r in c["solid"]])
        c.update(ref_u=ref_u, unc_u=unc_u, ref_rot=float(ref_r[0]), unc_rot=unc_r)
        for r in runs:
            r["err_u"] = float(np.linalg.norm(r["u"] - ref_u) / np.linalg.norm(ref_u))
            r["err_rot"] = abs(r["rot"] - c["ref_rot"]) / abs(c["ref_rot"])
    return out


def _pct(x: float) -> str:
    return f"{100 * x:.2f} %"


def _ancf(c: dict, elements: int, kind: str = "ancf") -> dict:
    return next(r for r in c[kind] if r["res"] == f"{elements} el.")


def render_block(rows: list[dict]) -> str:
    """The docs/fibres.md block: summary of every case, the main cases' runs, rotation along x."""
    cases = runs_of(rows)
    fine = max(int(r["res"].split()[0]) for c in cases.values() for r in c["ancf"])
    mid = fine // 2
    first = next(iter(cases.values()))
    by_ratio: dict = {}
    for c in cases.values():
        by_ratio.setdefault(", ".join(r["res"].removeprefix("h ").removesuffix(" mm") for r in c["solid"]),
                            []).append(f"{c['ratio']:g}")
    meshes = "; ".join(f"h = {h} mm at K/μ = {', '.join(sorted(set(rs), key=float, reverse=True))}"
                       for h, rs in by_ratio.items())
    lines = [f"Bar: ellipse {2e3 * SECTION['semi_axes'][0]:g} x {2e3 * SECTION['semi_axes'][1]:g} mm centred "
             f"on the twist axis, L = {1e3 * LENGTH:g} mm, ψ = {TWIST:g}°, root clamped, end traction "
             f"{FORCE:g} N along x in {len(STEPS)} levels; fibre inclination at the rim of the major axis "
             f"atan(ρψ/L) = {rim_inclination_deg():.1f}°. Matrix μ = {MU / 1e6:g} MPa; fibres k1 = "
             f"{FIBRES['k1'] / 1e6:g} MPa, k2 = {FIBRES['k2']:g}, κ = {FIBRES['kappa']:g}. ANCF: 3363, 2 axial "
             f"Gauss points, {', '.join(r['res'].split()[0] for r in first['ancf'])} elements. Solid: P2 "
             f"tetrahedra, {meshes}; reference = Richardson extrapolation "
             "of the finest three meshes (uncertainty: its distance from the finest). Errors against the reference; "
             "rotation = end-section rotation about x (negative: untwist).", "",
             f"| law | K/μ | solid: u_x [mm] | solid: rotation [°] | ANCF {mid} el.: u / rotation error | "
             f"ANCF {fine} el.: u / rotation error | **locking: mixed**, {mid} el.: u / rotation error | "
             f"**locking: mixed**, {fine} el.: u / rotation error | rotation ANCF / solid − 1, {fine} el.: "
             f"none / mixed | volumetric share of the energy, {fine} el.: none / mixed / finest solid | "
             f"diagnosis: ANCF {fine} el. with K/2 (J−1)² on a degree-{VOLUMETRIC_DEGREE} section rule: "
             "u / rotation error |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for c in cases.values():
        a, b = _ancf(c, mid), _ancf(c, fine)
        ma, mb = _ancf(c, mid, "mixed"), _ancf(c, fine, "mixed")
        vb = _ancf(c, fine, "vol")
        lines.append(f"| {c['law']} | {c['ratio']:g} | {1e3 * c['ref_u'][0]:.4f} (± {_pct(c['unc_u'])}) | "
                     f"{c['ref_rot']:+.3f} (± {_pct(c['unc_rot'])}) | {_pct(a['err_u'])} / {_pct(a['err_rot'])} | "
                     f"{_pct(b['err_u'])} / {_pct(b['err_rot'])} | "
                     f"{_pct(ma['err_u'])} / {_pct(ma['err_rot'])} | {_pct(mb['err_u'])} / {_pct(mb['err_rot'])} | "
                     f"{100 * (b['rot'] / c['ref_rot'] - 1):+.2f} % / {100 * (mb['rot'] / c['ref_rot'] - 1):+.2f} % | "
                     f"{100 * b['vol_share']:.2f} % / {100 * mb['vol_share']:.2f} % / "
                     f"{100 * c['solid'][-1]['vol_share']:.2f} % | {_pct(vb['err_u'])} / {_pct(vb['err_rot'])} |")
    for key, c in cases.items():
        if c["law"] != "goh_twist":
            continue
        lines += ["", f"Runs of {key} (GOH, helical fibres, K/μ = {c['ratio']:g}), end values at {FORCE:g} N:", "",
                  "| model | resolution | DOFs | Newton its | u_x [mm] | rotation [°] | u error | rotation error | "
                  "fibre field vs ANCF's |", "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
        for r in c["ancf"] + c["mixed"] + c["vol"] + c["solid"]:
            fe = "" if math.isnan(r["field_err"]) else f"{r['field_err']:.1e}"
            lines.append(f"| {r['model']} | {r['res']} | {r['dofs']} | {r['its']} | {1e3 * r['u'][0]:.4f} | "
                         f"{r['rot']:+.4f} | {_pct(r['err_u'])} | {_pct(r['err_rot'])} | {fe} |")
    ref = [k for k, c in cases.items() if c["ratio"] == max(BULK_RATIOS)]
    lines += ["", f"Section rotation [°] along the bar at {FORCE:g} N, K/μ = {max(BULK_RATIOS):g}: ANCF {fine} el. "
              "(r_y, r_z at the node) without and with `locking: mixed` / finest solid (least-squares fit over "
              "the section rule's points):", "",
              "| x/L | " + " | ".join(f"{cases[k]['law']} ANCF | mixed | solid" for k in ref) + " |",
              "|---:|" + "---:|---:|---:|" * len(ref)]
    for i in range(STATIONS):
        cells = []
        for k in ref:
            a, m, s = _ancf(cases[k], fine), _ancf(cases[k], fine, "mixed"), cases[k]["solid"][-1]
            cells.append(f"{a['along'][i]:+.3f} | {m['along'][i]:+.3f} | {s['along'][i]:+.3f}")
        lines.append(f"| {(i + 1) / STATIONS:.3f} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def replace_block(text: str, block: str, name: str = BLOCK, writer: str = "scripts/verify_solid_fibres.py") -> str:
    """``text`` with the marked block ``name`` (written by the script ``writer``) replaced by
    ``block``."""
    begin = f"<!-- {name}: begin (written by {writer}; do not edit) -->"
    end = f"<!-- {name}: end -->"
    i, j = text.find(begin), text.find(end)
    if i < 0 or j < i:
        raise vs.SolidError(f"{DOC}: the markers of block {name} are missing")
    return text[:i + len(begin)] + "\n" + block + "\n" + text[j:]


def write_block(doc: str, block: str, name: str = BLOCK, writer: str = "scripts/verify_solid_fibres.py") -> None:
    """The page ``doc`` with its block ``name`` replaced (``replace_block``); the page is only
    opened for writing once the new text stands (missing markers leave it as it was)."""
    with open(doc, encoding="utf-8") as fh:
        text = replace_block(fh.read(), block, name, writer)
    with open(doc, "w", encoding="utf-8") as fh:
        fh.write(text)


def plot(path: str, rows: list[dict]) -> None:
    """(a) end rotation against load, (b) rotation along x at the last level, both at the largest
    K/μ, ANCF (lines) and finest solid (markers); (c) ANCF's rotation error against K/μ."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cases = runs_of(rows)
    fine = max(int(r["res"].split()[0]) for c in cases.values() for r in c["ancf"])
    fig, ax = plt.subplots(1, 3, figsize=(15, 5.8))
    colours = {law.key: f"C{i}" for i, law in enumerate(LAWS)}
    for key, c in cases.items():
        col = colours[c["law"]]
        if c["ratio"] == max(BULK_RATIOS):
            a, s, m = _ancf(c, fine), c["solid"][-1], _ancf(c, fine, "mixed")
            ax[0].plot([0] + a["loads"], [0] + a["rots"], "-", color=col, label=f"{c['law']}: ANCF {fine} el.")
            ax[0].plot([0] + m["loads"], [0] + m["rots"], "--", color=col,
                       label=f"{c['law']}: ANCF {fine} el., locking: mixed")
            ax[1].plot([0] + m["x"], [0] + m["along"], "--", color=col)
            ax[0].plot([0] + s["loads"], [0] + s["rots"], "o", color=col, mfc="none",
                       label=f"{c['law']}: solid {s['res']}")
            ax[1].plot([0] + a["x"], [0] + a["along"], "-", color=col)
            ax[1].plot([0] + s["x"], [0] + s["along"], "o", color=col, mfc="none")
    for law in LAWS:
        cs = sorted((c for c in cases.values() if c["law"] == law.key), key=lambda c: c["ratio"])
        ratios, col = [c["ratio"] for c in cs], colours[law.key]
        ax[2].loglog(ratios, [100 * _ancf(c, fine)["err_rot"] for c in cs], "o-", color=col,
                     label=f"{law.key}: rotation")
        ax[2].loglog(ratios, [100 * _ancf(c, fine)["err_u"] for c in cs], "s--", color=col, mfc="none",
                     label=f"{law.key}: displacement")
        ax[2].loglog(ratios, [100 * _ancf(c, fine, "vol")["err_rot"] for c in cs], "^:", color=col,
                     label=f"{law.key}: rotation, vol. term degree {VOLUMETRIC_DEGREE}")
        ax[2].loglog(ratios, [100 * _ancf(c, fine, "mixed")["err_rot"] for c in cs], "D-.", color=col, lw=2,
                     label=f"{law.key}: rotation, locking: mixed")
    ax[2].axhline(1.0, color="k", lw=0.8, ls=":")
    ax[0].set(xlabel="end force [N]", ylabel="end-section rotation about x [deg]",
              title=f"untwist under tension, K/μ = {max(BULK_RATIOS):g}")
    ax[1].set(xlabel="x [m]", ylabel="section rotation [deg]", title=f"along the bar at {FORCE:g} N")
    ax[2].set(xlabel="matrix K/μ", ylabel=f"ANCF {fine} el. error vs solid [%]",
              title="error against the matrix's compressibility")
    for a in ax:
        a.grid(True, lw=0.3)
    ax[2].set_xticks(sorted(BULK_RATIOS), [f"{r:g}" for r in sorted(BULK_RATIOS)])
    ax[2].minorticks_off()
    ax[0].legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
    ax[2].legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.42, -0.14), ncol=2)
    fig.subplots_adjust(left=0.05, right=0.98, top=0.93, bottom=0.33, wspace=0.28)
    fig.savefig(path, dpi=120)
    plt.close(fig)


# --------------------------------------------------------------------------------------------
def write_outputs(out: str, rows: list[dict], doc: str) -> None:
    """CSV (unless it is the input), the docs block and the figure."""
    os.makedirs(os.path.join(out, "figures"), exist_ok=True)
    plot(os.path.join(out, FIGURE), rows)
    write_block(doc, render_block(rows))


def ancf_runs(case: vs.Case, tmp: str) -> list[dict]:
    """The ANCF runs of one case: plain and ``locking: mixed`` at every element count, the
    degree-2 diagnosis at the two finest."""
    runs = [run_ancf(case, n, tmp, model) for model in (ANCF, ANCF_MIXED) for n in ELEMENTS]
    return runs + [run_ancf(case, n, tmp, ANCF_VOL) for n in ELEMENTS[-2:]]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="coarse meshes, K/mu = 50 only (smoke run)")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs"), help="directory of the CSV and figures/")
    ap.add_argument("--doc", default=DOC, help="the page with the marked block (default docs/fibres.md)")
    ap.add_argument("--quad-degree", type=int, default=2, help="solid quadrature degree (default 2)")
    ap.add_argument("--replot", action="store_true", help="block and figure from <out>/solid_fibres.csv")
    ap.add_argument("--ancf-only", action="store_true",
                    help="run the ANCF models again and keep the solid rows of <out>/solid_fibres.csv (no dolfinx)")
    args = ap.parse_args(argv)
    if args.replot:
        write_outputs(args.out, read_csv(os.path.join(args.out, CSV_NAME)), args.doc)
        return 0
    solid_rows = [d for d in read_csv(os.path.join(args.out, CSV_NAME)) if d["model"] not in ANCF_MODELS] \
        if args.ancf_only else None
    if not args.ancf_only:
        vs._import_stack()
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
                sec = vs.ancf_section(case)
                for h in case.h:
                    runs.append(run_solid(case, sec, h, args.quad_degree))
                    r, a, m = runs[-1], runs[len(ELEMENTS) - 1], runs[2 * len(ELEMENTS) - 1]
                    print(f"[solid] {case.key} {r['res']}: {r['dofs']} DOFs, {r['wall']:.1f} s, {r['its']} its, "
                          f"u_x {1e3 * r['u'][0]:.4f} mm, rotation {r['rot']:+.4f} deg "
                          f"(ANCF {ELEMENTS[-1]} el.: {1e3 * a['u'][0]:.4f} mm, {a['rot']:+.4f} deg; "
                          f"{ANCF_MIXED}: {1e3 * m['u'][0]:.4f} mm, {m['rot']:+.4f} deg)", flush=True)
                rows += csv_rows(case, law.key, ratio, runs)
    write_csv(os.path.join(args.out, CSV_NAME), rows)
    write_outputs(args.out, rows, args.doc)
    print(render_block(rows))
    print(f"\n[verify-solid-fibres] {time.perf_counter() - t_start:.0f} s; wrote {args.out}/{CSV_NAME}, "
          f"{FIGURE} and the block {BLOCK} of {args.doc}")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except vs.SolidError as exc:
        print(f"verify_solid_fibres: {exc}", file=sys.stderr)
        sys.exit(1)
    except Exception as exc:   # a failed solve or mesh: one line, non-zero
        print(f"verify_solid_fibres: {type(exc).__name__}: {exc}", file=sys.stderr)
        sys.exit(1)
