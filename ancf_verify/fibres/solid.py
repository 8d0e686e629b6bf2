"""The fibre bar as a 3D solid: fibre field, GOH energy, probes of the section."""
from __future__ import annotations

import math
import time

import numpy as np

from ancf_verify.bars.cases import Case
from ancf_verify.bars.mesh import solid_mesh
from ancf_verify.bars.solid import neo_hookean, solve_solid
from ancf_verify.fibres.cases import OUTSIDE_TOL, SAMPLE_SCALE, SECTION, STATIONS
from ancf_verify.fibres.measures import fitted_rotation_deg, polar_angle_deg
from ancf_verify.stack import SolidError


# --------------------------------------------------------------------------------------------
# Solid
# --------------------------------------------------------------------------------------------
def fibre_field(case: Case, X):
    """UFL unit fibre direction at reference position X: the material line's tangent (twist)
    or x (axis)."""
    import ufl
    if case.material["fibres"]["follow"] == "axis":
        return ufl.as_vector([1.0, 0.0, 0.0])
    tau = math.radians(case.twist_deg) / case.length
    ay, az = case.twist_axis
    t = ufl.as_vector([1.0, -tau * (X[2] - az), tau * (X[1] - ay)])
    return t / ufl.sqrt(ufl.dot(t, t))


def goh_energy(case: Case, msh, F):
    """The energy density of ``case`` in UFL: neo-Hookean, or GOH = neo-Hookean +
    k1/(2 k2)(exp(k2 Ē²) − 1) for Ē ≥ 0 (the tension side's tangent at Ē = 0, as the beam's)."""
    import ufl
    m = case.material
    if m["model"] != "goh":
        return neo_hookean(case, msh, F)
    a0 = fibre_field(case, ufl.SpatialCoordinate(msh))
    C = F.T * F
    kappa = m["kappa"]
    E = kappa * (ufl.tr(C) - 3) + (1 - 3 * kappa) * (ufl.dot(a0, C * a0) - 1)
    Ep = ufl.conditional(ufl.ge(E, 0.0), E, 0.0)
    return neo_hookean(case, msh, F) + m["k1"] / (2 * m["k2"]) * (ufl.exp(m["k2"] * Ep ** 2) - 1)


def check_fibre_field(case: Case, sec, msh) -> float:
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
        raise SolidError(f"point {p} not found in the solid mesh (closest: {best:.3g} outside a cell)")
    return cell


class SolidProbe:
    """What the solid reports at each level: the end face's rotation (integrals over the face,
    quadrature degree 6), at the last level also the rotation of the sections x = k L / 8
    (fit over the ANCF section rule's points scaled by 0.95 about the centroid, evaluated in the
    mesh) and the volumetric share."""

    def __init__(self, case: Case, sec, msh):
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


def run_solid(case: Case, sec, h: float, quad_degree: int, probe=SolidProbe) -> dict:
    """Mesh, check the fibre field, solve; end displacement and rotation at every level (and
    what ``probe(case, sec, msh)``, a SolidProbe, reports)."""
    t0 = time.perf_counter()
    msh = solid_mesh(case, sec, h)
    t_mesh = time.perf_counter() - t0
    field_err = check_fibre_field(case, sec, msh) if case.material["model"] == "goh" else float("nan")
    t0 = time.perf_counter()
    out = solve_solid(case, sec, msh, quad_degree, energy=goh_energy, post=probe(case, sec, msh))
    for lv in out["levels"]:
        lv["load"] *= case.force[0]
    out.update(model="solid P2 tet", res=f"h {h * 1e3:.2f} mm", wall=time.perf_counter() - t0,
               mesh=t_mesh, field_err=field_err)
    return out
