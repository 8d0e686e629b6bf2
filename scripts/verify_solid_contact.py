#!/usr/bin/env python3
"""Three-subtendon Achilles tendon as a 3D solid with frictionless contact: a reference for ANCF.

The Type III tendon (soleus, medial and lateral gastrocnemius; configs/achilles_type3_psi*.yaml)
is solved twice, serially on one core:

* **solid**: three separate bodies of quadratic tetrahedra (gmsh 4.8, dolfinx 0.5.2).  Each
  subtendon's straight prism is its own gmsh volume (not fragmented: the interface nodes are
  duplicated and each body has its own interface faces); every geometry node is then mapped
  through the ANCF pretwist map ``place`` (as in scripts/verify_solid.py).  Same neo-Hookean
  energy as the beams, Ψ = μ/2 (J^(-2/3) I1 − 3) + K/2 (J − 1)², one μ per body.  Root faces
  x = 0 clamped; the soleus end face x = L carries the uniform dead traction F/A; the
  gastrocnemius end faces are free.
* **ANCF**: the same three beams in-process (``parse_config`` + ``run_model``), ``fix: clamped``,
  ``traction_force`` at the soleus' last node, 2 axial Gauss points, ``contact: {mode: ...}``.

Contact (solid).  On each interface one side is the slave (medial on soleus, lateral on soleus,
medial on lateral): Gauss points on its P2 faces are projected (closest point, every Newton
iteration, candidates from a cKDTree of the current master face centroids) onto the other body's
deformed P2 faces; g = (x_s − x_m)·n_m along the outward master normal, minus the reference gap
g0 of the point (the two tessellations of the curved interface are not the same surface).  The
constraints are mortar-type weighted gaps, one per slave node,

    ḡ_k = Σ_q w_q φ_k(q) (g_q − g0_q) / Σ_q w_q φ_k(q),

with φ_k the hat function of slave node k on the 4-triangle split of each P2 slave face
(piecewise-linear multipliers on quadratic faces: non-negative, partition of unity; as many
constraints as slave nodes, so the non-matching interface is not over-constrained).  They are
enforced exactly by Lagrange multipliers (Λ_k = k_s z_k, force): Newton on the symmetric
saddle-point system [[K + K_geo, −k_s Gᵀ], [−k_s G, 0]] with the consistent gap Hessian in K_geo,
factored by MUMPS LDLᵀ.  ``sliding``: ḡ = 0 (tension and compression).  ``unilateral``: ḡ ≥ 0,
Λ ≥ 0, Λ ḡ = 0 by a semismooth (primal-dual active set) Newton with NCP parameter c
(active: z − c ḡ > 0); the answer must not depend on c or on k_s (checked).

Usage:
  python scripts/verify_solid_contact.py                       # full study (see --help)
  python scripts/verify_solid_contact.py --quick               # smoke run, coarse meshes
  python scripts/verify_solid_contact.py --selftest            # contact implementation checks
  python scripts/verify_solid_contact.py --replot              # figure + report from the CSV
Writes docs/solid_contact.csv, docs/solid_contact.md, docs/figures/solid_contact.png.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
import tempfile
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
CONFIGS = os.path.join(ROOT, "configs")
sys.path.insert(0, ROOT)
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402

import verify_solid as vs  # noqa: E402

NAMES = ("soleus", "medial_gastrocnemius", "lateral_gastrocnemius")
SHORT = ("soleus", "medial", "lateral")
MU = (103.1e6, 143.2e6, 226.7e6)
KBULK = 0.86e9
LENGTH = 0.07
AXIS = (0.005896, -0.0029837333333333335)
LOADS = (10, 20, 30, 40, 45, 60, 80, 90, 100, 150, 200, 300, 400)
# (shared curve, slave body, master body): the gastrocnemii slide on the soleus (which moves
# past their ends at x = L, so they stay covered by it); medial on the stiffer lateral
INTERFACES = (("mg_sol", 1, 0), ("lg_sol", 2, 0), ("lg_mg", 1, 2))
SECTIONS_FILE = "data/achilles_type3_sections.yaml"


class ContactError(RuntimeError):
    """A failed solve or a broken setup (one line, exit status 1)."""


# ============================================================================================
# P2 triangle (faces of the P2 tetrahedra)
# ============================================================================================
# node order: vertices v0 v1 v2, then mid-edge nodes opposite v0, v1, v2: (v1v2), (v0v2), (v0v1)
# parameters (z1, z2), l0 = 1 - z1 - z2
P2_NODES = np.array([[0, 0], [1, 0], [0, 1], [.5, .5], [0, .5], [.5, 0]], dtype=float)
_D2N = np.zeros((6, 2, 2))
_D2N[0] = 4.0
_D2N[1, 0, 0] = 4.0
_D2N[2, 1, 1] = 4.0
_D2N[3, 0, 1] = _D2N[3, 1, 0] = 4.0
_D2N[4, 0, 1] = _D2N[4, 1, 0] = -4.0
_D2N[4, 1, 1] = -8.0
_D2N[5, 0, 1] = _D2N[5, 1, 0] = -4.0
_D2N[5, 0, 0] = -8.0
D2N = _D2N


def p2_shape(z: np.ndarray):
    """Shape functions (..., 6) and derivatives (..., 6, 2) of the P2 triangle at z (..., 2)."""
    z1, z2 = z[..., 0], z[..., 1]
    l0 = 1.0 - z1 - z2
    N = np.stack([l0 * (2 * l0 - 1), z1 * (2 * z1 - 1), z2 * (2 * z2 - 1),
                  4 * z1 * z2, 4 * l0 * z2, 4 * l0 * z1], axis=-1)
    d1 = np.stack([1 - 4 * l0, 4 * z1 - 1, 0 * z1, 4 * z2, -4 * z2, 4 * (l0 - z1)], axis=-1)
    d2 = np.stack([1 - 4 * l0, 0 * z1, 4 * z2 - 1, 4 * z1, 4 * (l0 - z2), -4 * z1], axis=-1)
    return N, np.stack([d1, d2], axis=-1)


# four sub-triangles of the P2 face (corner nodes in P2 order): the multiplier hats live on them
SUBTRI = np.array([[0, 5, 4], [5, 1, 3], [4, 3, 2], [3, 4, 5]])


def _tri_rule(n: int):
    """Barycentric points (m, 3) and weights (sum 1) of a triangle rule with n = 3, 6 or 7 points."""
    if n == 3:
        a, b = 2.0 / 3.0, 1.0 / 6.0
        return np.array([[a, b, b], [b, a, b], [b, b, a]]), np.full(3, 1.0 / 3.0)
    if n == 6:
        a1, w1 = 0.816847572980459, 0.109951743655322
        a2, w2 = 0.108103018168070, 0.223381589678011
        b1, b2 = (1 - a1) / 2, (1 - a2) / 2
        pts = [[a1, b1, b1], [b1, a1, b1], [b1, b1, a1], [a2, b2, b2], [b2, a2, b2], [b2, b2, a2]]
        return np.array(pts), np.array([w1] * 3 + [w2] * 3)
    if n == 7:
        a1, w1 = 0.797426985353087, 0.125939180544827
        a2, w2 = 0.059715871789770, 0.132394152788506
        b1, b2 = (1 - a1) / 2, (1 - a2) / 2
        pts = [[1 / 3] * 3, [a1, b1, b1], [b1, a1, b1], [b1, b1, a1], [a2, b2, b2], [b2, a2, b2],
               [b2, b2, a2]]
        return np.array(pts), np.array([0.225] + [w1] * 3 + [w2] * 3)
    raise ValueError(n)


def slave_rule(n: int):
    """Points of the slave-face rule: z (Q, 2), weights in z (Q,) (sum 1/2), hat corners (Q, 3)
    (P2 node indices) and hat values (Q, 3) of the sub-triangle each point lies in."""
    bary, w = _tri_rule(n)
    zs, ws, corners, hats = [], [], [], []
    for tri in SUBTRI:
        P = P2_NODES[tri]                       # (3, 2)
        zs.append(bary @ P)
        ws.append(w * 0.125)                    # sub-triangle area in z: 1/8
        corners.append(np.tile(tri, (len(w), 1)))
        hats.append(bary)
    return np.vstack(zs), np.concatenate(ws), np.vstack(corners), np.vstack(hats)


# ============================================================================================
# Geometry and meshes
# ============================================================================================
def tendon_config(psi: float, elements: int, mode: str | None, out_dir: str, beams=NAMES) -> dict:
    """The raw ANCF config: clamped first nodes, traction_force 1 N (load factors = newtons) at the
    soleus' last node, 2 axial points, contact ``mode`` (None: none), probes at the last nodes."""
    raw = {"name": f"type3_psi{psi:g}_e{elements}_{mode or 'free'}",
           "geometry": {"length": LENGTH, "twist_deg": float(psi), "twist_axis": list(AXIS)},
           "beams": [{"name": n, "section": {"shape": "outline", "file": SECTIONS_FILE, "loop": n,
                                             "spline_degree": 3, "cubature_degree": 6},
                      "material": {"model": "neo-hookean", "mu": MU[NAMES.index(n)],
                                   "bulk_modulus": KBULK},
                      "elements": elements, "axial_points": 2} for n in beams],
           "boundary_conditions": [{"beam": n, "node": "first", "fix": "clamped"} for n in beams],
           "loads": [{"beam": "soleus", "node": "last", "traction_force": [1.0, 0.0, 0.0]}],
           "steps": [float(f) for f in LOADS],
           "probes": [{"name": n, "beam": n, "node": "last"} for n in beams],
           "output": {"dir": out_dir, "vtk": False}}
    if mode:
        raw["contact"] = {"mode": mode}
    return raw


def tendon_sections() -> list:
    """The three ANCF Section objects (outline loops, centroids, areas)."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    spec = parse_config(tendon_config(0.0, 1, "sliding", tempfile.mkdtemp()), base_dir=CONFIGS)
    return [b.section for b in build_model(spec).beams]


def _curve_names(sec) -> list:
    return [cv.name for cv, _ in sec.loop]


def tendon_mesh(secs, h: float, psi: float, bodies=(0, 1, 2), layered: bool = True):
    """P2 tets of the chosen bodies as separate volumes (duplicated interface nodes), twisted.

    layered: the section's triangles are extruded in ceil(L/h) layers (each prism split into 3
    tets), so that the cross-section tessellation of a body is the same at every x; the shared
    interface curves get the same 1D mesh on both sides.  A body sliding along x then meets the
    same polygonal section of its neighbour everywhere (no washboard of tessellation mismatch
    for it to ride over).  Otherwise: gmsh's unstructured 3D mesh of the extruded prism (as
    verify_solid.solid_mesh).  Each body is meshed in its own gmsh model (gmsh 4.8 gives
    layered meshes whose surface triangles are not faces of the tets when several volumes are
    extruded in one model) and the meshes are merged for dolfinx.

    Cell tags: body b -> b + 1.  Facet tags: root 10 + b, end 20 + b, lateral face on curve c of
    body b -> 100 * (b + 1) + index of c in the loop."""
    from ancf_petsc.physics.geometry import place
    parts = [_gmsh_body(secs, b, h, layered) for b in bodies]
    msh, ct, ft = _merge_to_dolfinx(parts)
    x = msh.geometry.x          # gmsh (x, y, z) = tendon (y, z, x), then the pretwist map
    yz, xs = x[:, :2].copy(), x[:, 2].copy()
    x[:, :] = place(xs, yz, LENGTH, psi, AXIS)
    return msh, ct, ft


AXIAL = {"end_zone": 7e-3, "ratio": 2.5}   # graded layers: size h within 7 mm of each end, 2.5 h between


def axial_layers(h: float, layered) -> dict:
    """gmsh extrude layers: size h over ``end_zone`` at both ends (clamp and loaded end), about
    ``ratio`` h in between (the fields vary slowly along the middle of the bar); every size is
    proportional to h, so the meshes of a refinement study stay similar."""
    opt = dict(AXIAL, **(layered if isinstance(layered, dict) else {}))
    a, r = opt["end_zone"], opt["ratio"]
    if r <= 1.0 or a <= 0:
        return {"numElements": [int(math.ceil(LENGTH / h - 1e-9))]}
    n_end = int(math.ceil(a / h - 1e-9))
    n_mid = int(math.ceil((LENGTH - 2 * a) / (r * h) - 1e-9))
    return {"numElements": [n_end, n_mid, n_end], "heights": [a / LENGTH, (LENGTH - a) / LENGTH, 1.0]}


def _gmsh_body(secs, b: int, h: float, layered) -> dict:
    """Mesh one body in its own gmsh model; nodes, P2 tets and tagged P2 triangles (gmsh order)."""
    import gmsh
    from dolfinx.io import gmshio
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(f"body{b}")
        occ = gmsh.model.occ
        srf = vs._gmsh_section(occ, secs[b])
        if layered:
            out = occ.extrude([(2, srf)], 0.0, 0.0, LENGTH, recombine=False, **axial_layers(h, layered))
        else:
            out = occ.extrude([(2, srf)], 0.0, 0.0, LENGTH)
        occ.synchronize()
        vol = [t for d, t in out if d == 3][0]
        gmsh.model.addPhysicalGroup(3, [vol], b + 1)
        surfs = [t for d, t in gmsh.model.getBoundary([(3, vol)], oriented=False)]
        lateral = []
        for s in surfs:
            zc = occ.getCenterOfMass(2, s)[2]
            if abs(zc) < 1e-9:
                gmsh.model.addPhysicalGroup(2, [s], 10 + b)
            elif abs(zc - LENGTH) < 1e-9:
                gmsh.model.addPhysicalGroup(2, [s], 20 + b)
            else:
                lateral.append(s)
        off = secs[b].shape_params["offset"]
        for ci, (cv, flip) in enumerate(secs[b].loop):
            pts = cv.sample(4)[1:-1] + off        # interior samples of the curve
            dist = []
            for s in lateral:
                d = 0.0
                for p in pts:
                    q = gmsh.model.getClosestPoint(2, s, [p[0], p[1], 0.5 * LENGTH])[0]
                    d = max(d, math.dist(q, [p[0], p[1], 0.5 * LENGTH]))
                dist.append(d)
            k = int(np.argmin(dist))
            if dist[k] > 1e-7:
                raise ContactError(f"lateral face of curve {cv.name} not found (distance {dist[k]:.2e})")
            gmsh.model.addPhysicalGroup(2, [lateral[k]], 100 * (b + 1) + ci)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(2)
        x = gmshio.extract_geometry(gmsh.model)
        topo = gmshio.extract_topology_and_markers(gmsh.model)
        tdim = {t: gmsh.model.mesh.getElementProperties(t)[1] for t in topo}
    finally:
        gmsh.finalize()
    cell_t = [t for t in topo if tdim[t] == 3]
    face_t = [t for t in topo if tdim[t] == 2]
    if len(cell_t) != 1 or len(face_t) != 1:
        raise ContactError(f"body {b}: unexpected element types {sorted(topo)}")
    cells = np.asarray(topo[cell_t[0]]["topology"], dtype=np.int64)
    faces = np.asarray(topo[face_t[0]]["topology"], dtype=np.int64)
    # every tagged triangle must be a face of a tet (checked on the vertices)
    tet_faces = {tuple(sorted(np.delete(c[:4], i))) for c in cells for i in range(4)}
    bad = sum(tuple(sorted(f[:3])) not in tet_faces for f in faces)
    if bad:
        raise ContactError(f"body {b}: {bad} boundary triangles are not faces of the tets")
    used = np.unique(cells)                 # drop the nodes no tet uses (gmsh keeps some)
    renum = np.full(len(x), -1, dtype=np.int64)
    renum[used] = np.arange(len(used))
    if np.any(renum[faces] < 0):
        raise ContactError(f"body {b}: boundary triangles use nodes of no tet")
    x, cells, faces = x[used], renum[cells], renum[faces]
    return {"x": x, "cells": cells, "cell_values": np.asarray(topo[cell_t[0]]["cell_data"], dtype=np.int32),
            "faces": faces, "face_values": np.asarray(topo[face_t[0]]["cell_data"], dtype=np.int32),
            "cell_type": cell_t[0], "face_type": face_t[0]}


def _merge_to_dolfinx(parts: list):
    """One dolfinx mesh (serial) from several gmsh meshes: nodes stacked, no node shared."""
    from mpi4py import MPI
    from dolfinx import cpp as _cpp
    from dolfinx.io import gmshio
    from dolfinx.mesh import create_mesh, meshtags_from_entities
    off, xs, cells, cv, faces, fv = 0, [], [], [], [], []
    for p in parts:
        xs.append(p["x"])
        cells.append(p["cells"] + off)
        faces.append(p["faces"] + off)
        cv.append(p["cell_values"])
        fv.append(p["face_values"])
        off += len(p["x"])
    x, cells, faces = np.vstack(xs), np.vstack(cells), np.vstack(faces)
    cv, fv = np.concatenate(cv), np.concatenate(fv)
    comm = MPI.COMM_WORLD
    domain = gmshio.ufl_mesh(parts[0]["cell_type"], 3)
    ctype = _cpp.mesh.to_type(str(domain.ufl_cell()))
    cells = cells[:, gmshio.cell_perm_array(ctype, cells.shape[1])]
    msh = create_mesh(comm, cells, x[:, :3], domain)
    ents, vals = _cpp.io.distribute_entity_data(msh._mesh, 3, cells, cv)
    msh.topology.create_connectivity(3, 0)
    ct = meshtags_from_entities(msh, 3, _cpp.graph.AdjacencyList_int32(ents), vals.astype(np.int32))
    ftype = _cpp.mesh.cell_entity_type(ctype, 2, 0)
    faces = faces[:, gmshio.cell_perm_array(ftype, faces.shape[1])]
    ents, vals = _cpp.io.distribute_entity_data(msh._mesh, 2, faces, fv)
    msh.topology.create_connectivity(2, 3)
    ft = meshtags_from_entities(msh, 2, _cpp.graph.AdjacencyList_int32(ents), vals.astype(np.int32))
    return msh, ct, ft


def interface_tag(secs, body: int, curve: str) -> int:
    return 100 * (body + 1) + _curve_names(secs[body]).index(curve)


def blocks_mesh(hA: float, hB: float, size=(4e-3, 1e-3, 1e-3)):
    """Two boxes A = [0, lx] x [-ly, 0] x [0, lz] and B = [0, lx] x [0, ly] x [0, lz] (separate
    volumes, own mesh sizes: non-matching on the interface y = 0).  Cell tags 1, 2; facet tags:
    body b (0 = A, 1 = B): x = 0 -> 10 + b, x = lx -> 20 + b, z = 0 -> 30 + b, outer y face
    (A: y = -ly, B: y = ly) -> 40 + b, interface y = 0 -> 100 * (b + 1)."""
    import gmsh
    from mpi4py import MPI
    from dolfinx.io import gmshio
    lx, ly, lz = size
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("blocks")
        occ = gmsh.model.occ
        vA = occ.addBox(0, -ly, 0, lx, ly, lz)
        vB = occ.addBox(0, 0, 0, lx, ly, lz)
        occ.synchronize()
        for b, (v, hh) in enumerate(((vA, hA), (vB, hB))):
            gmsh.model.addPhysicalGroup(3, [v], b + 1)
            bnd = gmsh.model.getBoundary([(3, v)], oriented=False)
            pts = gmsh.model.getBoundary([(3, v)], combined=False, oriented=False, recursive=True)
            gmsh.model.mesh.setSize(pts, hh)
            for d, s in bnd:
                c = occ.getCenterOfMass(2, s)
                if abs(c[0]) < 1e-12:
                    tag = 10 + b
                elif abs(c[0] - lx) < 1e-12:
                    tag = 20 + b
                elif abs(c[2]) < 1e-12:
                    tag = 30 + b
                elif abs(c[1]) < 1e-12:
                    tag = 100 * (b + 1)
                elif abs(abs(c[1]) - ly) < 1e-12:
                    tag = 40 + b
                else:
                    continue
                gmsh.model.addPhysicalGroup(2, [s], tag)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(2)
        msh, ct, ft = gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=3)
    finally:
        gmsh.finalize()
    return msh, ct, ft


# ============================================================================================
# Contact: faces, projection, gap and its derivatives
# ============================================================================================
class Faces:
    """P2 boundary faces with one facet tag: node (block) indices (n, 6) in P2-triangle order,
    oriented so that t1 x t2 points out of the body."""

    def __init__(self, V, ft, tag: int, X: np.ndarray):
        import basix
        msh = V.mesh
        tdim = msh.topology.dim
        facets = ft.indices[ft.values == tag]
        if len(facets) == 0:
            raise ContactError(f"no facets with tag {tag}")
        msh.topology.create_connectivity(tdim - 1, tdim)
        msh.topology.create_connectivity(tdim, tdim - 1)
        f2c, c2f = msh.topology.connectivity(tdim - 1, tdim), msh.topology.connectivity(tdim, tdim - 1)
        cells = np.array([f2c.links(f)[0] for f in facets], dtype=np.int64)
        c2f_arr = c2f.array.reshape(-1, 4)
        local = np.argmax(c2f_arr[cells] == facets[:, None], axis=1)
        layout = V.dofmap.dof_layout
        vdof = [layout.entity_dofs(0, v)[0] for v in range(4)]
        edges = basix.topology(basix.CellType.tetrahedron)[1]
        edof = {tuple(sorted(e)): layout.entity_dofs(1, i)[0] for i, e in enumerate(edges)}
        table = np.zeros((4, 6), dtype=np.int64)      # local facet -> 6 cell-local dofs
        opp = np.zeros((4,), dtype=np.int64)
        for i in range(4):
            a, b, c = [v for v in range(4) if v != i]
            table[i] = [vdof[a], vdof[b], vdof[c], edof[(b, c)], edof[(a, c)], edof[(a, b)]]
            opp[i] = vdof[i]
        dm = V.dofmap.list.array.reshape(-1, 10)
        nodes = dm[cells[:, None], table[local]]
        opp_nodes = dm[cells, opp[local]]
        # orient outwards: normal at the face centre against the opposite vertex
        N, dN = p2_shape(np.array([1 / 3, 1 / 3]))
        Xf = X[nodes]
        t = np.einsum("ab,nai->nbi", dN, Xf)
        nrm = np.cross(t[:, 0], t[:, 1])
        inward = np.einsum("ni,ni->n", nrm, np.einsum("a,nai->ni", N, Xf) - X[opp_nodes]) < 0
        nodes[inward] = nodes[inward][:, [0, 2, 1, 3, 5, 4]]
        self.nodes = nodes
        self.tag = tag

    def __len__(self):
        return len(self.nodes)


def project(xq: np.ndarray, Y: np.ndarray, cand: np.ndarray, iters: int = 40, clip: bool = True,
            z0=None):
    """Closest points of xq (n, 3) on the P2 faces Y (m, 6, 3), searched over cand (n, k):
    Gauss-Newton in z per (point, face), clipped to the triangle; returns the best face (n,) and z
    (n, 2) and whether that z is on the face's border (clipped)."""
    n, k = cand.shape
    Yc = Y[cand].reshape(n * k, 6, 3)
    P = np.repeat(xq, k, axis=0)
    z = np.full((n * k, 2), 1.0 / 3.0) if z0 is None else np.repeat(z0, k, axis=0)
    todo = np.arange(n * k)
    for _ in range(iters):
        Yt, zt = Yc[todo], z[todo]
        N, dN = p2_shape(zt)
        x = np.matmul(N[:, None, :], Yt)[:, 0, :]
        T = np.matmul(np.swapaxes(dN, -1, -2), Yt)          # (m, 2, 3)
        r = P[todo] - x
        rhs = np.matmul(T, r[:, :, None])[:, :, 0]
        A = np.matmul(T, np.swapaxes(T, -1, -2))
        det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] ** 2
        dz = np.stack([A[:, 1, 1] * rhs[:, 0] - A[:, 0, 1] * rhs[:, 1],
                       A[:, 0, 0] * rhs[:, 1] - A[:, 0, 1] * rhs[:, 0]], axis=-1) / det[:, None]
        znew = _clip_tri(zt + dz) if clip else zt + dz
        moved = np.abs(znew - zt).max(axis=1) > 1e-15
        z[todo] = znew
        todo = todo[moved]
        if len(todo) == 0:
            break
    N, _ = p2_shape(z)
    d = np.linalg.norm(P - np.matmul(N[:, None, :], Yc)[:, 0, :], axis=1).reshape(n, k)
    best = np.argmin(d, axis=1)
    zb = z.reshape(n, k, 2)[np.arange(n), best]
    border = (zb.min(axis=1) < 1e-12) | (zb.sum(axis=1) > 1 - 1e-12)
    return cand[np.arange(n), best], zb, border


def _clip_tri(z):
    z = np.maximum(z, 0.0)
    s = z.sum(axis=-1)
    over = s > 1.0
    if np.any(over):
        # closest point on the hypotenuse z1 + z2 = 1 (then clipped to its ends)
        d = 0.5 * (z[..., 0] - z[..., 1])
        z1 = np.clip(0.5 + d, 0.0, 1.0)
        z[over] = np.stack([z1, 1.0 - z1], axis=-1)[over]
    return z


def gap_terms(xs: np.ndarray, Ym: np.ndarray, z: np.ndarray, hessian: bool):
    """Gap g = (xs − x_m(z))·n and, per point, the master shape values (n, 6), the unit outward
    normal (n, 3), and for the Hessian W (n, 36, 4) and C (n, 4, 4) with ∇²g = −W C Wᵀ (slave
    rows 0-17 filled by the caller's slave shape values)."""
    N, dN = p2_shape(z)
    x = np.einsum("na,nai->ni", N, Ym)
    T = np.einsum("nab,nai->nbi", dN, Ym)
    c = np.cross(T[:, 0], T[:, 1])
    nrm = c / np.linalg.norm(c, axis=1)[:, None]
    r = xs - x
    g = np.einsum("ni,ni->n", r, nrm)
    out = {"g": g, "N": N, "dN": dN, "n": nrm, "T": T}
    if hessian:
        X2 = np.einsum("abc,nai->nbci", D2N, Ym)
        a = np.einsum("nbi,nci->nbc", T, T)
        b = np.einsum("nbci,ni->nbc", X2, nrm)
        H = a - g[:, None, None] * b
        Hi, ai = np.linalg.inv(H), np.linalg.inv(a)
        C = np.zeros((len(g), 4, 4))
        C[:, :2, :2] = ai @ b @ Hi
        C[:, :2, 2:] = Hi
        C[:, 2:, :2] = Hi
        C[:, 2:, 2:] = g[:, None, None] * Hi
        out["C"] = 0.5 * (C + np.transpose(C, (0, 2, 1)))
    return out


class Interface:
    """One slave/master pair: slave Gauss points, hats (weighted-gap matrix), reference gaps."""

    def __init__(self, name, slave: Faces, master: Faces, X: np.ndarray, rule_points: int,
                 candidates: int = 8, fixed=None):
        self.name, self.slave, self.master = name, slave, master
        zq, wq, corners, hats = slave_rule(rule_points)
        self.Q = len(wq)
        Ns, dNs = p2_shape(zq)                               # (Q, 6), (Q, 6, 2)
        self.Ns = Ns
        Xs = X[slave.nodes]                                  # (nf, 6, 3)
        T = np.einsum("qab,fai->fqbi", dNs, Xs)
        jac = np.linalg.norm(np.cross(T[:, :, 0], T[:, :, 1]), axis=2)   # (nf, Q)
        w = (jac * wq[None, :]).ravel()                      # reference area weights
        nf = len(slave)
        self.face_of_q = np.repeat(np.arange(nf), self.Q)
        self.area = float(w.sum())
        # constraint k = unique slave node; B_kq = w_q φ_k(q) / Σ_q w_q φ_k(q).  Slave nodes whose
        # displacement is prescribed (the clamped root) carry no multiplier: their gap is fixed
        # already, and a constraint there would over-constrain the first row of elements (as in
        # mortar methods, the removed hat is shared out to the free corners of its sub-triangle,
        # which keeps the partition of unity)
        cn = slave.nodes[:, corners].reshape(-1, 3)          # (nf Q, 3) node ids of the hat corners
        beta = np.broadcast_to(hats, (nf, self.Q, 3)).reshape(-1, 3).copy()
        if fixed is not None:
            rem = fixed[cn]
            nfree = 3 - rem.sum(axis=1)
            extra = np.where(nfree > 0, (beta * rem).sum(axis=1) / np.maximum(nfree, 1), 0.0)
            beta = np.where(rem, 0.0, beta + extra[:, None])
        keep = beta.ravel() > 0
        self.cnodes, inv = np.unique(cn.ravel()[keep], return_inverse=True)
        rows = inv
        cols = np.repeat(np.arange(nf * self.Q), 3)[keep]
        vals = (w[:, None] * beta).ravel()[keep]
        Braw = sp.csr_matrix((vals, (rows, cols)), shape=(len(self.cnodes), nf * self.Q))
        self.ak = np.asarray(Braw.sum(axis=1)).ravel()
        self.Braw = Braw
        self.w = w
        self.set_on(np.ones(nf * self.Q, dtype=bool))
        self.candidates = candidates
        self.g0, self.last_mf, self.track = None, None, True
        self.g0 = self.evaluate(X, hessian=False)["g"].copy()

    def set_on(self, on: np.ndarray) -> None:
        """Which slave points are over the master surface (in contact).  A point past the master's
        edge (its end, or the edge of the interface strip after sliding across it) has nothing
        to touch and leaves the constraints; a constraint whose points are all off is dead."""
        self.on = on.copy()
        self.B = (sp.diags(1.0 / self.ak) @ self.Braw @ sp.diags(on.astype(float))).tocsr()
        self.frac = (self.Braw @ on.astype(float)) / self.ak
        self.alive = self.frac > 1e-3

    @property
    def nq(self):
        return len(self.face_of_q)

    @property
    def nc(self):
        return len(self.cnodes)

    def slave_points(self, x: np.ndarray) -> np.ndarray:
        return np.einsum("qa,fai->fqi", self.Ns, x[self.slave.nodes]).reshape(-1, 3)

    def evaluate(self, x: np.ndarray, hessian: bool) -> dict:
        """Project the slave points of configuration x (nodes, 3) and evaluate gaps (and Hessian terms)."""
        from scipy.spatial import cKDTree
        xs = self.slave_points(x)
        Ym = x[self.master.nodes]
        Nc, _ = p2_shape(np.array([1 / 3, 1 / 3]))
        cent = np.einsum("a,fai->fi", Nc, Ym)
        # phase 1: the face of the last projection (or the nearest centroid); an interior foot
        # point there is the closest point (the interface is smooth on the scale of the gap)
        first = self.last_mf if self.last_mf is not None else \
            cKDTree(cent).query(xs, k=1)[1].astype(np.int64)
        mf, z, border = project(xs, Ym, first[:, None])
        if np.any(border):
            # phase 2: points on a face border: search the k nearest faces (and the last one)
            b = np.nonzero(border)[0]
            k = min(self.candidates, len(cent))
            cand = cKDTree(cent).query(xs[b], k=k)[1].reshape(len(b), k)
            cand = np.hstack([first[b, None], cand])
            mf[b], z[b], border[b] = project(xs[b], Ym, cand)
            # points off the master surface (past its end or the edge of the interface strip):
            # foot point on the smooth extension of the nearest face (unclipped), so that g and
            # its derivatives stay smooth and consistent
            b = np.nonzero(border)[0]
            if len(b):
                zc = z[b].copy()
                _, zu, _ = project(xs[b], Ym, mf[b, None], clip=False, z0=zc)
                ok = np.isfinite(zu).all(axis=1) & (zu.min(axis=1) > -0.5) & (zu.sum(axis=1) < 1.5)
                z[b[ok]] = zu[ok]
        if self.track:
            self.last_mf = mf.copy()
        out = gap_terms(xs, Ym[mf], z, hessian)
        out.update(mf=mf, z=z, border=border, xs=xs,
                   zout=np.maximum(0.0, np.maximum(-z.min(axis=1), z.sum(axis=1) - 1.0)))
        if self.g0 is not None:
            out["gr"] = out["g"] - self.g0
        return out

    def dofs(self, mf: np.ndarray) -> np.ndarray:
        """(nq, 36) DOF indices: slave face nodes then master face nodes, xyz each."""
        nodes = np.hstack([self.slave.nodes[self.face_of_q], self.master.nodes[mf]])   # (nq, 12)
        return (3 * nodes[:, :, None] + np.arange(3)).reshape(len(mf), 36)

    def grad_values(self, ev: dict) -> np.ndarray:
        """(nq, 36) ∇g per point: slave N_i n, master −M_a n."""
        Ns = self.Ns[np.tile(np.arange(self.Q), len(self.slave))]          # (nq, 6)
        gs = Ns[:, :, None] * ev["n"][:, None, :]
        gm = -ev["N"][:, :, None] * ev["n"][:, None, :]
        return np.hstack([gs.reshape(-1, 18), gm.reshape(-1, 18)])

    def hess_W(self, ev: dict) -> np.ndarray:
        """W (nq, 36, 4) of ∇²g = −W C Wᵀ: columns U_α (slave N_i t_α, master −M_a t_α) and
        V_α (slave 0, master M_a,α n)."""
        Ns = self.Ns[np.tile(np.arange(self.Q), len(self.slave))]
        T, N, dN, n = ev["T"], ev["N"], ev["dN"], ev["n"]
        W = np.zeros((len(N), 12, 3, 4))
        W[:, :6, :, 0:2] = np.einsum("na,nbi->naib", Ns, T)
        W[:, 6:, :, 0:2] = -np.einsum("na,nbi->naib", N, T)
        W[:, 6:, :, 2:4] = np.einsum("nab,ni->naib", dN, n)
        return W.reshape(len(N), 36, 4)


# ============================================================================================
# The solid problem
# ============================================================================================
class Problem:
    """Hyperelastic bodies (one dolfinx mesh, one μ, K per cell tag) with Dirichlet faces, dead end
    tractions and frictionless contact interfaces enforced by Lagrange multipliers.

    dirichlet: [(facet tag, components)]; tractions: {facet tag: total force per unit load
    factor (3,)}; interfaces: [(name, slave facet tag, master facet tag)]; law: None, 'sliding'
    or 'unilateral'."""

    def __init__(self, msh, ct, ft, materials: dict, dirichlet, tractions: dict, interfaces=(),
                 law: str | None = "sliding", quad_degree: int = 2, rule_points: int = 3,
                 ks: float | None = None, ncp_c: float = 1.0, geometric: bool = True,
                 candidates: int = 8):
        import ufl
        from petsc4py import PETSc
        from dolfinx import fem
        from dolfinx.fem.petsc import create_matrix
        self.msh, self.ct, self.ft = msh, ct, ft
        V = fem.FunctionSpace(msh, ufl.VectorElement("CG", msh.ufl_cell(), 2))
        self.V = V
        self.u = fem.Function(V)
        u, v, du = self.u, ufl.TestFunction(V), ufl.TrialFunction(V)
        Q = fem.FunctionSpace(msh, ("DG", 0))
        mu, K = fem.Function(Q), fem.Function(Q)
        qd = Q.dofmap.list.array
        for tag, (m, k) in materials.items():
            cells = ct.indices[ct.values == tag]
            mu.x.array[qd[cells]] = m
            K.x.array[qd[cells]] = k
        self.mu_ref = max(m for m, _ in materials.values())
        bcs = []
        for tag, comps in dirichlet:
            facets = ft.indices[ft.values == tag]
            if len(facets) == 0:
                raise ContactError(f"no facets with Dirichlet tag {tag}")
            if tuple(comps) == (0, 1, 2):
                bcs.append(fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType),
                                           fem.locate_dofs_topological(V, 2, facets), V))
            else:
                for c in comps:
                    bcs.append(fem.dirichletbc(PETSc.ScalarType(0.0),
                                               fem.locate_dofs_topological(V.sub(c), 2, facets), V.sub(c)))
        self.bcs = bcs
        self.ndof = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
        mask = np.ones(self.ndof)
        for bc in bcs:
            mask[bc.dof_indices()[0]] = 0.0
        self.mask = mask
        md = {"quadrature_degree": quad_degree}
        dx = ufl.Measure("dx", domain=msh, metadata=md)
        ds = ufl.Measure("ds", domain=msh, subdomain_data=ft, metadata=md)
        F = ufl.Identity(3) + ufl.grad(u)
        J, I1 = ufl.det(F), ufl.tr(F.T * F)
        psi = mu / 2 * (J ** (-2.0 / 3.0) * I1 - 3) + K / 2 * (J - 1) ** 2
        self.tr_consts, self.tr_force, self.face_area = {}, {}, {}
        energy = psi * dx
        for tag, force in tractions.items():
            area = fem.assemble_scalar(fem.form(1.0 * ds(tag)))
            if area <= 0:
                raise ContactError(f"traction face {tag} not found")
            c = fem.Constant(msh, np.zeros(3, dtype=PETSc.ScalarType))
            self.tr_consts[tag], self.tr_force[tag], self.face_area[tag] = c, np.asarray(force, float), area
            energy = energy - ufl.dot(c, u) * ds(tag)
        self.ds, self.dx = ds, dx
        res = ufl.derivative(energy, u, v)
        self.F_form = fem.form(res)
        self.J_form = fem.form(ufl.derivative(res, u, du))
        self.A = create_matrix(self.J_form)
        self.b = self.u.vector.duplicate()
        self.X = V.tabulate_dof_coordinates().copy()
        self.law = law if interfaces else None
        self.geometric = geometric
        self.ifaces = []
        for name, st, mt in interfaces:
            fixed = mask.reshape(-1, 3).sum(axis=1) == 0
            self.ifaces.append(Interface(name, Faces(V, ft, st, self.X), Faces(V, ft, mt, self.X), self.X,
                                         rule_points, candidates, fixed))
        self.nc = sum(i.nc for i in self.ifaces)
        hmin = self._mesh_size()
        self.h = hmin
        self.ks = ks if ks is not None else self.mu_ref * hmin     # multiplier unit [N/m]
        self.ncp_c = ncp_c
        self.z = np.zeros(self.nc)
        self.alive = np.ones(self.nc, dtype=bool)
        self.active = np.ones(self.nc, dtype=bool) if self.law == "sliding" else np.zeros(self.nc, dtype=bool)
        self.set_passes, self.set_changes = 0, 0
        self.load = 0.0
        self.debug = False
        self.stats = {"newton": 0, "factorizations": 0, "t_assemble": 0.0, "t_contact": 0.0, "t_solve": 0.0}

    def _mesh_size(self) -> float:
        """Mean edge length of the contact slave faces (or of the mesh), for scales."""
        if self.ifaces:
            nodes = np.vstack([i.slave.nodes for i in self.ifaces])
        else:
            dm = self.V.dofmap.list.array.reshape(-1, 10)
            return float(np.linalg.norm(self.X[dm[:, 0]] - self.X[dm[:, 1]], axis=1).mean())
        X = self.X
        e = [np.linalg.norm(X[nodes[:, a]] - X[nodes[:, b]], axis=1) for a, b in ((0, 1), (1, 2), (0, 2))]
        return float(np.mean(e))

    # ---------------------------------------------------------------------------------------
    def set_load(self, lam: float) -> None:
        self.load = lam
        for tag, c in self.tr_consts.items():
            c.value[:] = lam * self.tr_force[tag] / self.face_area[tag]

    def positions(self, uvec: np.ndarray) -> np.ndarray:
        return self.X + uvec.reshape(-1, 3)

    def _internal(self, uvec: np.ndarray, matrix: bool):
        """dolfinx residual (BC rows zero) and, if asked, the tangent as scipy CSR (BC rows/cols
        identity)."""
        from petsc4py import PETSc
        from dolfinx.fem.petsc import assemble_matrix, assemble_vector
        t0 = time.perf_counter()
        self.u.x.array[:] = uvec
        self.u.x.scatter_forward()
        with self.b.localForm() as loc:
            loc.set(0.0)
        assemble_vector(self.b, self.F_form)
        self.b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        r = self.b.array.copy() * self.mask
        Kc = None
        if matrix:
            self.A.zeroEntries()
            assemble_matrix(self.A, self.J_form, bcs=self.bcs)
            self.A.assemble()
            ip, ix, val = self.A.getValuesCSR()
            Kc = sp.csr_matrix((val.copy(), ix.copy(), ip.copy()), shape=(self.ndof, self.ndof))
        self.stats["t_assemble"] += time.perf_counter() - t0
        return r, Kc

    def contact(self, uvec: np.ndarray, z: np.ndarray, matrix: bool, active=None) -> dict:
        """Weighted gaps, their gradient G (nc x ndof, BC columns zero), the contact residual
        −k_s Gᵀ z_active and, if asked, the geometric stiffness k_s Σ_q τ_q W C Wᵀ."""
        t0 = time.perf_counter()
        x = self.positions(uvec)
        active = self.active if active is None else active
        gbar, Gs, evs, rows0 = [], [], [], 0
        Kg = None
        za = np.where(active, z, 0.0)
        kg_rows, kg_cols, kg_vals = [], [], []
        for itf in self.ifaces:
            ev = itf.evaluate(x, hessian=matrix and self.geometric)
            evs.append(ev)
            dofs = itf.dofs(ev["mf"])
            gv = itf.grad_values(ev)
            Gq = sp.csr_matrix((gv.ravel(), dofs.ravel(), np.arange(0, 36 * itf.nq + 1, 36)),
                               shape=(itf.nq, self.ndof))
            gbar.append(itf.B @ ev["gr"])
            Gs.append(itf.B @ Gq)
            if matrix and self.geometric:
                tau = self.ks * (itf.B.T @ za[rows0:rows0 + itf.nc])      # (nq,) point forces
                nzq = np.nonzero(tau)[0]
                if len(nzq):
                    # group the points of one (slave face, master face) pair: one 36 x 36 block each
                    key = itf.face_of_q[nzq] * len(itf.master) + ev["mf"][nzq]
                    order = np.argsort(key, kind="stable")
                    nzq = nzq[order]
                    key = key[order]
                    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
                    W = itf.hess_W(ev)[nzq]
                    WC = np.matmul(W, ev["C"][nzq]) * tau[nzq, None, None]
                    blocks = np.add.reduceat(np.matmul(WC, np.swapaxes(W, 1, 2)), starts, axis=0)
                    d = dofs[nzq[starts]]
                    kg_rows.append(np.repeat(d, 36, axis=1).ravel())
                    kg_cols.append(np.tile(d, (1, 36)).ravel())
                    kg_vals.append(blocks.ravel())
            rows0 += itf.nc
        G = (sp.vstack(Gs).tocsr() @ sp.diags(self.mask)).tocsr() if Gs else sp.csr_matrix((0, self.ndof))
        gb = np.concatenate(gbar) if gbar else np.zeros(0)
        r = -self.ks * (G.T @ za)
        if matrix and self.geometric and kg_vals:
            Kg = sp.csr_matrix((np.concatenate(kg_vals), (np.concatenate(kg_rows), np.concatenate(kg_cols))),
                               shape=(self.ndof, self.ndof))
            Dm = sp.diags(self.mask)
            Kg = (Dm @ Kg @ Dm).tocsr()
        self.stats["t_contact"] += time.perf_counter() - t0
        return {"gbar": gb, "G": G, "r": r, "Kg": Kg, "evs": evs}

    # ---------------------------------------------------------------------------------------
    def residual(self, uvec, z, active, matrix=False):
        """Full residual [R_u; R_z] (and the saddle-point matrix as CSR)."""
        r, Kc = self._internal(uvec, matrix)
        if not np.all(np.isfinite(r)):
            return None, None, None
        if not self.ifaces:
            return r, (Kc if matrix else None), None
        c = self.contact(uvec, z, matrix, active)
        ru = r + c["r"]
        rz = np.where(active, -self.ks * c["gbar"], -self.ks * z)
        R = np.concatenate([ru, rz])
        if not matrix:
            return R, None, c
        Kt = Kc if c["Kg"] is None else (Kc + c["Kg"])
        Ga = (sp.diags(active.astype(float)) @ c["G"]).tocsr()
        D = sp.diags(np.where(active, 0.0, -self.ks))
        Jm = sp.bmat([[Kt, -self.ks * Ga.T], [-self.ks * Ga, D]], format="csr")
        return R, Jm, c

    def _solve_linear(self, Jm, rhs):
        from petsc4py import PETSc
        t0 = time.perf_counter()
        Jm.sort_indices()
        A = PETSc.Mat().createAIJ(size=Jm.shape, csr=(Jm.indptr.astype(PETSc.IntType),
                                                      Jm.indices.astype(PETSc.IntType), Jm.data))
        A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        A.assemble()
        ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("cholesky")
        pc.setFactorSolverType("mumps")
        ksp.setOperators(A)
        ksp.setUp()
        b = A.createVecLeft()
        b.array[:] = rhs
        x = A.createVecRight()
        ksp.solve(b, x)
        if ksp.getConvergedReason() < 0:
            raise ContactError(f"MUMPS failed (reason {ksp.getConvergedReason()})")
        out = x.array.copy()
        # destroy the factor and the PC explicitly: left to the garbage collector, petsc4py 3.18
        # keeps MUMPS's factors alive (tens of MB per factorization)
        pc.getFactorMatrix().destroy()
        pc.destroy()
        for o in (ksp, A, b, x):
            o.destroy()
        PETSc.garbage_cleanup()
        self.stats["factorizations"] += 1
        self.stats["t_solve"] += time.perf_counter() - t0
        return out

    def _update_active(self, z, gbar):
        if self.law == "unilateral":
            return ((z - self.ncp_c * gbar) > 0.0) & self.alive
        return self.active

    def update_contact_set(self, uvec: np.ndarray, tol: float = 1e-6) -> int:
        """Re-decide which slave points are over their master (at uvec); returns how many changed.
        The set is frozen during a Newton solve (so that Newton sees a smooth problem) and
        updated after it until it no longer changes."""
        if not self.ifaces:
            return 0
        x = self.positions(uvec)
        changed = 0
        for itf in self.ifaces:
            ev = itf.evaluate(x, hessian=False)
            on = ~(ev["border"] & (ev["zout"] > tol))
            changed += int(np.sum(on != itf.on))
            if np.any(on != itf.on):
                itf.set_on(on)
        self.alive = np.concatenate([i.alive for i in self.ifaces])
        if self.law == "sliding":
            self.active = self.alive.copy()
        else:
            self.active &= self.alive
        return changed

    def newton(self, uvec, z, rtol=1e-10, atol=1e-9, max_it=30):
        """Newton (semismooth for the unilateral law) from (uvec, z); residual-guarded steps.
        Returns (ok, its, uvec, z)."""
        ndof = self.ndof
        active = self.active.copy()
        R, Jm, c = self.residual(uvec, z, active, matrix=True)
        if R is None:
            return False, 0, uvec, z
        if self.law == "unilateral":
            new = self._update_active(z, c["gbar"])
            if np.any(new != active):
                active = new
                R, Jm, c = self.residual(uvec, z, active, matrix=True)
        r0 = r = float(np.linalg.norm(R))
        changed = True
        for it in range(max_it + 1):
            if r <= max(rtol * r0, atol) and not changed:
                self.active = active
                return True, it, uvec, z
            if it == max_it:
                return False, it, uvec, z
            self.stats["newton"] += 1
            d = self._solve_linear(Jm, -R)
            step, accepted = 1.0, False
            while step >= 1.0 / 16:
                u_t = uvec + step * d[:ndof]
                z_t = z + step * d[ndof:] if self.nc else z
                # the full step is usually taken: assemble its tangent at once
                R_t, J_t, c_t = self.residual(u_t, z_t, active, matrix=step == 1.0)
                if R_t is not None:
                    r_t = float(np.linalg.norm(R_t))
                    if r_t < r or (r < 1e-6 * r0 and r_t < 10 * r) or (step < 1.0 / 8 and r_t < 2 * r):
                        accepted = True
                        break
                step *= 0.5
            if not accepted:
                return False, it + 1, uvec, z
            floor = r < 1e-7 * r0 and r_t > 0.5 * r
            if self.debug:
                nb = sum(int(e["border"].sum()) for e in c_t["evs"]) if c_t else 0
                print(f"      it {it + 1}: |R| {r_t:.3e} (u {np.linalg.norm(R_t[:ndof]):.2e}, "
                      f"z {np.linalg.norm(R_t[ndof:]):.2e}) step {step:g} border {nb} "
                      f"|du| {np.abs(d[:ndof]).max():.2e}", flush=True)
            uvec, z = u_t, z_t
            changed = False
            if self.law == "unilateral":
                new = self._update_active(z, c_t["gbar"])
                changed = bool(np.any(new != active))
                active = new
            if step == 1.0 and not changed and J_t is not None:
                R, Jm, c = R_t, J_t, c_t
            else:
                R, Jm, c = self.residual(uvec, z, active, matrix=True)
            r = float(np.linalg.norm(R))
            if floor and not changed:
                self.active = active
                return True, it + 1, uvec, z
        return False, max_it, uvec, z

    def solve_path(self, levels, on_level=None, first_increment=None, max_increment=None,
                   max_cutbacks=10, predictor=True, log=None):
        """Load stepping through ``levels`` (load factors) with cut-backs and a secant predictor.
        Calls on_level(level, its) after each converged level.  Returns total Newton iterations."""
        uvec = np.zeros(self.ndof)
        z = np.zeros(self.nc)
        lam = 0.0
        prev = None                 # (lam, u, z) of the state before the last converged one
        dlam = first_increment or levels[0]
        its_total, cutbacks = 0, 0
        for level in levels:
            its_level = 0
            while lam < level - 1e-12:
                trial = min(lam + dlam, level)
                if max_increment:
                    trial = min(trial, lam + max_increment)
                if level - trial < 1e-9 * level:
                    trial = level
                self.set_load(trial)
                u0, z0 = uvec, z
                if predictor and prev is not None and lam - prev[0] > 0:
                    s = (trial - lam) / (lam - prev[0])
                    u0, z0 = uvec + s * (uvec - prev[1]), z + s * (z - prev[2])
                on0 = [i.on.copy() for i in self.ifaces]
                self.update_contact_set(uvec)
                act0 = self.active.copy()
                ok, n, u1, z1 = self.newton(u0, z0)
                if not ok and u0 is not uvec:       # predictor may have overshot: plain start
                    self.active = act0
                    its_total += n
                    its_level += n
                    ok, n, u1, z1 = self.newton(uvec, z)
                its_total += n
                its_level += n
                passes = 0
                while ok:                           # the contact set at the solution: a fixed point
                    ch = self.update_contact_set(u1)
                    if ch == 0:
                        break
                    passes += 1
                    self.set_changes += ch
                    if passes > 8:
                        ok = False
                        break
                    z1 = np.where(self.alive, z1, 0.0)
                    ok, n, u1, z1 = self.newton(u1, z1)
                    its_total += n
                    its_level += n
                self.set_passes += passes
                if ok:
                    prev = (lam, uvec, z)
                    lam, uvec, z = trial, u1, z1
                    if n <= 6:
                        dlam = dlam * 1.5
                    cutbacks = 0
                else:
                    for i, o in zip(self.ifaces, on0):
                        i.set_on(o)
                    if self.ifaces:
                        self.alive = np.concatenate([i.alive for i in self.ifaces])
                    self.active = act0
                    dlam = 0.5 * (trial - lam)
                    cutbacks += 1
                    if log:
                        log(f"    cut back at {trial:.4g} (Newton {n} its) -> increment {dlam:.4g}")
                    if cutbacks > max_cutbacks:
                        raise ContactError(f"Newton failed at load factor {trial:.4g}")
            self.uvec, self.zvec = uvec, z
            if on_level:
                on_level(level, its_level)
        self.uvec, self.zvec = uvec, z
        return its_total

    # ---------------------------------------------------------------------------------------
    def point_values(self, pts: np.ndarray, cell_tag: int) -> np.ndarray:
        """u at reference points (n, 3) inside the body with cell tag ``cell_tag``."""
        from dolfinx import geometry
        self.u.x.array[:] = self.uvec
        self.u.x.scatter_forward()
        body = set(self.ct.indices[self.ct.values == cell_tag].tolist())
        tree = geometry.BoundingBoxTree(self.msh, self.msh.topology.dim)
        cells = geometry.compute_colliding_cells(self.msh, geometry.compute_collisions(tree, pts), pts)
        out = []
        for i in range(len(pts)):
            cs = [c for c in cells.links(i) if c in body]
            if not cs:
                raise ContactError(f"point {pts[i]} not found in body {cell_tag}")
            out.append(np.asarray(self.u.eval(pts[i:i + 1], np.array([cs[0]], dtype=np.int32)),
                                  float).ravel())
        return np.array(out)

    def face_mean(self, tag: int) -> np.ndarray:
        """Mean displacement over a tagged face (reference area)."""
        from dolfinx import fem
        self.u.x.array[:] = self.uvec
        self.u.x.scatter_forward()
        a = fem.assemble_scalar(fem.form(1.0 * self.ds(tag)))
        return np.array([fem.assemble_scalar(fem.form(self.u[i] * self.ds(tag))) / a for i in range(3)])

    def gap_report(self) -> dict:
        """Pointwise |g − g0| (max, rms), weighted gaps, pressure range, active count."""
        if not self.ifaces:
            return {}
        c = self.contact(self.uvec, self.zvec, False, self.active)
        on = np.concatenate([i.on for i in self.ifaces])
        g = np.concatenate([ev["gr"] for ev in c["evs"]])[on]
        w = np.concatenate([i.w for i in self.ifaces])[on]
        ak = np.concatenate([i.ak for i in self.ifaces])
        p = self.ks * self.zvec / ak
        act = self.active
        return {"g_max": float(np.abs(g).max()), "g_rms": float(np.sqrt(np.sum(w * g ** 2) / w.sum())),
                "gbar_max_active": float(np.abs(c["gbar"][act]).max()) if act.any() else 0.0,
                "gbar_min": float(c["gbar"][self.alive].min()),
                "p_min": float(p.min()), "p_max": float(p.max()), "active": int(act.sum()), "nc": self.nc,
                "alive": int(self.alive.sum()), "off": int((~on).sum()),
                "set_passes": self.set_passes,
                "nq": int(sum(i.nq for i in self.ifaces))}


# ============================================================================================
# The tendon: solid runs
# ============================================================================================
def centroid_points(secs, psi: float, bodies=(0, 1, 2)) -> np.ndarray:
    """Reference end-section centroids a + R(psi)(c - a) on x = L."""
    from ancf_petsc.physics.geometry import place
    return np.vstack([place(np.array([LENGTH]), secs[b].centroid[None, :], LENGTH, psi, AXIS)
                      for b in bodies])


def tendon_problem(secs, psi: float, h: float, law: str | None, bodies=(0, 1, 2), loads_on=(0,),
                   layered: bool = True, **kw):
    """Mesh (timed) and Problem of the tendon: clamped roots, end traction 1 N x load factor on
    the end faces of ``loads_on``, contact on the interfaces between the chosen bodies."""
    t0 = time.perf_counter()
    msh, ct, ft = tendon_mesh(secs, h, psi, bodies, layered)
    t_mesh = time.perf_counter() - t0
    mats = {b + 1: (MU[b], KBULK) for b in bodies}
    dirich = [(10 + b, (0, 1, 2)) for b in bodies]
    tr = {20 + b: (1.0, 0.0, 0.0) for b in loads_on}
    ifs = []
    if law:
        ifs = [(cv, interface_tag(secs, s, cv), interface_tag(secs, m, cv)) for cv, s, m in INTERFACES
               if s in bodies and m in bodies]
    P = Problem(msh, ct, ft, mats, dirich, tr, ifs, law=law if ifs else None, **kw)
    return P, t_mesh


def run_solid(secs, psi: float, law: str | None, h: float, loads=LOADS, bodies=(0, 1, 2), log=print,
              **kw) -> dict:
    """One solid run over the load levels: per level the end-centroid u of each body, the soleus
    end-face mean, Newton iterations, cumulative wall time and the contact diagnostics."""
    t0 = time.perf_counter()
    P, t_mesh = tendon_problem(secs, psi, h, law, bodies, **kw)
    pts = centroid_points(secs, psi, bodies)
    levels = []
    t_solve0 = time.perf_counter()

    def on_level(level, its):
        u = [P.point_values(pts[i:i + 1], b + 1)[0] for i, b in enumerate(bodies)]
        rec = {"load": float(level), "its": its, "wall": time.perf_counter() - t_solve0,
               "u": {SHORT[b]: u[i] for i, b in enumerate(bodies)},
               "face": P.face_mean(20)}
        rec.update(P.gap_report())
        levels.append(rec)
        if log:
            extra = ""
            if "g_max" in rec:
                extra = (f", |g-g0| max {rec['g_max'] * 1e6:.2f} um, p [{rec['p_min'] / 1e6:+.2f}, "
                         f"{rec['p_max'] / 1e6:+.2f}] MPa, active {rec['active']}/{rec['nc']}, "
                         f"off-master points {rec['off']}/{rec['nq']}")
            log(f"    {level:5.0f} N: soleus u_x {1e3 * u[0][0]:.6f} mm, {its} its, "
                f"{rec['wall']:.1f} s{extra}")

    ok, msg = True, ""
    try:
        P.solve_path(list(loads), on_level=on_level, max_increment=50.0, log=log)
    except ContactError as exc:
        ok, msg = False, str(exc)
    return {"psi": psi, "law": law or "free", "h": h, "dofs": P.ndof, "nc": P.nc, "levels": levels,
            "ok": ok, "msg": msg, "t_mesh": t_mesh, "wall": time.perf_counter() - t_solve0,
            "stats": dict(P.stats), "ks": P.ks, "h_mean": P.h}


# ============================================================================================
# ANCF runs
# ============================================================================================
def run_ancf(psi: float, mode: str | None, elements: int, tmp: str) -> dict:
    """One ANCF column in-process; per load the x-displacement of r at each last node."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    beams = NAMES if mode else NAMES[:1]
    out = os.path.join(tmp, f"ancf_{psi:g}_{mode or 'free'}_{elements}")
    t0 = time.perf_counter()
    try:
        spec = parse_config(tendon_config(psi, elements, mode, out, beams), base_dir=CONFIGS)
        res = run_model(spec, log=lambda *_: None)
        status, message, s = res.status, res.message, res.summary
    except Exception as exc:   # record and go on
        status, message, s = "failed", f"{type(exc).__name__}: {exc}", None
    wall = time.perf_counter() - t0
    rec = {"psi": psi, "law": mode or "free", "elements": elements, "ok": status == "completed",
           "msg": "" if status == "completed" else str(message), "wall": wall, "levels": [],
           "dofs": int(s["dofs"]) if s else 0}
    if s:
        for st in s["steps"]:
            rec["levels"].append({"load": float(st.get("load_factor", st.get("level", float("nan")))),
                                  "its": int(st["iterations"]),
                                  "u": {SHORT[NAMES.index(n)]: np.array(st["probes"][n]["displacement"])
                                        for n in beams}})
    return rec


# ============================================================================================
# Self-tests
# ============================================================================================
def uniaxial_stretch(mu: float, K: float, P: float) -> tuple[float, float]:
    """Stretches (along the load, lateral) of the neo-Hookean block under the dead uniaxial
    first Piola-Kirchhoff stress P with free lateral faces."""
    from scipy.optimize import fsolve

    def eqs(v):
        l1, l2 = v
        J, I1 = l1 * l2 * l2, l1 * l1 + 2 * l2 * l2
        d1 = mu / 2 * (-2 / 3 * J ** (-5 / 3) * l2 * l2 * I1 + 2 * l1 * J ** (-2 / 3)) + K * (J - 1) * l2 * l2
        d2 = mu / 2 * (-4 / 3 * J ** (-5 / 3) * l1 * l2 * I1 + 4 * l2 * J ** (-2 / 3)) + K * (J - 1) * 2 * l1 * l2
        return [d1 - P, d2]
    l1, l2 = fsolve(eqs, [1.0 + P / (3 * mu), 1.0 - P / (6 * mu)], xtol=1e-15)
    return float(l1), float(l2)


def selftest_single_bodies(secs, h: float, psi: float, force: float, log=print) -> dict:
    """(1) Contact off: the three bodies in one mesh, each pulled at its end, against
    verify_solid.solve_solid on each body meshed alone (same h)."""
    t0 = time.perf_counter()
    P, _ = tendon_problem(secs, psi, h, None, loads_on=(0, 1, 2))
    P.solve_path([0.25 * force, 0.5 * force, 0.75 * force, force])
    pts = centroid_points(secs, psi)
    out = {}
    for b in range(3):
        mine = P.point_values(pts[b:b + 1], b + 1)[0]
        case = vs.Case(SHORT[b], SHORT[b], {"shape": "outline", "file": SECTIONS_FILE, "loop": NAMES[b],
                                           "spline_degree": 3, "cubature_degree": 6},
                       {"mu": MU[b], "bulk_modulus": KBULK}, (force, 0.0, 0.0), h=(h,), h_quick=(h,),
                       length=LENGTH, twist_deg=psi, twist_axis=AXIS)
        ref = vs.solve_solid(case, secs[b], vs.solid_mesh(case, secs[b], h))
        d = float(np.linalg.norm(mine - ref["u"]) / np.linalg.norm(ref["u"]))
        out[SHORT[b]] = {"mine": mine, "ref": ref["u"], "rel": d, "dofs_ref": ref["dofs"]}
        log(f"  [1] {SHORT[b]:8s} alone, {force:g} N, h {h * 1e3:g} mm: u_end here "
            f"{_fmt(mine)} mm, verify_solid {_fmt(ref['u'])} mm, relative difference {d:.2e}")
    out["dofs"] = P.ndof
    out["time"] = time.perf_counter() - t0
    return out


def _fmt(u) -> str:
    return "(" + ", ".join(f"{1e3 * x:+.6f}" for x in u) + ")"


def selftest_blocks(log=print, hA=0.45e-3, hB=0.32e-3) -> list:
    """(2) Patch tests: two blocks with a flat shared interface y = 0, non-matching meshes,
    different materials, symmetry rollers; the homogeneous analytic solution must be reproduced
    (P2 contains it).  'pull'/'press': dead traction ±t on B's outer face y = ly, carried through
    the interface in tension/compression (the blocks contract differently: they slide laterally).
    'slide': A and B pulled along x by different tractions: B slides along A by several elements."""
    lx, ly, lz = 4e-3, 1e-3, 1e-3
    msh, ct, ft = blocks_mesh(hA, hB, (lx, ly, lz))
    muA, muB, Kb = 1.0e6, 3.0e6, 2.0e7
    mats = {1: (muA, Kb), 2: (muB, Kb)}
    res = []
    cases = [("pull", "sliding", 0.6e6), ("press", "sliding", -0.6e6), ("press", "unilateral", -0.6e6),
             ("slide", "sliding", (0.3e6, 1.2e6)), ("slide", "unilateral", (0.3e6, 1.2e6, -0.05e6))]
    for kind, law, t in cases:
        if kind in ("pull", "press"):
            dirich = [(10, (0,)), (11, (0,)), (30, (2,)), (31, (2,)), (40, (1,))]
            tr = {41: (0.0, t * lx * lz, 0.0)}
        else:
            dirich = [(10, (0,)), (11, (0,)), (30, (2,)), (31, (2,)), (40, (1,))]
            tr = {20: (t[0] * ly * lz, 0.0, 0.0), 21: (t[1] * ly * lz, 0.0, 0.0)}
            if len(t) > 2:   # a light compression across the interface keeps it closed
                tr[41] = (0.0, t[2] * lx * lz, 0.0)
        P = Problem(msh, ct, ft, mats, dirich, tr, [("y0", 200, 100)], law=law)
        t0 = time.perf_counter()
        P.solve_path([0.25, 0.5, 0.75, 1.0])
        U = P.uvec.reshape(-1, 3)
        X = P.X
        dm = P.V.dofmap.list.array.reshape(-1, 10)
        inB = np.zeros(len(X), dtype=bool)
        inB[np.unique(dm[ct.indices[ct.values == 2]].ravel())] = True
        ex = np.zeros_like(X)
        if kind in ("pull", "press"):
            (a1, a2), (b1, b2) = uniaxial_stretch(muA, Kb, t), uniaxial_stretch(muB, Kb, t)
            A = ~inB
            ex[A] = np.column_stack([(a2 - 1) * X[A, 0], (a1 - 1) * (X[A, 1] + ly), (a2 - 1) * X[A, 2]])
            ex[inB] = np.column_stack([(b2 - 1) * X[inB, 0], (a1 - 1) * ly + (b1 - 1) * X[inB, 1],
                                       (b2 - 1) * X[inB, 2]])
            slide = abs(b2 - a2) * lx
        else:
            tyy = t[2] if len(t) > 2 else 0.0
            # with a lateral traction tyy the blocks are biaxially loaded: solve the general case
            (a1, a2, a3), (b1, b2, b3) = _biaxial(muA, Kb, t[0], tyy), _biaxial(muB, Kb, t[1], tyy)
            A = ~inB
            ex[A] = np.column_stack([(a1 - 1) * X[A, 0], (a2 - 1) * (X[A, 1] + ly), (a3 - 1) * X[A, 2]])
            ex[inB] = np.column_stack([(b1 - 1) * X[inB, 0], (a2 - 1) * ly + (b2 - 1) * X[inB, 1],
                                       (b3 - 1) * X[inB, 2]])
            slide = abs(b1 - a1) * lx
        err = float(np.abs(U - ex).max() / np.abs(ex).max())
        rep = P.gap_report()
        pexp = abs(t) if kind == "press" else (-t if kind == "pull" else abs(t[2]) if len(t) > 2 else 0.0)
        res.append({"kind": kind, "law": law, "err": err, "slide": slide, "h": (hA, hB),
                    "g_max": rep["g_max"], "p_min": rep["p_min"], "p_max": rep["p_max"], "p_exact": pexp,
                    "active": rep["active"], "nc": rep["nc"], "time": time.perf_counter() - t0,
                    "its": P.stats["newton"], "dofs": P.ndof})
        log(f"  [2] blocks {kind:5s} {law:10s}: max nodal |u - u_exact| / max |u_exact| = {err:.2e}; "
            f"relative slide {slide * 1e3:.3f} mm (h {hB * 1e3:.2f}/{hA * 1e3:.2f} mm); pointwise |g - g0| "
            f"max {rep['g_max']:.1e} m; contact pressure [{rep['p_min'] / 1e6:+.4f}, {rep['p_max'] / 1e6:+.4f}] "
            f"MPa (exact {pexp / 1e6:+.4f}); active {rep['active']}/{rep['nc']}; {P.stats['newton']} Newton its")
    return res


def _biaxial(mu, K, px, py):
    """Stretches (x, y, z) of the neo-Hookean block under dead PK1 stresses px (x), py (y), 0 (z)."""
    from scipy.optimize import fsolve

    def eqs(v):
        l = np.asarray(v)
        J, I1 = np.prod(l), np.sum(l * l)
        d = mu / 2 * (-2 / 3 * J ** (-5 / 3) * (J / l) * I1 + 2 * l * J ** (-2 / 3)) + K * (J - 1) * J / l
        return d - np.array([px, py, 0.0])
    return tuple(float(x) for x in fsolve(eqs, [1 + px / (3 * mu), 1 + py / (3 * mu), 1.0], xtol=1e-15))


def selftest_fd(secs, h: float, psi: float, log=print) -> list:
    """(3) Central differences of the contact residual and of the full residual against the
    assembled Jacobian on the tendon mesh, at a deformed state with sliding (both laws)."""
    out = []
    rng = np.random.default_rng(7)
    for law in ("sliding", "unilateral"):
        P, _ = tendon_problem(secs, psi, h, law)
        P.set_load(60.0)
        X = P.X
        dm = P.V.dofmap.list.array.reshape(-1, 10)
        sol = np.unique(dm[P.ct.indices[P.ct.values == 1]].ravel())
        U = np.zeros_like(X)
        U[:, 0] = 0.005 * X[:, 0]
        U[sol, 0] += 0.03 * X[sol, 0]                 # the soleus slides by 2 mm at the end
        U[:, 1] += 0.01 * (X[:, 0] / LENGTH) * (X[:, 2] - AXIS[1])
        U[:, 2] -= 0.01 * (X[:, 0] / LENGTH) * (X[:, 1] - AXIS[0])
        u = U.ravel() * P.mask
        z = rng.normal(size=P.nc) * 1e-6
        active = rng.random(P.nc) < (1.0 if law == "sliding" else 0.7)
        P.active = active
        R, Jm, c = P.residual(u, z, active, matrix=True)
        du = rng.normal(size=P.ndof) * P.mask
        dz = rng.normal(size=P.nc) * 1e-6 / h
        d = np.concatenate([du, dz])
        Jd = Jm @ d
        rec = {"law": law, "h": h, "ndof": P.ndof, "nc": P.nc,
               "border": int(sum(e["border"].sum() for e in c["evs"]))}
        for eps in (1e-5, 1e-6, 1e-7):
            e = eps * h
            Rp, _, cp = P.residual(u + e * du, z + e * dz, active)
            Rm, _, cm = P.residual(u - e * du, z - e * dz, active)
            fd = (Rp - Rm) / (2 * e)
            fdg = (cp["gbar"] - cm["gbar"]) / (2 * e)
            fdc = (cp["r"] - cm["r"]) / (2 * e)          # contact forces only
            Jc = (c["Kg"] @ du if c["Kg"] is not None else 0.0) - P.ks * (
                (sp.diags(active.astype(float)) @ c["G"]).T @ dz)
            rec[eps] = {"full": float(np.linalg.norm(fd - Jd) / np.linalg.norm(Jd)),
                        "gbar": float(np.linalg.norm(fdg - c["G"] @ du) / np.linalg.norm(c["G"] @ du)),
                        "contact_force": float(np.linalg.norm(fdc - Jc) / np.linalg.norm(fdc))}
            log(f"  [3] FD {law:10s} eps {eps:g} h: |FD - J d| / |J d| full {rec[eps]['full']:.2e}, "
                f"weighted gaps {rec[eps]['gbar']:.2e}, contact forces {rec[eps]['contact_force']:.2e}")
        # without the geometric stiffness: how much of the contact force derivative it carries
        P.geometric = False
        _, Jm0, c0 = P.residual(u, z, active, matrix=True)
        rec["no_geo_full"] = float(np.linalg.norm((Jm0 @ d) - Jd) / np.linalg.norm(Jd))
        log(f"  [3] FD {law:10s}: the geometric term is {rec['no_geo_full']:.2e} of |J d| "
            f"({rec['border']} of the points off the master surface, none expected here)")
        out.append(rec)
    return out


def selftest(secs, log=print) -> dict:
    log("[selftest] (1) contact off: each body against verify_solid.solve_solid")
    r1 = selftest_single_bodies(secs, 3e-3, 45.0, 20.0, log)
    log("[selftest] (2) patch tests: two blocks, flat interface, non-matching meshes")
    r2 = selftest_blocks(log)
    log("[selftest] (3) finite differences on the tendon (h 3 mm, psi 45 deg)")
    r3 = selftest_fd(secs, 3e-3, 45.0, log)
    return {"single": r1, "blocks": r2, "fd": r3}


# ============================================================================================
# Reference values, CSV, report, figure
# ============================================================================================
CSV_FIELDS = ["psi_deg", "law", "model", "resolution", "h_m", "elements", "dofs", "load_N",
              "soleus_ux_m", "medial_ux_m", "lateral_ux_m", "soleus_face_ux_m", "uncertainty_rel",
              "wall_s", "newton_its", "gap_max_m", "note"]
SOLID, ANCF, REF = "solid P2 tet", "ANCF 2pt", "solid reference (Richardson)"


def solid_rows(run: dict) -> list:
    rows = []
    for lv in run["levels"]:
        u = lv["u"]
        note = "" if run["ok"] else f"run stopped: {run['msg']}"
        if "p_min" in lv:
            note = (f"p [{lv['p_min'] / 1e6:+.3f}, {lv['p_max'] / 1e6:+.3f}] MPa; active {lv['active']}/{lv['nc']}; "
                    f"slave points past the master's edge {lv['off']}/{lv['nq']}" + ("; " + note if note else ""))
        rows.append({"psi_deg": run["psi"], "law": run["law"], "model": SOLID,
                     "resolution": f"h {run['h'] * 1e3:.2f} mm", "h_m": run["h"], "elements": "",
                     "dofs": run["dofs"], "load_N": lv["load"],
                     "soleus_ux_m": u["soleus"][0], "medial_ux_m": u.get("medial", [np.nan])[0],
                     "lateral_ux_m": u.get("lateral", [np.nan])[0], "soleus_face_ux_m": lv["face"][0],
                     "uncertainty_rel": "", "wall_s": lv["wall"], "newton_its": lv["its"],
                     "gap_max_m": lv.get("g_max", ""), "note": note})
    if not run["levels"] or not run["ok"]:
        rows.append({"psi_deg": run["psi"], "law": run["law"], "model": SOLID,
                     "resolution": f"h {run['h'] * 1e3:.2f} mm", "h_m": run["h"], "dofs": run["dofs"],
                     "load_N": "", "note": f"FAILED: {run['msg']}"})
    return rows


def ancf_rows(run: dict) -> list:
    rows = []
    for lv in run["levels"]:
        u = lv["u"]
        rows.append({"psi_deg": run["psi"], "law": run["law"], "model": ANCF,
                     "resolution": f"{run['elements']} el.", "h_m": "", "elements": run["elements"],
                     "dofs": run["dofs"], "load_N": lv["load"], "soleus_ux_m": u["soleus"][0],
                     "medial_ux_m": u["medial"][0] if "medial" in u else np.nan,
                     "lateral_ux_m": u["lateral"][0] if "lateral" in u else np.nan, "soleus_face_ux_m": "",
                     "uncertainty_rel": "", "wall_s": run["wall"], "newton_its": lv["its"], "gap_max_m": "",
                     "note": ""})
    if not run["ok"]:
        rows.append({"psi_deg": run["psi"], "law": run["law"], "model": ANCF,
                     "resolution": f"{run['elements']} el.", "elements": run["elements"], "dofs": run["dofs"],
                     "load_N": "", "wall_s": run["wall"], "note": f"FAILED: {run['msg']}"})
    return rows


def _num(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


def reference_rows(rows: list) -> list:
    """Richardson extrapolation (verify_solid.richardson: finest three meshes, h ~ DOFs^-1/3,
    fitted order; or the finest mesh with its last change) per (psi, law, load) for each of the
    four quantities; the soleus end-centroid's uncertainty in ``uncertainty_rel``."""
    out = []
    keys = sorted({(r["psi_deg"], r["law"]) for r in rows if r["model"] == SOLID}, key=lambda k: (_num(k[0]), k[1]))
    for psi, law in keys:
        fam = [r for r in rows if r["model"] == SOLID and r["psi_deg"] == psi and r["law"] == law
               and r["load_N"] not in ("", None)]
        hs = sorted({_num(r["h_m"]) for r in fam}, reverse=True)
        loads = sorted({_num(r["load_N"]) for r in fam})
        for F in loads:
            per_h = []
            for h in hs:
                r = [x for x in fam if _num(x["h_m"]) == h and _num(x["load_N"]) == F]
                if r:
                    per_h.append(r[0])
            if len(per_h) < 2 or len(per_h) < len(hs):
                continue
            rec = {"psi_deg": psi, "law": law, "model": REF, "resolution": "", "h_m": "", "elements": "",
                   "dofs": "", "load_N": F, "wall_s": "", "newton_its": "", "gap_max_m": ""}
            notes = []
            for q in ("soleus_ux_m", "medial_ux_m", "lateral_ux_m", "soleus_face_ux_m"):
                vals = [_num(r[q]) for r in per_h]
                if not np.all(np.isfinite(vals)):
                    rec[q] = ""
                    continue
                solids = [{"u": np.array([v]), "dofs": int(_num(r["dofs"]))} for v, r in zip(vals, per_h)]
                ref, unc, how = vs.richardson(solids)
                rec[q] = float(ref[0]) if vals[-1] >= 0 else -float(ref[0])
                if q == "soleus_ux_m":
                    rec["uncertainty_rel"] = unc
                    notes.append(how)
            rec["resolution"] = f"{len(per_h)} meshes, h {1e3 * hs[0]:.2f}-{1e3 * hs[-1]:.2f} mm"
            rec["note"] = "; ".join(notes)
            out.append(rec)
    return out


def write_csv(path: str, rows: list) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=CSV_FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            d = {}
            for k in CSV_FIELDS:
                v = r.get(k, "")
                if isinstance(v, float):
                    v = "" if not np.isfinite(v) else (f"{v:.10e}" if k.endswith("_m") or k == "uncertainty_rel"
                                                       else f"{v:.6g}")
                d[k] = v
            w.writerow(d)


def read_csv(path: str) -> list:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def ancf_errors(rows: list) -> dict:
    """Relative error of the ANCF soleus elongation against the solid reference, per (psi, law,
    elements): worst over the loads, at 10 N and at 400 N (NaN where missing)."""
    refs = {(r["psi_deg"], r["law"], _num(r["load_N"])): r for r in rows if r["model"] == REF}
    out = {}
    for r in rows:
        if r["model"] != ANCF or r["load_N"] in ("", None):
            continue
        ref = refs.get((r["psi_deg"], r["law"], _num(r["load_N"])))
        if ref is None:
            continue
        e = (_num(r["soleus_ux_m"]) - _num(ref["soleus_ux_m"])) / _num(ref["soleus_ux_m"])
        d = out.setdefault((r["psi_deg"], r["law"], int(_num(r["elements"]))), {})
        d[_num(r["load_N"])] = e
    return out


def plot(path: str, rows: list) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    errs = ancf_errors(rows)
    psis = sorted({k[0] for k in errs}, key=_num)
    laws = [l for l in ("sliding", "unilateral", "free") if any(k[1] == l for k in errs)]
    if not psis:
        return
    fig, axes = plt.subplots(1, len(psis), figsize=(4.6 * len(psis), 4.0), squeeze=False, sharey=True)
    style = {"sliding": ("C0", "o"), "unilateral": ("C1", "s"), "free": ("C2", "^")}
    unc = {(r["psi_deg"], r["law"]): max(_num(x["uncertainty_rel"]) for x in rows
                                          if x["model"] == REF and x["psi_deg"] == r["psi_deg"]
                                          and x["law"] == r["law"])
           for r in rows if r["model"] == REF}
    for ax, psi in zip(axes[0], psis):
        for law in laws:
            col, mk = style[law]
            ks = sorted(k for k in errs if k[0] == psi and k[1] == law)
            if not ks:
                continue
            n = [k[2] for k in ks]
            worst = [max(abs(v) for v in errs[k].values()) if len(errs[k]) == len(LOADS) else np.nan for k in ks]
            e10 = [abs(errs[k].get(10.0, np.nan)) for k in ks]
            e400 = [abs(errs[k].get(400.0, np.nan)) for k in ks]
            ax.loglog(n, worst, "-", marker=mk, color=col, label=f"{law}: worst over 10-400 N")
            ax.loglog(n, e10, "--", marker=mk, color=col, mfc="none", label=f"{law}: 10 N")
            ax.loglog(n, e400, ":", marker=mk, color=col, mfc="none", label=f"{law}: 400 N")
            if (psi, law) in unc and np.isfinite(unc[(psi, law)]):
                ax.axhline(unc[(psi, law)], color=col, lw=0.6, alpha=0.5)
        ax.set_xscale("log", base=2)
        ax.set_xticks([2, 4, 8, 16])
        ax.set_xticklabels(["2", "4", "8", "16"])
        ax.set_title(f"psi = {_num(psi):g} deg")
        ax.set_xlabel("ANCF elements per subtendon")
        ax.grid(True, which="both", lw=0.3, alpha=0.6)
    axes[0][0].set_ylabel("|relative error| of the soleus elongation")
    h, l = axes[0][0].get_legend_handles_labels()
    fig.legend(h, l, loc="lower center", ncol=3, fontsize=7.5, frameon=False)
    fig.suptitle("ANCF (2 axial points) against the 3D solid reference (thin lines: the reference's "
                 "uncertainty)", fontsize=9.5)
    fig.tight_layout(rect=(0, 0.12, 1, 0.95))
    fig.savefig(path, dpi=130)
    plt.close(fig)


def check_row(name: str, value: float, text: str, psi="", law="") -> dict:
    """A verification result as a CSV row (model 'check'): the number in uncertainty_rel."""
    return {"psi_deg": psi, "law": law, "model": "check", "resolution": name, "uncertainty_rel": value,
            "note": text}


def selftest_rows(st: dict) -> list:
    rows = []
    s = st["single"]
    worst = max(s[b]["rel"] for b in SHORT)
    rows.append(check_row("single bodies vs verify_solid", worst,
                          "contact off, the three bodies of one mesh each pulled by 20 N at its end (psi 45, h 3 mm), "
                          "against verify_solid.solve_solid on each body meshed alone with its unstructured mesh: "
                          + "; ".join(f"{b} {1e3 * s[b]['mine'][0]:.5f} vs {1e3 * s[b]['ref'][0]:.5f} mm "
                                      f"(|du|/|u| {s[b]['rel']:.2e})" for b in SHORT)))
    for r in st["blocks"]:
        rows.append(check_row(f"patch {r['kind']} {r['law']}", r["err"],
                              f"two blocks, flat interface, non-matching meshes (h {r['h'][1] * 1e3:.2f}/"
                              f"{r['h'][0] * 1e3:.2f} mm), relative slide {r['slide'] * 1e3:.3f} mm: max nodal "
                              f"|u - u_exact|/max|u_exact| {r['err']:.2e}; pointwise |g - g0| max {r['g_max']:.1e} m; "
                              f"pressure [{r['p_min'] / 1e6:+.5f}, {r['p_max'] / 1e6:+.5f}] MPa (exact "
                              f"{r['p_exact'] / 1e6:+.5f}); active {r['active']}/{r['nc']}; {r['its']} Newton its"))
    for r in st["fd"]:
        e = min(r[k]["full"] for k in (1e-5, 1e-6, 1e-7))
        rows.append(check_row(f"finite differences {r['law']}", e,
                              f"tendon psi 45 deg, h {r['h'] * 1e3:g} mm ({r['ndof']} DOFs, {r['nc']} multipliers), "
                              "deformed state with 2 mm of sliding; |FD - J d|/|J d| at eps = 1e-5/1e-6/1e-7 h: "
                              "full system " + "/".join(f"{r[k]['full']:.1e}" for k in (1e-5, 1e-6, 1e-7))
                              + ", weighted gaps " + "/".join(f"{r[k]['gbar']:.1e}" for k in (1e-5, 1e-6, 1e-7))
                              + ", contact forces " + "/".join(f"{r[k]['contact_force']:.1e}" for k in (1e-5, 1e-6, 1e-7))
                              + f"; without the gap Hessian the tangent is off by {r['no_geo_full']:.1e} of |J d|"))
    return rows


def independence_rows(base: dict, other: dict, label: str) -> list:
    """Largest relative difference of the four end quantities between two runs (same mesh)."""
    worst, where = 0.0, ""
    for a, b in zip(base["levels"], other["levels"]):
        for q in a["u"]:
            d = abs(a["u"][q][0] - b["u"][q][0]) / abs(a["u"]["soleus"][0])
            if d > worst:
                worst, where = d, f"{q} at {a['load']:g} N"
    n = min(len(base["levels"]), len(other["levels"]))
    ok = base["ok"] and other["ok"]
    return [check_row(f"independence {label}", worst,
                      f"{label}: largest difference of the end-centroid u_x (relative to the soleus') over "
                      f"{n} load levels {worst:.1e} ({where}); h {base['h'] * 1e3:.2f} mm"
                      + ("" if ok else "; a run did not complete"), base["psi"], base["law"])]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--psi", default="0,15,45", help="pretwist angles [deg]")
    ap.add_argument("--laws", default="sliding,unilateral", help="contact laws: sliding,unilateral")
    ap.add_argument("--h", default="2e-3,1.4e-3,1e-3", help="solid mesh sizes [m], coarse to fine")
    ap.add_argument("--elements", default="2,4,8,16", help="ANCF elements per subtendon")
    ap.add_argument("--quick", action="store_true", help="coarse meshes only (smoke run)")
    ap.add_argument("--selftest", action="store_true", help="only the contact self-tests")
    ap.add_argument("--no-selftest", action="store_true", help="skip the self-tests in a full run")
    ap.add_argument("--no-checks", action="store_true", help="skip the k_s / NCP-parameter checks")
    ap.add_argument("--no-free", action="store_true", help="skip the free soleus")
    ap.add_argument("--rule-points", type=int, default=3, choices=(3, 6, 7),
                    help="Gauss points per sub-triangle of a slave face (4 sub-triangles)")
    ap.add_argument("--replot", action="store_true", help="figure and report from the CSV (no solving)")
    ap.add_argument("--report", action="store_true", help="same as --replot")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs"), help="output directory")
    args = ap.parse_args(argv)
    csv_path = os.path.join(args.out, "solid_contact.csv")
    md_path = os.path.join(args.out, "solid_contact.md")
    png_path = os.path.join(args.out, "figures", "solid_contact.png")
    os.makedirs(os.path.dirname(png_path), exist_ok=True)
    if args.replot or args.report:
        rows = read_csv(csv_path)
        plot(png_path, rows)
        with open(md_path, "w") as fh:
            fh.write(render_md(rows, {}))
        print(f"[solid-contact] rewrote {md_path} and {png_path} from {csv_path}")
        return 0
    vs._import_stack()
    t_start = time.perf_counter()
    secs = tendon_sections()
    if args.selftest:
        st = selftest(secs)
        for r in selftest_rows(st):
            print(f"[selftest] {r['resolution']}: {r['uncertainty_rel']:.2e}")
        return 0
    psis = [float(p) for p in args.psi.split(",") if p.strip()]
    laws = [l.strip() for l in args.laws.split(",") if l.strip()]
    bad = set(laws) - {"sliding", "unilateral"}
    if bad:
        raise ContactError(f"unknown law(s) {sorted(bad)}")
    hs = [float(h) for h in args.h.split(",")]
    elements = [int(e) for e in args.elements.split(",")]
    if args.quick:
        hs, elements = [3e-3, 2e-3], [e for e in elements if e <= 4] or [2]
    kw = {"rule_points": args.rule_points}
    rows: list = []
    meta = {"argv": " ".join(sys.argv[1:]), "h": hs, "rule_points": args.rule_points}

    def save():
        write_csv(csv_path, rows + reference_rows(rows))

    if not args.no_selftest:
        print("[solid-contact] self-tests", flush=True)
        rows += selftest_rows(selftest(secs))
        save()
    with tempfile.TemporaryDirectory(prefix="solid_contact_") as tmp:
        for psi in psis:
            runs = [(None, (0,))] if not args.no_free else []
            runs += [(law, (0, 1, 2)) for law in laws]
            for law, bodies in runs:
                for h in hs:
                    print(f"[solid] psi {psi:g}, {law or 'free soleus'}, h {h * 1e3:.2f} mm", flush=True)
                    r = run_solid(secs, psi, law, h, bodies=bodies, **kw)
                    print(f"[solid]   {r['dofs']} DOFs, {r['nc']} multipliers, {r['wall']:.0f} s "
                          f"(+ mesh {r['t_mesh']:.0f} s), {r['stats']['newton']} Newton its"
                          + ("" if r["ok"] else f", FAILED: {r['msg']}"), flush=True)
                    rows += solid_rows(r)
                    save()
            for law in ([None] if not args.no_free else []) + laws:
                for ne in elements:
                    a = run_ancf(psi, law, ne, tmp)
                    print(f"[ancf] psi {psi:g}, {law or 'free'}, {ne} el.: "
                          + (f"soleus u_x(400 N) {1e3 * a['levels'][-1]['u']['soleus'][0]:.5f} mm, "
                             f"{a['wall']:.1f} s" if a["ok"] else f"FAILED ({a['msg']})"), flush=True)
                    rows += ancf_rows(a)
            save()
        if not args.no_checks:
            psi, h = psis[-1], hs[0]
            print(f"[solid-contact] independence checks at psi {psi:g}, h {h * 1e3:.2f} mm", flush=True)
            for law in laws:
                base = run_solid(secs, psi, law, h, log=None, **kw)
                other = run_solid(secs, psi, law, h, log=None, ks=100.0 * base["ks"], **kw)
                rows += independence_rows(base, other, f"{law}: multiplier unit k_s x 100")
                if law == "unilateral":
                    other = run_solid(secs, psi, law, h, log=None, ncp_c=100.0, **kw)
                    rows += independence_rows(base, other, f"{law}: NCP parameter c = 1 -> 100")
                save()
    rows += reference_rows(rows)
    write_csv(csv_path, rows)
    plot(png_path, rows)
    meta["total"] = time.perf_counter() - t_start
    with open(md_path, "w") as fh:
        fh.write(render_md(rows, meta))
    print(f"[solid-contact] {meta['total']:.0f} s; wrote {md_path}, {csv_path}, {png_path}")
    return 0


def _fmt_pct(x: float, digits: int = 3) -> str:
    return "—" if not np.isfinite(x) else f"{100 * x:+.{digits}f} %"


def render_md(rows: list, meta: dict) -> str:
    """The Markdown report, from the rows alone (so that --report can redo it from the CSV)."""
    import platform
    solids = [r for r in rows if r["model"] == SOLID and r["load_N"] not in ("", None)]
    refs = [r for r in rows if r["model"] == REF]
    checks = [r for r in rows if r["model"] == "check"]
    psis = sorted({_num(r["psi_deg"]) for r in solids})
    laws = [l for l in ("sliding", "unilateral", "free") if any(r["law"] == l for r in solids)]
    hs = sorted({_num(r["h_m"]) for r in solids}, reverse=True)
    L = []
    L.append("# Three-subtendon Achilles tendon: 3D solid reference with frictionless contact\n")
    gen = "Generated by `scripts/verify_solid_contact.py"
    gen += (" " + meta["argv"] if meta.get("argv") else "") + "`"
    if meta.get("total"):
        gen += f" in {meta['total'] / 60:.0f} min (1 core, {platform.machine()})"
    gen += "; `--report` redraws this page and the figure from `docs/solid_contact.csv`."
    L.append(gen + "\n")
    L.append("""## What is solved

* **Geometry.** The Type III tendon of `configs/achilles_type3_psi*.yaml`: the outlines `soleus`,
  `medial_gastrocnemius`, `lateral_gastrocnemius` of `configs/data/achilles_type3_sections.yaml`
  (cubic splines, as the ANCF sections), L = 70 mm, pretwist ψ about the triple point
  (y, z) = (5.896, −2.984) mm.  Each subtendon is its own body: its straight prism is meshed on
  its own (no shared nodes; each body has its own interface faces), every geometry node is then
  mapped through `ancf_petsc.physics.geometry.place` (the ANCF pretwist map).  Quadratic
  tetrahedra (P2 geometry and displacement), quadrature degree 2 (as `verify_solid.py`).
* **Mesh.** Layered: each section is triangulated with size h (the shared interface curves get
  the same 1D mesh on both sides) and extruded in layers of h within 7 mm of each end and
  ≈ 2.5 h in between, each prism split into three tetrahedra.  Every size scales with h.  The
  layers keep a body's cross-section tessellation the same at every x, so a body sliding along
  x meets the same polygonal neighbour everywhere.  (With gmsh's unstructured tetrahedra the two
  P2 tessellations of a curved interface differ by up to 20 µm at h = 2 mm, and a body sliding
  several elements rides over that washboard: its elongation changed by 0.3 % from h = 2 to
  1.4 mm, against 0.02–0.05 % with layers.)
* **Material.** Ψ = μ/2 (J^(−2/3) I1 − 3) + K/2 (J − 1)², μ = 103.1 / 143.2 / 226.7 MPa (soleus /
  medial / lateral), K = 0.86 GPa.
* **Supports and load.** Root faces x = 0 of all three bodies clamped (u = 0).  Soleus end face
  x = L: uniform dead traction F/A along +x (A = that face's area in the mesh), F = 10, 20, 30,
  40, 45, 60, 80, 90, 100, 150, 200, 300, 400 N (Table 1's levels).  Gastrocnemius end faces free.
* **Contact.** Interfaces (slave on master): medial on soleus, lateral on soleus, medial on
  lateral (the soleus moves past its neighbours' ends, so they stay on it).  Gauss points on the
  slave's P2 faces (4 sub-triangles × 3 points) are projected onto the master's deformed P2 faces
  every Newton iteration (closest point, candidates from a k-d tree of the current face centres,
  the last face first); g = (x_s − x_m)·n_m along the outward master normal, minus the point's
  reference gap g0.  Points past the master's edge (its end, the edges of the interface strip)
  use the smooth extension of the nearest master face.  Constraints: one weighted gap per slave
  node, ḡ_k = Σ w φ_k (g − g0) / Σ w φ_k, with φ_k the node's hat function on the 4-triangle split
  of the P2 slave faces (mortar-type, piecewise-linear multipliers on quadratic faces; nodes on
  the clamped root carry none).  **sliding**: ḡ = 0 (holds in tension and compression);
  **unilateral**: ḡ ≥ 0, Λ ≥ 0, Λ ḡ = 0.  Enforced exactly by Lagrange multipliers: Newton on the
  symmetric saddle-point system with the consistent gap Hessian, MUMPS LDLᵀ, a new projection and
  factorisation every iteration; unilateral: semismooth Newton (active where z − c ḡ > 0).
  There is no penalty: the checks below change the multipliers' unit k_s (and c) instead.
* **Quantities.** u_x at the reference end-section centroid place(L, c) of each body (the
  soleus' is the soleus elongation), and the mean u_x of the soleus end face.  The converged
  solid answer per (ψ, law, load) is `verify_solid.richardson` over the meshes (h ∝ DOFs^(−1/3),
  fitted order) or, when the changes do not shrink, the finest mesh with its last change as the
  uncertainty.
""")
    # meshes
    if solids:
        L.append("Meshes (DOFs incl. all three bodies; free soleus in brackets): " + ", ".join(
            f"h {1e3 * h:.2f} mm: {next((r['dofs'] for r in solids if _num(r['h_m']) == h and r['law'] != 'free'), '?')}"
            f" ({next((r['dofs'] for r in solids if _num(r['h_m']) == h and r['law'] == 'free'), '—')})" for h in hs) + ".\n")
    # checks
    if checks:
        L.append("## Checks of the contact implementation\n")
        L.append("| check | number | details |\n|---|---:|---|")
        for c in checks:
            L.append(f"| {c['resolution']} | {_num(c['uncertainty_rel']):.1e} | {c['note']} |")
        L.append("")
    # convergence tables
    if solids:
        L.append("## Mesh convergence of the solid (soleus elongation u_x [mm])\n")
        for law in laws:
            L.append(f"**{law}**" + (" (the soleus alone: no neighbours, same supports and load)" if law == "free" else "") + "\n")
            head = "| ψ | load [N] | " + " | ".join(f"h {1e3 * h:.2f} mm" for h in hs) + \
                " | reference | uncertainty | how |"
            L.append(head)
            L.append("|---:|---:|" + "---:|" * len(hs) + "---:|---:|---|")
            for psi in psis:
                for F in (10.0, 100.0, 400.0):
                    vals = []
                    for h in hs:
                        r = [x for x in solids if x["law"] == law and _num(x["psi_deg"]) == psi
                             and _num(x["h_m"]) == h and _num(x["load_N"]) == F]
                        vals.append(f"{1e3 * _num(r[0]['soleus_ux_m']):.5f}" if r else "—")
                    ref = [x for x in refs if x["law"] == law and _num(x["psi_deg"]) == psi and _num(x["load_N"]) == F]
                    if ref:
                        rr = ref[0]
                        L.append(f"| {psi:g}° | {F:g} | " + " | ".join(vals) +
                                 f" | {1e3 * _num(rr['soleus_ux_m']):.5f} | {100 * _num(rr['uncertainty_rel']):.3f} % | {rr['note']} |")
                    else:
                        L.append(f"| {psi:g}° | {F:g} | " + " | ".join(vals) + " | — | — | |")
            L.append("")
        # reference summary incl. neighbours
        L.append("## Solid reference: end-centroid u_x [mm]\n")
        L.append("| ψ | law | load [N] | soleus | ± | medial | lateral | soleus end face (mean) |")
        L.append("|---:|---|---:|---:|---:|---:|---:|---:|")
        for psi in psis:
            for law in laws:
                for F in (10.0, 100.0, 400.0):
                    ref = [x for x in refs if x["law"] == law and _num(x["psi_deg"]) == psi and _num(x["load_N"]) == F]
                    if not ref:
                        continue
                    r = ref[0]
                    f = lambda k: "—" if not np.isfinite(_num(r[k])) else f"{1e3 * _num(r[k]):.5f}"
                    L.append(f"| {psi:g}° | {law} | {F:g} | {f('soleus_ux_m')} | {100 * _num(r['uncertainty_rel']):.3f} % | "
                             f"{f('medial_ux_m')} | {f('lateral_ux_m')} | {f('soleus_face_ux_m')} |")
        L.append("")
        # contact diagnostics at 400 N on the finest mesh
        diag = [r for r in solids if r["law"] != "free" and _num(r["load_N"]) == 400.0 and _num(r["h_m"]) == hs[-1]]
        if diag:
            L.append("Contact state at 400 N on the finest mesh (pressure p = Λ_k / ∫φ_k, positive = compression; "
                     "pointwise |g − g0| is what the weighted constraints leave between the quadrature points):\n")
            L.append("| ψ | law | pointwise max |g − g0| [µm] | contact state |\n|---:|---|---:|---|")
            for r in diag:
                L.append(f"| {_num(r['psi_deg']):g}° | {r['law']} | {1e6 * _num(r['gap_max_m']):.3f} | {r['note']} |")
            L.append("")
    # ANCF comparison
    errs = ancf_errors(rows)
    if errs:
        L.append("## ANCF against the solid reference\n")
        L.append("Relative error (u_ANCF − u_ref)/u_ref of the soleus elongation, ANCF 3363 with 2 axial "
                 "Gauss points, `fix: clamped`, `traction_force` at the soleus' last node, "
                 "`contact: {mode: sliding | unilateral}` (free: the soleus beam alone).  Worst = largest "
                 "|error| over the 13 load levels (signed value shown).\n")
        L.append("| ψ | law | elements | worst over 10–400 N | at 10 N | at 100 N | at 400 N | reference uncertainty (max over loads) |")
        L.append("|---:|---|---:|---:|---:|---:|---:|---:|")
        fails = {(r["psi_deg"], r["law"], r["elements"]): r["note"] for r in rows
                 if r["model"] == ANCF and str(r.get("note", "")).startswith("FAILED")}
        for psi in psis:
            for law in ("sliding", "unilateral", "free"):
                ks = sorted(k for k in errs if _num(k[0]) == psi and k[1] == law)
                unc = [_num(x["uncertainty_rel"]) for x in refs if _num(x["psi_deg"]) == psi and x["law"] == law]
                for k in ks:
                    e = errs[k]
                    worst = max(e.values(), key=abs) if len(e) == len(LOADS) else float("nan")
                    note = "" if len(e) == len(LOADS) else f" (only {len(e)} levels)"
                    L.append(f"| {psi:g}° | {law} | {k[2]} | {_fmt_pct(worst)}{note} | {_fmt_pct(e.get(10.0, np.nan))} | "
                             f"{_fmt_pct(e.get(100.0, np.nan))} | {_fmt_pct(e.get(400.0, np.nan))} | "
                             f"{100 * max(unc):.3f} % |")
                for (p, l, ne), note in sorted(fails.items()):
                    if _num(p) == psi and l == law and not any(k[2] == int(_num(ne)) for k in ks):
                        L.append(f"| {psi:g}° | {law} | {ne} | {note} | | | | |")
        L.append("")
        L.append("![ANCF error vs elements](figures/solid_contact.png)\n")
    L.append(meta.get("notes", ""))
    return "\n".join(L) + "\n"
