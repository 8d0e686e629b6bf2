"""gmsh meshes of the bars: the section extruded along x, P2 nodes mapped through the ANCF pretwist."""
from __future__ import annotations

import math

import numpy as np

from ancf_verify.bars.cases import Case
from ancf_verify.stack import SolidError


# --------------------------------------------------------------------------------------------
# Solid runs (gmsh + dolfinx)
# --------------------------------------------------------------------------------------------
def gmsh_section(occ, sec) -> int:
    """Add the section as a plane surface in gmsh's (x, y) = tendon (y, z) plane; its tag."""
    cy, cz = sec.centroid
    if sec.kind in ("ellipse", "circle"):
        a, b = sec.shape_params["semi_axes"]
        s = occ.addDisk(cy, cz, 0.0, max(a, b), min(a, b))   # OCC wants rx >= ry
        if a < b:
            occ.rotate([(2, s)], cy, cz, 0.0, 0.0, 0.0, 1.0, 0.5 * math.pi)
        return s
    if sec.kind == "rectangle":
        w, h = sec.shape_params["size"]
        return occ.addRectangle(cy - 0.5 * w, cz - 0.5 * h, 0.0, w, h)
    # outline: one interpolating spline per ANCF curve through 8 samples per polynomial piece
    offset, tags, curves = sec.shape_params["offset"], {}, []

    def point(p):
        key = tuple(np.round(p / 1e-12).astype(np.int64))    # shared end points: one tag
        if key not in tags:
            tags[key] = occ.addPoint(p[0], p[1], 0.0)
        return tags[key]

    for cv, flip in sec.loop:
        pts = (cv.reversed() if flip else cv).sample(8) + offset
        curves.append(occ.addSpline([point(p) for p in pts]))
    return occ.addPlaneSurface([occ.addCurveLoop(curves)])


def checked_size(h: float) -> float:
    """``h`` if it is a mesh size gmsh can take (> 0, finite): gmsh aborts the process on others."""
    if not (h > 0 and math.isfinite(h)):
        raise SolidError(f"mesh size h must be > 0 [m]; got {h!r}")
    return h


def solid_mesh(case: Case, sec, h: float):
    """P2 tetrahedral dolfinx mesh of the (pretwisted) bar with mesh size ``h``."""
    checked_size(h)
    import gmsh
    from mpi4py import MPI
    from dolfinx.io import gmshio
    from ancf_petsc.physics.geometry import place
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(case.key)
        occ = gmsh.model.occ
        out = occ.extrude([(2, gmsh_section(occ, sec))], 0.0, 0.0, case.length)
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [t for d, t in out if d == 3], 1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(2)
        msh = gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=3)[0]
    finally:
        gmsh.finalize()
    # gmsh (x, y, z) = (Y, Z, x): cyclic permutation (a rotation: tets keep their orientation),
    # then the pretwist map on every geometry node.  geometry.x is a writable view.
    x = msh.geometry.x
    yz, xs = x[:, :2].copy(), x[:, 2].copy()
    x[:, :] = place(xs, yz, case.length, case.twist_deg, case.twist_axis)
    return msh
