"""The soft-matrix bar as a 3D solid: probes, section profiles, the measured rows."""
from __future__ import annotations

import math

import numpy as np

from ancf_verify.bars.cases import Case, ancf_config, ancf_section
from ancf_verify.convergence import richardson
from ancf_verify.fibres.beams import run_ancf
from ancf_verify.fibres.cases import SAMPLE_SCALE, SECTION
from ancf_verify.fibres.report import COLUMNS, csv_rows
from ancf_verify.fibres.solid import SolidProbe, fibre_field, owning_cell, run_solid
from ancf_verify.paths import CONFIGS
from ancf_verify.soft_matrix.cases import BULK_RATIO, LOCKINGS, MIDDLE, model_name
from ancf_verify.stack import import_stack


class SoftProbe(SolidProbe):
    """verify_solid_fibres.SolidProbe and, at the last level, the range of Ē over the solid's
    degree-2 quadrature points in the middle half, the end face's mean displacement ∫ u dA / A,
    and the span and quadratic-fit constant of u_x on the end face (``end_face_fit``)."""

    def __init__(self, case: Case, sec, msh):
        super().__init__(case, sec, msh)
        from ancf_petsc.physics.element3363 import section_monomials
        self.m = section_monomials(*(SAMPLE_SCALE * sec.points).T)[0]

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
            a0 = fibre_field(self.case, X)
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
            tree = geometry.BoundingBoxTree(self.msh, 3, padding=0.1 * SECTION["semi_axes"][1])
            for axis, P in semi_axis_points().items():
                for xf in (0.5, 1.0 - 1e-12):
                    pts = place(np.full(len(P), xf * self.case.length), P, self.case.length, self.case.twist_deg,
                                self.case.twist_axis)
                    cells = np.array([owning_cell(self.msh, tree, p) for p in pts], dtype=np.int32)
                    print(f"[profile] solid x/L = {xf:.2f}, {axis}: " +
                          " ".join(f"{1e3 * v:.4f}" for v in u.eval(pts, cells)[:, 0]), flush=True)
        return out


def semi_axis_points() -> dict:
    """Local section points along the semi-axes y and z at 0, 0.095, ..., 0.95 of their length."""
    t = np.linspace(0.0, 0.95, 11)
    a, b = SECTION["semi_axes"]
    return {"y": np.stack([a * t, 0 * t], axis=1), "z": np.stack([0 * t, b * t], axis=1)}


def profile(case: Case, h: float, tmp: str) -> None:
    """u_x [mm] along the end face's semi-axes: the 8-element traction beams (their quadratic
    section field) and the solid on the mesh of size h [mm]."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    model = build_model(parse_config(ancf_config(case, 8, 2, tmp), base_dir=CONFIGS))
    q0, section_monomials = model.q0, model.block.section_monomials
    for model in LOCKINGS:
        q = run_ancf(case, 8, tmp, model, "traction_force")["q"]
        for axis, P in semi_axis_points().items():
            ux = section_monomials(P[:, 0], P[:, 1]) @ (q[-1, :, 0] - q0[-1, :, 0])
            print(f"[profile] {model_name(LOCKINGS[model], 'traction_force')} x/L = 1.00, {axis}: " +
                  " ".join(f"{1e3 * v:.4f}" for v in ux), flush=True)
    import_stack()
    run_solid(case, ancf_section(case), 1e-3 * h, 2, probe=ProfileProbe)


def rows_of(case: Case, runs: list) -> list[dict]:
    """verify_solid_fibres' CSV rows with the Ē range, face mean and fit on each run's last end
    row, and (beam runs) one row per element (kind "strain": its Ē range)."""
    rows = []
    for r in runs:
        rr = csv_rows(case, "goh_twist", BULK_RATIO, [r])
        last = [d for d in rr if d["kind"] == "end"][-1]
        last.update(fibre_strain_min=f"{r['E'][0]:.5e}", fibre_strain_max=f"{r['E'][1]:.5e}",
                    ux_mean_m=f"{r['u_mean'][0]:.9e}", ux_fit0_m=f"{r['fit0']:.9e}", ux_span_m=f"{r['span']:.9e}")
        n = len(r.get("E_elements", []))
        rr += [{**{k: v for k, v in last.items() if k in COLUMNS[:9]}, "kind": "strain",
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
    ref_u, unc_u, how = richardson(solid)
    ref_r, unc_r, how_r = richardson([{"u": np.array([r["rot"]]), "dofs": r["dofs"]} for r in solid])
    ref_m, unc_m, how_m = richardson([{"u": np.array([r["ux_mean"]]), "dofs": r["dofs"]} for r in solid])
    out = {"ref_u": ref_u, "unc_u": unc_u, "ref_rot": float(ref_r[0]), "unc_rot": unc_r, "how": how,
           "how_rot": how_r, "ref_mean": float(ref_m[0]), "unc_mean": unc_m, "how_mean": how_m,
           "beam": beam, "solid": solid}
    for r in beam + solid:
        r["du"] = r["u"][0] / ref_u[0] - 1.0
        r["dmean"] = r["ux_mean"] / out["ref_mean"] - 1.0
        r["err_u"] = float(np.linalg.norm(r["u"] - ref_u) / np.linalg.norm(ref_u))
        r["drot"] = r["rot"] / out["ref_rot"] - 1.0
    return out
