"""The supports of a solid's root face, named as the beams' fix presets: ``clamped`` (u = 0 over
the face; ANCF ``fix: clamped``) and ``plane`` (the face on a frictionless plane x = const,
u_x = 0 over it, free in its plane; ANCF ``fix: plane``)."""
from __future__ import annotations

import numpy as np

from ancf_verify.stack import SolidError

ROOTS = ("clamped", "plane")


def root_conditions(V, msh, facets: np.ndarray, root: str) -> list:
    """Dirichlet conditions of one body's root face (its boundary facets at x = const).

    ``plane``: u_x = 0 over the face; its rigid motions in the plane are held as the beams' fix:
    plane holds them (r, the section centroid, and r_y·e_z, its turn about x): u_y = u_z = 0 at
    the face's vertex nearest its centroid, u_z at the face's vertex farthest from that one
    along y.  Their reactions are the body's net in-plane load (zero under axial loads alone)."""
    from petsc4py import PETSc
    from dolfinx import fem, mesh as dmesh
    if root not in ROOTS:
        raise SolidError(f"root {root!r}: use one of {', '.join(ROOTS)}")
    if root == "clamped":
        return [fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), fem.locate_dofs_topological(V, 2, facets), V)]
    zero = PETSc.ScalarType(0.0)
    bcs = [fem.dirichletbc(zero, fem.locate_dofs_topological(V.sub(0), 2, facets), V.sub(0))]
    msh.topology.create_connectivity(2, 0)
    verts = dmesh.compute_incident_entities(msh, facets, 2, 0)
    xyz = dmesh.compute_midpoints(msh, 0, verts)
    areas = _facet_areas(msh, facets)
    centroid = (areas[:, None] * dmesh.compute_midpoints(msh, 2, facets)).sum(0) / areas.sum()
    a = int(np.argmin(np.linalg.norm(xyz[:, 1:] - centroid[1:], axis=1)))
    b = int(np.argmax(np.abs(xyz[:, 1] - xyz[a, 1])))
    for v, comps in ((verts[a], (1, 2)), (verts[b], (2,))):
        for c in comps:
            bcs.append(fem.dirichletbc(zero, fem.locate_dofs_topological(V.sub(c), 0, np.array([v], dtype=np.int32)),
                                       V.sub(c)))
    return bcs


def _facet_areas(msh, facets: np.ndarray) -> np.ndarray:
    """Areas of triangular facets from their vertices (straight-sided: weights for the centroid)."""
    from dolfinx import mesh as dmesh
    conn = msh.topology.connectivity(2, 0)
    tri = np.array([conn.links(f) for f in facets])
    p = dmesh.compute_midpoints(msh, 0, tri.ravel()).reshape(len(facets), 3, 3)
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
