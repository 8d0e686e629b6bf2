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
Λ ≥ 0, Λ ḡ = 0: augmented-Lagrangian (Uzawa) iterations λ ← max(0, λ − ε ḡ) around a Newton
solve of the regularised problem (ε = κ μ/h), then the active set is "polished" with exact
multipliers (the sliding solver on the active constraints) and accepted when its pressures are
≥ 0 and the free constraints do not penetrate; the answer must not depend on κ or k_s (checked).

Projection.  The closest master face of a slave point is history-free: feet within 2 % of a face
edge (in the face's parameters) are searched among the k nearest faces and the closest kept, and
points past a face border take the face whose unclipped foot is least outside.  Where the
deformed master surface has a kink, the closest face of a point can still switch inside a
Newton solve, which makes the contact force jump by (point force) x (kink angle); Newton then
may cycle between the two sides.  Such a state is accepted ("kink floor", counted and reported)
when five iterations no longer halve the residual and it is below 1e-4 of the applied force.

Usage (make verify-solid-contact runs the first two; about 75 min on one shared core):
  python scripts/verify_solid_contact.py                       # sliding study + free soleus + checks
  python scripts/verify_solid_contact.py --merge --no-selftest --no-free --no-checks --laws unilateral \
      --psi 45 --h 2e-3,1.4e-3 --loads 10,20,40 --max-increment 10   # unilateral rows, added to the CSV
  python scripts/verify_solid_contact.py --ancf-src DIR        # ANCF (and configs) from an export of a commit
  python scripts/verify_solid_contact.py --quick               # smoke run, coarse meshes
  python scripts/verify_solid_contact.py --selftest            # contact implementation checks
  python scripts/verify_solid_contact.py --replot              # figure + report from the CSV
Writes docs/solid_contact.csv, docs/solid_contact.md, docs/figures/solid_contact.png.
"""
from __future__ import annotations

import argparse
import csv
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
ANCF_LABEL = "the working tree"


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


def project_free(xq: np.ndarray, Y: np.ndarray, cand: np.ndarray, iters: int = 40) -> np.ndarray:
    """Unclipped Gauss-Newton feet of xq (n, 3) on the smooth extensions of the P2 faces
    Y[cand] (n, k): z (n, k, 2), NaN where it does not converge."""
    n, k = cand.shape
    Yc = Y[cand].reshape(n * k, 6, 3)
    P = np.repeat(xq, k, axis=0)
    z = np.full((n * k, 2), 1.0 / 3.0)
    for _ in range(iters):
        N, dN = p2_shape(z)
        x = np.matmul(N[:, None, :], Yc)[:, 0, :]
        T = np.matmul(np.swapaxes(dN, -1, -2), Yc)
        r = P - x
        rhs = np.matmul(T, r[:, :, None])[:, :, 0]
        A = np.matmul(T, np.swapaxes(T, -1, -2))
        det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] ** 2
        dz = np.stack([A[:, 1, 1] * rhs[:, 0] - A[:, 0, 1] * rhs[:, 1],
                       A[:, 0, 0] * rhs[:, 1] - A[:, 0, 1] * rhs[:, 0]], axis=-1) / det[:, None]
        dz = np.clip(dz, -0.5, 0.5)
        z = z + dz
        if np.nanmax(np.abs(dz)) < 1e-15:
            break
    z[~(np.abs(dz).max(axis=1) < 1e-10)] = np.nan
    return z.reshape(n, k, 2)


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
                 candidates: int = 24, fixed=None):
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
        self.edge_band = 0.02
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
        far = np.zeros(len(xs), dtype=bool)
        # phase 2 also for interior feet close to a face edge: where the deformed P2 surface
        # has a concave kink, a point near the edge has an interior foot on both faces, and
        # keeping the last face would make the gap depend on the iteration history (Newton then
        # cycles between two states); the closest of the candidates is history-free
        near = border | (np.minimum(z.min(axis=1), 1.0 - z.sum(axis=1)) < self.edge_band)
        if np.any(near):
            # phase 2: search the k nearest faces (and the last one), keep the closest foot
            b = np.nonzero(near)[0]
            k = min(self.candidates, len(cent))
            cand = cKDTree(cent).query(xs[b], k=k)[1].reshape(len(b), k)
            cand = np.hstack([first[b, None], cand])
            mf[b], z[b], border[b] = project(xs[b], Ym, cand)
            # points off the master surface (past its end or the edge of the interface strip):
            # foot point on the smooth extension of the nearest face (unclipped), so that g and
            # its derivatives stay smooth and consistent
            # Of the candidates, the face whose unclipped foot is least outside it (not the
            # first of equally close clipped feet on a shared edge, which would depend on the
            # candidate order, i.e. on the history).
            row = np.full(len(xs), -1, dtype=np.int64)
            row[b] = np.arange(len(b))
            b = np.nonzero(border)[0]
            if len(b):
                cb = cand[row[b]]                                   # (nb, k + 1)
                zu = project_free(xs[b], Ym, cb)                    # (nb, k + 1, 2)
                out_by = np.maximum(-zu.min(axis=2), zu.sum(axis=2) - 1.0)
                out_by = np.where(np.isfinite(out_by), out_by, np.inf)
                j = np.argmin(out_by, axis=1)
                sel = np.arange(len(b))
                best_out = out_by[sel, j]
                ok = best_out < 0.5
                mf[b[ok]] = cb[sel, j][ok]
                z[b[ok]] = zu[sel, j][ok]
                far[b[~ok]] = True           # too far past the edge to extrapolate: off anyway
        if self.track:
            self.last_mf = mf.copy()
        out = gap_terms(xs, Ym[mf], z, hessian)
        out.update(mf=mf, z=z, border=border, xs=xs,
                   zout=np.where(far, 1.0, np.maximum(0.0, np.maximum(-z.min(axis=1), z.sum(axis=1) - 1.0))))
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
    #: the factorisation of the Newton matrix (MUMPS): LDLᵀ of the symmetric saddle-point system
    #: (a subclass with an unsymmetric term, such as friction, uses "lu")
    factor = "cholesky"

    def __init__(self, msh, ct, ft, materials: dict, dirichlet, tractions: dict, interfaces=(),
                 law: str | None = "sliding", quad_degree: int = 2, rule_points: int = 3,
                 ks: float | None = None, kappa: float = 1.0, geometric: bool = True,
                 candidates: int = 24):
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
        self.E_form = fem.form(energy)
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
        self.kappa = kappa                                        # unilateral: ε = κ μ / h
        self.eps_pen = kappa * self.mu_ref / hmin
        self.ak_all = np.concatenate([i.ak for i in self.ifaces]) if self.ifaces else np.zeros(0)
        self.lam = np.zeros(self.nc)                              # Uzawa multipliers [Pa]
        self.restrict = None
        self.uzawa = {"outer": 0, "max_outer": 0}
        self.z = np.zeros(self.nc)
        self.alive = np.ones(self.nc, dtype=bool)
        self.active = np.ones(self.nc, dtype=bool) if self.law == "sliding" else np.zeros(self.nc, dtype=bool)
        self.set_passes, self.set_changes, self.set_unsettled = 0, 0, 0
        self.load = 0.0
        self.stall_tol = 1e-4
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

    def contact(self, uvec: np.ndarray, z, matrix: bool) -> dict:
        """Weighted gaps, their gradient G (nc x ndof, BC columns zero), the contact forces
        −k_s Gᵀ z (dead constraints carry none) and, if asked, the geometric stiffness
        k_s Σ_q τ_q W C Wᵀ.  z may be a function of the weighted gaps (augmented Lagrangian)."""
        t0 = time.perf_counter()
        x = self.positions(uvec)
        gbar, Gs, evs, dofl = [], [], [], []
        for itf in self.ifaces:
            ev = itf.evaluate(x, hessian=matrix and self.geometric)
            evs.append(ev)
            dofs = itf.dofs(ev["mf"])
            dofl.append(dofs)
            gv = itf.grad_values(ev)
            Gq = sp.csr_matrix((gv.ravel(), dofs.ravel(), np.arange(0, 36 * itf.nq + 1, 36)),
                               shape=(itf.nq, self.ndof))
            gbar.append(itf.B @ ev["gr"])
            Gs.append(itf.B @ Gq)
        G = (sp.vstack(Gs).tocsr() @ sp.diags(self.mask)).tocsr() if Gs else sp.csr_matrix((0, self.ndof))
        gb = np.concatenate(gbar) if gbar else np.zeros(0)
        if callable(z):
            z = z(gb)
        za = np.where(self.alive, z, 0.0)
        r = -self.ks * (G.T @ za)
        Kg, rows0 = None, 0
        kg_rows, kg_cols, kg_vals = [], [], []
        for itf, ev, dofs in zip(self.ifaces, evs, dofl):
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
        if matrix and self.geometric and kg_vals:
            Kg = sp.csr_matrix((np.concatenate(kg_vals), (np.concatenate(kg_rows), np.concatenate(kg_cols))),
                               shape=(self.ndof, self.ndof))
            Dm = sp.diags(self.mask)
            Kg = (Dm @ Kg @ Dm).tocsr()
        self.stats["t_contact"] += time.perf_counter() - t0
        return {"gbar": gb, "G": G, "r": r, "Kg": Kg, "evs": evs, "z": za}

    # ---------------------------------------------------------------------------------------
    def residual(self, uvec, z, matrix=False):
        """Sliding law: full residual [R_u; R_z], R_z = −k_s ḡ (dead constraints: −k_s z), and
        the symmetric saddle-point matrix [[K + K_geo, −k_s Gᵀ], [−k_s G, 0]] as CSR."""
        r, Kc = self._internal(uvec, matrix)
        if not np.all(np.isfinite(r)):
            return None, None, None
        if not self.ifaces:
            return r, (Kc if matrix else None), None
        c = self.contact(uvec, z, matrix)
        alive = self.alive
        c["active"] = alive.copy()
        rz = np.where(alive, -self.ks * c["gbar"], -self.ks * z)
        R = np.concatenate([r + c["r"], rz])
        if not matrix:
            return R, None, c
        Kt = Kc if c["Kg"] is None else (Kc + c["Kg"])
        Ga = (sp.diags(alive.astype(float)) @ c["G"]).tocsr()
        D = sp.diags(np.where(alive, 0.0, -self.ks))
        Jm = sp.bmat([[Kt, -self.ks * Ga.T], [-self.ks * Ga, D]], format="csr")
        c["corr"] = np.zeros(self.ndof)
        return R, Jm, c

    def residual_alm(self, uvec, matrix=False):
        """Unilateral law, inner problem of the augmented Lagrangian: minimise
        E(u) = Π(u) + Σ_k a_k/(2ε) [max(0, λ_k − ε ḡ_k)² − λ_k²]  (λ fixed, ε = κ μ/h).
        Returns (R_u, matrix, c, E): R_u = ∇E (forces of p_k = max(0, λ_k − ε ḡ_k)), and the
        Newton matrix in the regularised saddle-point form [[K + K_geo, −k_s G_Aᵀ],
        [−k_s G_A, −k_s²/(a ε)]] (A: p_k > 0), whose Schur complement is the penalty Hessian
        K + K_geo + ε G_Aᵀ diag(a) G_A without forming G_Aᵀ G_A."""
        r, Kc = self._internal(uvec, matrix)
        if not np.all(np.isfinite(r)):
            return None, None, None, None
        ak, eps, lam = self.ak_all, self.eps_pen, self.lam
        holder = {}

        def zfun(gb):
            p = np.where(self.alive, np.maximum(0.0, lam - eps * gb), 0.0)
            holder["p"] = p
            return ak * p / self.ks
        c = self.contact(uvec, zfun, matrix)
        p = holder["p"]
        # generalised Hessian: at the kink λ − ε ḡ = 0 (the touching reference state) the
        # constraint counts as closed, so that a first step does not run into the penalty
        active = self.alive & (lam - eps * c["gbar"] >= -1e-12 * eps * self.h)
        c["active"], c["p"] = active, p
        R = r + c["r"]
        E = self._energy(uvec) + float(np.sum(ak / (2 * eps) * (p ** 2 - np.where(self.alive, lam, 0.0) ** 2)))
        if not matrix:
            return R, None, c, E
        Kt = Kc if c["Kg"] is None else (Kc + c["Kg"])
        Ga = (sp.diags(active.astype(float)) @ c["G"]).tocsr()
        D = sp.diags(np.where(active, -self.ks ** 2 / (ak * eps), -self.ks))
        Jm = sp.bmat([[Kt, -self.ks * Ga.T], [-self.ks * Ga, D]], format="csr")
        return R, Jm, c, E

    def _energy(self, uvec) -> float:
        from dolfinx import fem
        self.u.x.array[:] = uvec
        self.u.x.scatter_forward()
        return float(fem.assemble_scalar(self.E_form))

    def _solve_linear(self, Jm, rhs):
        from petsc4py import PETSc
        t0 = time.perf_counter()
        Jm.sort_indices()
        A = PETSc.Mat().createAIJ(size=Jm.shape, csr=(Jm.indptr.astype(PETSc.IntType),
                                                      Jm.indices.astype(PETSc.IntType), Jm.data))
        A.setOption(PETSc.Mat.Option.SYMMETRIC, self.factor == "cholesky")
        A.assemble()
        ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType(self.factor)
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
        if self.restrict is not None:
            self.alive &= self.restrict
        self.active &= self.alive
        return changed

    def newton(self, uvec, z, rtol=1e-10, atol=1e-9, max_it=None):
        """Newton from (uvec, z) with residual-guarded steps (the sliding law, or exact multipliers on
        a given active set for the unilateral polish);
        the set of slave points over their master is updated at convergence (and Newton goes
        on if it changed).  Returns (ok, its, uvec, z)."""
        ndof = self.ndof
        if max_it is None:
            max_it = 60 if self.law == "unilateral" else 30
        R, Jm, c = self.residual(uvec, z, matrix=True)
        if R is None:
            return False, 0, uvec, z
        r0 = r = float(np.linalg.norm(R))
        set_updates, hist, floor = 0, [r0], False
        for it in range(max_it + 1):
            conv = r <= max(rtol * r0, atol)
            if conv or (it > 0 and floor):
                if self._settle_set(uvec, set_updates):
                    set_updates += 1
                    z = np.where(self.alive, z, 0.0)
                    R, Jm, c = self.residual(uvec, z, matrix=True)
                    r = float(np.linalg.norm(R))
                    floor, hist = False, [r]
                    continue
                if c is not None:
                    self.active = c["active"]
                return True, it, uvec, z
            if it == max_it:
                return False, it, uvec, z
            self.stats["newton"] += 1
            rhs = -R
            if c is not None:
                rhs[:ndof] -= c["corr"]
            d = self._solve_linear(Jm, rhs)
            step, accepted = 1.0, False
            while step >= 1.0 / 32:
                u_t = uvec + step * d[:ndof]
                z_t = z + step * d[ndof:] if self.nc else z
                # the full step is usually taken: assemble its tangent at once
                R_t, J_t, c_t = self.residual(u_t, z_t, matrix=step == 1.0)
                if R_t is not None:
                    r_t = float(np.linalg.norm(R_t))
                    if r_t < r or (r < 1e-6 * r0 and r_t < 10 * r) or (step < 1.0 / 16 and r_t < 2 * r):
                        accepted = True
                        break
                step *= 0.5
            if not accepted:
                return False, it + 1, uvec, z
            # rounding / kink floor: a slave point on an edge between two master faces makes the
            # residual only piecewise smooth; below 1e-6 of the applied force that is noise
            fs = max(r0, self.load * sum(float(np.linalg.norm(f)) for f in self.tr_force.values()))
            floor = (r < 1e-7 * r0 or r < 1e-6 * fs) and r_t > 0.5 * r
            # kink floor: a slave point whose closest master face switches makes the contact
            # force jump by (point force) x (kink angle between the deformed master faces), and
            # Newton can cycle between the two sides.  Accepted (and counted) when five
            # iterations no longer halve the residual and it is below 1e-4 of the applied force
            hist.append(r_t)
            if not floor and len(hist) > 5 and min(hist[-5:]) > 0.5 * hist[-6] and r_t < self.stall_tol * fs:
                floor = True
                self.stats["stalls"] = self.stats.get("stalls", 0) + 1
                self.stats["stall_max"] = max(self.stats.get("stall_max", 0.0), r_t / fs)
            if self.debug:
                extra = ""
                if c_t is not None:
                    nb = sum(int(e["border"].sum()) for e in c_t["evs"])
                    extra = f" border {nb} active {int(c_t['active'].sum())}/{self.nc}"
                print(f"      it {it + 1}: |R| {r_t:.3e} (u {np.linalg.norm(R_t[:ndof]):.2e}, "
                      f"z {np.linalg.norm(R_t[ndof:]):.2e}) step {step:g}{extra} "
                      f"|du| {np.abs(d[:ndof]).max():.2e}", flush=True)
            uvec, z = u_t, z_t
            if J_t is not None:
                R, Jm, c = R_t, J_t, c_t
            else:
                R, Jm, c = self.residual(uvec, z, matrix=True)
            r = float(np.linalg.norm(R))
        return False, max_it, uvec, z

    def newton_alm(self, uvec, rtol=1e-10, atol=1e-9, max_it=40):
        """Newton on the inner augmented-Lagrangian problem (λ fixed): steps guarded by the
        energy E or the residual (as verify_solid.Newton); the slave-point set is updated at
        convergence.  Returns (ok, its, uvec, c)."""
        ndof = self.ndof
        R, Jm, c, E = self.residual_alm(uvec, matrix=True)
        if R is None:
            return False, 0, uvec, None
        r0 = r = float(np.linalg.norm(R))
        fs = max(r0, self.load * sum(float(np.linalg.norm(f)) for f in self.tr_force.values()))
        set_updates, floor = 0, False
        for it in range(max_it + 1):
            if r <= max(rtol * r0, atol) or floor:
                if self._settle_set(uvec, set_updates):
                    set_updates += 1
                    R, Jm, c, E = self.residual_alm(uvec, matrix=True)
                    r, floor = float(np.linalg.norm(R)), False
                    continue
                return True, it, uvec, c
            if it == max_it:
                return False, it, uvec, c
            self.stats["newton"] += 1
            d = self._solve_linear(Jm, np.concatenate([-R, np.zeros(self.nc)]))[:ndof]
            step, accepted = 1.0, False
            while step >= 1.0 / 256:
                u_t = uvec + step * d
                R_t, J_t, c_t, E_t = self.residual_alm(u_t, matrix=step == 1.0)
                if R_t is not None:
                    r_t = float(np.linalg.norm(R_t))
                    if E_t < E or r_t < r:
                        accepted = True
                        break
                step *= 0.5
            if not accepted:
                return False, it + 1, uvec, c
            floor = (r < 1e-7 * r0 or r < 1e-6 * fs) and r_t > 0.5 * r
            if self.debug:
                print(f"      it {it + 1}: |R| {r_t:.3e} E {E_t:.9e} step {step:g} "
                      f"active {int(c_t['active'].sum())}/{self.nc} |du| {np.abs(d).max():.2e}", flush=True)
            uvec = u_t
            if J_t is not None:
                R, Jm, c, E = R_t, J_t, c_t, E_t
            else:
                R, Jm, c, E = self.residual_alm(uvec, matrix=True)
            r = float(np.linalg.norm(R))
        return False, max_it, uvec, c

    def solve_alm(self, uvec, tol_gap=None, max_outer=60):
        """Unilateral law: Uzawa iterations λ ← max(0, λ − ε ḡ) around newton_alm.  Once the
        update is small (max |Δλ|/ε < 1e-3 h, or the active set A = {λ > 0} unchanged over two
        updates), the active set is polished exactly: Lagrange multipliers on A (ḡ_A = 0, the
        sliding solver), the rest free; accepted when its pressures are ≥ 0 (to 1e-3 of the
        largest) and the free constraints do not penetrate (ḡ ≥ −1e-6 h): the discrete
        unilateral solution, independent of ε.  Otherwise Uzawa goes on (to max |Δλ|/ε <
        tol_gap = 1e-6 h).  Returns (ok, its, u)."""
        tol_gap = 1e-6 * self.h if tol_gap is None else tol_gap
        its, A_prev, same = 0, None, 0
        for outer in range(max_outer):
            ok, n, uvec, c = self.newton_alm(uvec)
            its += n
            if not ok:
                return False, its, uvec
            p = c["p"]
            viol = float(np.max(np.abs(p - np.where(self.alive, self.lam, 0.0)))) / self.eps_pen \
                if self.nc else 0.0
            self.lam = p.copy()
            self.uzawa["outer"] += 1
            A = p > 0
            same = same + 1 if A_prev is not None and np.array_equal(A, A_prev) else 0
            A_prev = A
            if self.debug:
                print(f"    Uzawa {outer + 1}: max |Δλ|/ε = {viol:.2e} m, active {int(A.sum())}/{self.nc}",
                      flush=True)
            if viol < tol_gap:
                self.uzawa["max_outer"] = max(self.uzawa["max_outer"], outer + 1)
                return True, its, uvec
            if viol < 1e-3 * self.h or same >= 2:
                okp, n, up = self._polish(uvec, A)
                its += n
                if okp:
                    self.uzawa["polished"] = self.uzawa.get("polished", 0) + 1
                    self.uzawa["max_outer"] = max(self.uzawa["max_outer"], outer + 1)
                    return True, its, up
        return False, its, uvec

    def _polish(self, uvec, A):
        """Exact Lagrange multipliers on the active set A (the rest free); checks the signs."""
        z0 = np.where(A, self.ak_all * self.lam / self.ks, 0.0)
        self.restrict = A.copy()
        self.alive = self.alive & A
        try:
            ok, n, u1, z1 = self.newton(uvec, z0)
        finally:
            self.restrict = None
            self.alive = np.concatenate([i.alive for i in self.ifaces])
        if not ok:
            return False, n, uvec
        p = self.ks * z1 / self.ak_all
        gb = self.contact(u1, np.zeros(self.nc), False)["gbar"]
        free = self.alive & ~A
        pmax = max(float(p[A].max()) if A.any() else 0.0, 1e-30)
        good = (not A.any() or p[A].min() >= -1e-3 * pmax) and (not free.any() or gb[free].min() >= -1e-6 * self.h)
        if self.debug:
            print(f"    polish on {int(A.sum())} constraints: p min {p[A].min() if A.any() else 0:.3e} Pa, "
                  f"free gap min {gb[free].min() if free.any() else 0:.3e} m -> {'accepted' if good else 'rejected'}",
                  flush=True)
        if not good:
            return False, n, uvec
        self.lam = np.where(A & self.alive, np.maximum(p, 0.0), 0.0)
        return True, n, u1

    def _settle_set(self, uvec, updates: int) -> bool:
        """At a converged Newton iterate: update the set of slave points over their master;
        True if it changed (Newton then goes on from here with the new set).  After 3 updates
        the set is kept (points that toggle at the master's edge are counted as unsettled)."""
        if not self.ifaces:
            return False
        if updates >= 3:
            x = self.positions(uvec)
            for itf in self.ifaces:
                ev = itf.evaluate(x, hessian=False)
                self.set_unsettled += int(np.sum(~(ev["border"] & (ev["zout"] > 1e-6)) != itf.on))
            return False
        ch = self.update_contact_set(uvec)
        if ch:
            self.set_passes += 1
            self.set_changes += ch
        return ch > 0

    def _increment(self, u0, z0):
        """One load increment from (u0, z0): (ok, its, u, z)."""
        if self.law == "unilateral":
            ok, n, u1 = self.solve_alm(u0)
            return ok, n, u1, self.ak_all * self.lam / self.ks
        return self.newton(u0, z0)

    def solve_path(self, levels, on_level=None, first_increment=None, max_increment=None,
                   max_cutbacks=10, predictor=True, log=None):
        """Load stepping through ``levels`` (load factors) with cut-backs and a secant predictor.
        Calls on_level(level, its) after each converged level.  Returns total Newton iterations."""
        self.uvec, self.zvec, self.load_done = np.zeros(self.ndof), np.zeros(self.nc), 0.0
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
                act0, lam0 = self.active.copy(), self.lam.copy()
                ok, n, u1, z1 = self._increment(u0, z0)
                if not ok and u0 is not uvec:       # predictor may have overshot: plain start
                    self.active, self.lam = act0, lam0.copy()
                    its_total += n
                    its_level += n
                    ok, n, u1, z1 = self._increment(uvec, z)
                its_total += n
                its_level += n
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
                    self.active, self.lam = act0, lam0
                    dlam = 0.5 * (trial - lam)
                    cutbacks += 1
                    if log:
                        log(f"    cut back at {trial:.4g} (Newton {n} its) -> increment {dlam:.4g}")
                    if cutbacks > max_cutbacks or dlam < 1e-6 * max(level, 1.0):
                        raise ContactError(f"Newton failed at load factor {trial:.4g}")
            self.uvec, self.zvec = uvec, z
            self.load_done = level
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
        c = self.contact(self.uvec, self.zvec, False)
        on = np.concatenate([i.on for i in self.ifaces])
        g = np.concatenate([ev["gr"] for ev in c["evs"]])[on]
        w = np.concatenate([i.w for i in self.ifaces])[on]
        ak = np.concatenate([i.ak for i in self.ifaces])
        p = self.ks * self.zvec / ak
        act = (self.lam > 0) if self.law == "unilateral" else self.active
        return {"g_max": float(np.abs(g).max()), "g_rms": float(np.sqrt(np.sum(w * g ** 2) / w.sum())),
                "gbar_max_active": float(np.abs(c["gbar"][act]).max()) if act.any() else 0.0,
                "gbar_min": float(c["gbar"][self.alive].min()),
                "p_min": float(p.min()), "p_max": float(p.max()), "active": int(act.sum()), "nc": self.nc,
                "alive": int(self.alive.sum()), "off": int((~on).sum()),
                "set_passes": self.set_passes, "set_unsettled": self.set_unsettled,
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
                   layered: bool = True, problem_class=None, **kw):
    """Mesh (timed) and Problem of the tendon: clamped roots, end traction 1 N x load factor on
    the end faces of ``loads_on``, contact on the interfaces between the chosen bodies
    (``problem_class``: a Problem subclass taking the same arguments, e.g. with friction)."""
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
    P = (problem_class or Problem)(msh, ct, ft, mats, dirich, tr, ifs, law=law if ifs else None, **kw)
    return P, t_mesh


def run_solid(secs, psi: float, law: str | None, h: float, loads=LOADS, bodies=(0, 1, 2), log=print,
              max_increment: float = 50.0, **kw) -> dict:
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
        P.solve_path(list(loads), on_level=on_level, max_increment=max_increment, log=log)
    except ContactError as exc:
        ok, msg = False, str(exc)
    return {"psi": psi, "law": law or "free", "h": h, "dofs": P.ndof, "nc": P.nc, "levels": levels,
            "ok": ok, "msg": msg, "t_mesh": t_mesh, "wall": time.perf_counter() - t_solve0,
            "stats": dict(P.stats), "ks": P.ks, "h_mean": P.h, "t_total": time.perf_counter() - t0}


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
    P, _ = tendon_problem(secs, psi, h, None, loads_on=(0, 1, 2), layered=False)
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


def selftest_blocks(log=print, hA=0.45e-3, hB=0.32e-3, rule_points=3, cases=None) -> list:
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
    cases = cases or [("pull", "sliding", 0.6e6), ("press", "sliding", -0.6e6), ("press", "unilateral", -0.6e6),
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
        P = Problem(msh, ct, ft, mats, dirich, tr, [("y0", 200, 100)], law=law, rule_points=rule_points)
        t0 = time.perf_counter()
        done = 1.0
        # the master side is integrated with the slave's points, which is not exact on
        # non-matching meshes: the discrete answer has small kinks, and the kink floor is set
        # at 1e-3 of the load here (reported)
        P.stall_tol = 1e-3
        try:
            P.solve_path([0.5, 1.0], max_cutbacks=3)
        except ContactError as exc:          # measure what was reached
            done = P.load_done
            log(f"  [2] blocks {kind} {law}: {exc}; compared at load factor {done:g}")
        t = np.asarray(t, float) * done if not np.isscalar(t) else t * done
        t = tuple(t) if np.ndim(t) else float(t)
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
        err = float(np.abs(U - ex).max() / np.abs(ex).max()) if done > 0 else float("nan")
        rep = P.gap_report()
        pexp = abs(t) if kind == "press" else (-t if kind == "pull" else abs(t[2]) if len(t) > 2 else 0.0)
        res.append({"kind": kind, "law": law, "err": err, "slide": slide, "h": (hA, hB), "done": done,
                    "rule": rule_points, "stalls": P.stats.get("stalls", 0),
                    "stall_max": P.stats.get("stall_max", 0.0),
                    "g_max": rep["g_max"], "p_min": rep["p_min"], "p_max": rep["p_max"], "p_exact": pexp,
                    "active": rep["active"], "nc": rep["nc"], "time": time.perf_counter() - t0,
                    "its": P.stats["newton"], "dofs": P.ndof})
        log(f"  [2] blocks {kind:5s} {law:10s}: max nodal |u - u_exact| / max |u_exact| = {err:.2e}; "
            f"relative slide {slide * 1e3:.3f} mm (h {hB * 1e3:.2f}/{hA * 1e3:.2f} mm); pointwise |g - g0| "
            f"max {rep['g_max']:.1e} m; contact pressure [{rep['p_min'] / 1e6:+.4f}, {rep['p_max'] / 1e6:+.4f}] "
            f"MPa (exact {pexp / 1e6:+.4f}); active {rep['active']}/{rep['nc']}; {P.stats['newton']} Newton its; "
            f"rule {rule_points} points; load factor reached {done:g}; kink-floor acceptances "
            f"{P.stats.get('stalls', 0)} (|R|/F up to {P.stats.get('stall_max', 0.0):.1e})", flush=True)
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
        du = rng.normal(size=P.ndof) * P.mask
        if law == "sliding":
            z = rng.normal(size=P.nc) * 1e-6
            dz = rng.normal(size=P.nc) * 1e-6 / h
            R, Jm, c = P.residual(u, z, matrix=True)
            d = np.concatenate([du, dz])
            Jd = Jm @ d
            fun = lambda e: P.residual(u + e * du, z + e * dz)      # noqa: E731
            dzc = dz
        else:
            # λ such that about half of the constraints press (augmented-Lagrangian inner problem)
            gb = P.contact(u, np.zeros(P.nc), False)["gbar"]
            P.lam = np.maximum(0.0, P.eps_pen * gb + rng.normal(size=P.nc) * P.eps_pen * np.abs(gb).mean())
            R, Jm, c, _ = P.residual_alm(u, matrix=True)
            n = P.ndof
            A11, A21, Dd = Jm[:n, :n], Jm[n:, :n], Jm.diagonal()[n:]
            Jd = A11 @ du - A21.T @ ((A21 @ du) / Dd)            # Schur complement: the penalty Hessian
            fun = lambda e: P.residual_alm(u + e * du)[:3]         # noqa: E731
            dzc = None
        active = c["active"]
        rec = {"law": law, "h": h, "ndof": P.ndof, "nc": P.nc, "active": int(active.sum()),
               "border": int(sum(e["border"].sum() for e in c["evs"]))}
        for eps in (1e-5, 1e-6, 1e-7):
            e = eps * h
            Rp, _, cp = fun(e)
            Rm, _, cm = fun(-e)
            fd = (Rp - Rm) / (2 * e)
            fdg = (cp["gbar"] - cm["gbar"]) / (2 * e)
            same = bool(np.all(cp["active"] == active) and np.all(cm["active"] == active))
            rec[eps] = {"full": float(np.linalg.norm(fd - Jd) / np.linalg.norm(Jd)),
                        "gbar": float(np.linalg.norm(fdg - c["G"] @ du) / np.linalg.norm(c["G"] @ du)),
                        "same_set": same}
            if law == "sliding":
                fdc = (cp["r"] - cm["r"]) / (2 * e)          # contact forces only (z moves too)
                Jc = (c["Kg"] @ du if c["Kg"] is not None else 0.0) - P.ks * (c["G"].T @ np.where(P.alive, dzc, 0.0))
                rec[eps]["contact_force"] = float(np.linalg.norm(fdc - Jc) / np.linalg.norm(fdc))
            else:
                fdc = (cp["r"] - cm["r"]) / (2 * e)
                Jc = Jd - A11 @ du + (c["Kg"] @ du if c["Kg"] is not None else 0.0)
                rec[eps]["contact_force"] = float(np.linalg.norm(fdc - Jc) / np.linalg.norm(fdc))
            log(f"  [3] FD {law:10s} eps {eps:g} h: |FD - J d| / |J d| full {rec[eps]['full']:.2e}, "
                f"weighted gaps {rec[eps]['gbar']:.2e}, contact forces {rec[eps]['contact_force']:.2e}"
                + ("" if same else " (the active set changed within +-eps)"))
        # without the geometric stiffness: how much of the contact force derivative it carries
        P.geometric = False
        if law == "sliding":
            _, Jm0, _ = P.residual(u, z, matrix=True)
            Jd0 = Jm0 @ d
        else:
            _, Jm0, _, _ = P.residual_alm(u, matrix=True)
            Jd0 = Jm0[:n, :n] @ du - A21.T @ ((A21 @ du) / Dd)
        rec["no_geo_full"] = float(np.linalg.norm(Jd0 - Jd) / np.linalg.norm(Jd))
        log(f"  [3] FD {law:10s}: the gap-Hessian term is {rec['no_geo_full']:.2e} of |J d| "
            f"({rec['active']}/{P.nc} constraints active; {rec['border']} points on a master face border)")
        out.append(rec)
    return out


def selftest(secs, log=print, patch: bool = False) -> dict:
    log("[selftest] (1) contact off: each body against verify_solid.solve_solid")
    r1 = selftest_single_bodies(secs, 3e-3, 45.0, 20.0, log)
    r2 = []
    if patch:   # slow, and not passed exactly (see docs/solid_contact.md): on request only
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
              "wall_s", "newton_its", "gap_max_m", "multipliers", "kink_floor", "note"]
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
                     "gap_max_m": lv.get("g_max", ""), "multipliers": run["nc"],
                     "kink_floor": run["stats"].get("stalls", 0), "note": note})
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
                     "note": f"ancf_petsc of {ANCF_LABEL}"})
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
    keys = sorted({(_num(r["psi_deg"]), r["law"]) for r in rows if r["model"] == SOLID})
    for psi, law in keys:
        fam = [r for r in rows if r["model"] == SOLID and _num(r["psi_deg"]) == psi and r["law"] == law
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
                if len(solids) >= 3:
                    ref, unc, how = vs.richardson(solids)
                    if how.startswith("finest mesh"):
                        # not monotone: the finest mesh, and (conservatively) its largest
                        # difference to any coarser mesh as the uncertainty
                        unc = max(abs(v - vals[-1]) for v in vals[:-1]) / abs(vals[-1])
                        how = ("finest mesh (changes not monotone); uncertainty: its largest difference "
                               "to a coarser mesh")
                else:   # two meshes: the finer, with the last change as its uncertainty
                    ref = solids[-1]["u"]
                    unc = float(abs(vals[-1] - vals[-2]) / abs(vals[-1]))
                    how = "finest of two meshes, the last change as the uncertainty"
                rec[q] = float(ref[0])
                if q == "soleus_ux_m":
                    rec["uncertainty_rel"] = unc
                    notes.append(how)
            rec["resolution"] = f"{len(per_h)} meshes, h {1e3 * hs[0]:.2f}-{1e3 * hs[-1]:.2f} mm"
            rec["note"] = "; ".join(notes)
            out.append(rec)
    return out


def write_rows(path: str, fields: tuple, rows: list, precise) -> None:
    """``rows`` as CSV with the columns ``fields``: floats with 11 digits where ``precise(field)``,
    6 elsewhere, empty where not finite."""
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            d = {}
            for k in fields:
                v = r.get(k, "")
                if isinstance(v, (float, np.floating)):
                    v = "" if not np.isfinite(v) else (f"{v:.10e}" if precise(k) else f"{v:.6g}")
                d[k] = v
            w.writerow(d)


def write_csv(path: str, rows: list) -> None:
    write_rows(path, CSV_FIELDS, rows, lambda k: k.endswith("_m") or k == "uncertainty_rel")


def read_csv(path: str) -> list:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def ancf_errors(rows: list) -> dict:
    """Relative error of the ANCF soleus elongation against the solid reference, per (psi, law,
    elements): worst over the loads, at 10 N and at 400 N (NaN where missing)."""
    refs = {(_num(r["psi_deg"]), r["law"], _num(r["load_N"])): r for r in rows if r["model"] == REF}
    out = {}
    for r in rows:
        if r["model"] != ANCF or r["load_N"] in ("", None):
            continue
        ref = refs.get((_num(r["psi_deg"]), r["law"], _num(r["load_N"])))
        if ref is None:
            continue
        e = (_num(r["soleus_ux_m"]) - _num(ref["soleus_ux_m"])) / _num(ref["soleus_ux_m"])
        d = out.setdefault((r["psi_deg"], r["law"], int(_num(r["elements"]))), {})
        d[_num(r["load_N"])] = e
    return out


def ref_loads(rows: list, psi, law) -> set:
    """The load levels [N] at which the solid reference of (psi, law) exists."""
    return {_num(r["load_N"]) for r in rows if r["model"] == REF and _num(r["psi_deg"]) == _num(psi)
            and r["law"] == law}


def plot(path: str, rows: list) -> None:
    """Signed relative error of the ANCF soleus elongation against the solid reference, per ψ:
    worst over the loads, at 10 N and at 400 N, with the ±0.3 % target band and the reference's
    uncertainty."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    errs = ancf_errors(rows)
    psis = sorted({k[0] for k in errs}, key=_num)
    laws = [l for l in ("sliding", "unilateral", "free") if any(k[1] == l for k in errs)]
    if not psis:
        return
    fig, axes = plt.subplots(1, len(psis), figsize=(4.6 * len(psis), 4.2), squeeze=False, sharey=True)
    style = {"sliding": ("C0", "o"), "unilateral": ("C1", "s"), "free": ("C2", "^")}
    handles = {}
    for ax, psi in zip(axes[0], psis):
        ax.axhspan(-0.3, 0.3, color="0.92", zorder=0)
        ax.axhline(0.0, color="0.5", lw=0.6)
        for law in laws:
            col, mk = style[law]
            ks = sorted(k for k in errs if k[0] == psi and k[1] == law)
            if not ks:
                continue
            nref = len(ref_loads(rows, psi, law))
            n = [k[2] for k in ks]
            worst = [100 * max(errs[k].values(), key=abs) if len(errs[k]) == nref else np.nan for k in ks]
            e10 = [100 * errs[k].get(10.0, np.nan) for k in ks]
            e400 = [100 * errs[k].get(400.0, np.nan) for k in ks]
            h1, = ax.plot(n, worst, "-", marker=mk, color=col, ms=6)
            h2, = ax.plot(n, e10, "--", marker=mk, color=col, mfc="none", ms=5)
            h3, = ax.plot(n, e400, ":", marker=mk, color=col, mfc="none", ms=5)
            handles[f"{law}: worst over the loads"] = h1
            handles[f"{law}: 10 N"] = h2
            handles[f"{law}: 400 N"] = h3
            unc = [_num(x["uncertainty_rel"]) for x in rows if x["model"] == REF and _num(x["psi_deg"]) == _num(psi)
                   and x["law"] == law]
            if unc and np.isfinite(max(unc)):
                u = 100 * max(unc)
                ax.fill_between([1.8, 18], [-u, -u], [u, u], color=col, alpha=0.10, lw=0)
        ax.set_xscale("log", base=2)
        ax.set_xlim(1.8, 18)
        ax.set_xticks([2, 4, 8, 16])
        ax.set_xticklabels(["2", "4", "8", "16"])
        ax.set_title(f"psi = {_num(psi):g} deg")
        ax.set_xlabel("ANCF elements per subtendon")
        ax.grid(True, which="both", lw=0.3, alpha=0.6)
    axes[0][0].set_ylabel("ANCF error of the soleus elongation [%]")
    fig.legend(list(handles.values()), list(handles.keys()), loc="lower center", ncol=3, fontsize=7.5,
               frameon=False)
    fig.suptitle("ANCF (2 axial points) against the 3D solid reference; grey: the +-0.3 % target, "
                 "tinted: +- the reference's uncertainty", fontsize=9.5)
    fig.tight_layout(rect=(0, 0.14, 1, 0.95))
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
    ap.add_argument("--laws", default="sliding", help="contact laws: sliding,unilateral")
    ap.add_argument("--h", default="2e-3,1.4e-3,1.15e-3", help="solid mesh sizes [m], coarse to fine")
    ap.add_argument("--elements", default="2,4,8,16", help="ANCF elements per subtendon")
    ap.add_argument("--quick", action="store_true", help="coarse meshes only (smoke run)")
    ap.add_argument("--selftest", action="store_true", help="only the contact self-tests")
    ap.add_argument("--no-selftest", action="store_true", help="skip the self-tests in a full run")
    ap.add_argument("--patch-tests", action="store_true", help="also the two-block patch tests (slow)")
    ap.add_argument("--no-checks", action="store_true", help="skip the k_s / kappa checks")
    ap.add_argument("--no-free", action="store_true", help="skip the free soleus")
    ap.add_argument("--rule-points", type=int, default=3, choices=(3, 6, 7),
                    help="Gauss points per sub-triangle of a slave face (4 sub-triangles)")
    ap.add_argument("--replot", action="store_true", help="figure and report from the CSV (no solving)")
    ap.add_argument("--report", action="store_true", help="same as --replot")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs"), help="output directory")
    ap.add_argument("--loads", default="10,20,40,100,200,300,400",
                    help="solid load levels [N] (the ANCF columns run all of Table 1's levels)")
    ap.add_argument("--max-increment", type=float, default=100.0, help="largest solid load increment [N]")
    ap.add_argument("--free-psi", default="0,15,45", help="pretwists at which the free soleus is solved too")
    ap.add_argument("--ancf-src", default="",
                    help="import ancf_petsc (and read configs/) from this directory, e.g. an export of a commit")
    ap.add_argument("--ancf-label", default="the working tree", help="what --ancf-src is (recorded in the CSV)")
    ap.add_argument("--no-solid", action="store_true", help="only the ANCF columns (with --merge)")
    ap.add_argument("--merge", action="store_true",
                    help="keep the rows of the existing CSV that this run does not redo")
    args = ap.parse_args(argv)
    global CONFIGS, ANCF_LABEL
    ANCF_LABEL = args.ancf_label
    if args.ancf_src:
        if "ancf_petsc" in sys.modules:
            raise ContactError("--ancf-src: ancf_petsc is imported already")
        sys.path.insert(0, os.path.abspath(args.ancf_src))
        CONFIGS = os.path.join(os.path.abspath(args.ancf_src), "configs")
    csv_path = os.path.join(args.out, "solid_contact.csv")
    md_path = os.path.join(args.out, "solid_contact.md")
    png_path = os.path.join(args.out, "figures", "solid_contact.png")
    os.makedirs(os.path.dirname(png_path), exist_ok=True)
    if args.replot or args.report:
        rows = [r for r in read_csv(csv_path) if r["model"] != REF]
        rows += reference_rows(rows)
        write_csv(csv_path, rows)
        rows = read_csv(csv_path)
        plot(png_path, rows)
        with open(md_path, "w") as fh:
            fh.write(render_md(rows, {}))
        print(f"[solid-contact] rewrote {md_path} and {png_path} from {csv_path}")
        return 0
    vs._import_stack()
    t_start = time.perf_counter()
    secs = tendon_sections()
    old_rows = [r for r in read_csv(csv_path) if r["model"] != REF] \
        if args.merge and os.path.exists(csv_path) else []

    def finish(rows, meta):
        keys = {_row_key(r) for r in rows}
        rows = [r for r in old_rows if _row_key(r) not in keys] + rows
        rows = [r for r in rows if r["model"] != REF]
        rows += reference_rows(rows)
        write_csv(csv_path, rows)
        rows = read_csv(csv_path)          # the page is what the CSV says (as --report makes it)
        plot(png_path, rows)
        meta["total"] = time.perf_counter() - t_start
        with open(md_path, "w") as fh:
            fh.write(render_md(rows, meta))
        print(f"[solid-contact] {meta['total']:.0f} s; wrote {md_path}, {csv_path}, {png_path}")

    if args.selftest:
        st = selftest(secs, patch=args.patch_tests)
        rows = selftest_rows(st)
        for r in rows:
            print(f"[selftest] {r['resolution']}: {r['uncertainty_rel']:.2e}")
        if args.merge:
            finish(rows, {"argv": " ".join(sys.argv[1:])})
        return 0
    psis = [float(p) for p in args.psi.split(",") if p.strip()]
    laws = [l.strip() for l in args.laws.split(",") if l.strip()]
    bad = set(laws) - {"sliding", "unilateral"}
    if bad:
        raise ContactError(f"unknown law(s) {sorted(bad)}")
    hs = [float(h) for h in args.h.split(",")]
    elements = [int(e) for e in args.elements.split(",")]
    loads = [float(f) for f in args.loads.split(",") if f.strip()]
    free_psis = [float(p) for p in args.free_psi.split(",") if p.strip()]
    if args.quick:
        hs, elements = [3e-3, 2e-3], [e for e in elements if e <= 4] or [2]
    kw = {"rule_points": args.rule_points}
    rows: list = []
    meta = {"argv": " ".join(sys.argv[1:]), "h": hs, "rule_points": args.rule_points}
    runs_done = {}

    def save():
        keys = {_row_key(r) for r in rows}
        keep = [r for r in old_rows if _row_key(r) not in keys]
        write_csv(csv_path, keep + rows + reference_rows(keep + rows))

    if not args.no_selftest:
        print("[solid-contact] self-tests", flush=True)
        rows += selftest_rows(selftest(secs, patch=args.patch_tests))
        save()
    with tempfile.TemporaryDirectory(prefix="solid_contact_") as tmp:
        for psi in psis:
            free = not args.no_free and psi in free_psis
            runs = [(None, (0,))] if free else []
            runs += [(law, (0, 1, 2)) for law in laws]
            for law, bodies in (runs if not args.no_solid else []):
                for h in hs:
                    print(f"[solid] psi {psi:g}, {law or 'free soleus'}, h {h * 1e3:.2f} mm", flush=True)
                    r = run_solid(secs, psi, law, h, loads=loads, bodies=bodies,
                                  max_increment=args.max_increment, **kw)
                    runs_done[(psi, law, h)] = r
                    st = r["stats"]
                    print(f"[solid]   {r['dofs']} DOFs, {r['nc']} multipliers, {r['wall']:.0f} s "
                          f"(+ mesh {r['t_mesh']:.0f} s), {st['newton']} Newton its, "
                          f"kink-floor acceptances {st.get('stalls', 0)} (|R|/F up to {st.get('stall_max', 0):.1e})"
                          + ("" if r["ok"] else f", FAILED: {r['msg']}"), flush=True)
                    rows += solid_rows(r)
                    save()
            for law in ([None] if free else []) + laws:
                for ne in elements:
                    a = run_ancf(psi, law, ne, tmp)
                    print(f"[ancf] psi {psi:g}, {law or 'free'}, {ne} el.: "
                          + (f"soleus u_x(400 N) {1e3 * a['levels'][-1]['u']['soleus'][0]:.5f} mm, "
                             f"{a['wall']:.1f} s" if a["ok"] else f"FAILED ({a['msg']})"), flush=True)
                    rows += ancf_rows(a)
            save()
        if not args.no_checks and not args.no_solid:
            psi, h = psis[-1], hs[0]
            print(f"[solid-contact] independence checks at psi {psi:g}, h {h * 1e3:.2f} mm", flush=True)
            for law in laws:
                opt = dict(kw, loads=loads, max_increment=args.max_increment)
                base = runs_done.get((psi, law, h)) or run_solid(secs, psi, law, h, log=None, **opt)
                other = run_solid(secs, psi, law, h, log=None, ks=100.0 * base["ks"], **opt)
                rows += independence_rows(base, other, f"{law}: multiplier unit k_s x 100")
                if law == "unilateral":
                    other = run_solid(secs, psi, law, h, log=None, kappa=10.0, **opt)
                    rows += independence_rows(base, other, f"{law}: penalty eps = kappa mu/h, kappa 1 -> 10")
                save()
    finish(rows, meta)
    return 0


def _row_key(r: dict) -> tuple:
    """Rows of one run (or one check) share this key; --merge replaces them as a whole."""
    if r["model"] == "check":
        return ("check", r["resolution"])
    return (r["model"], _num(r["psi_deg"]), r["law"], r["resolution"])


def mesh_changes(rows: list) -> dict:
    """Per (law, psi): the largest relative change of the soleus elongation over the loads between
    the two finest meshes, and the largest reference uncertainty."""
    out = {}
    solids = [r for r in rows if r["model"] == SOLID and r["load_N"] not in ("", None)]
    for law, psi in sorted({(r["law"], _num(r["psi_deg"])) for r in solids}):
        fam = [r for r in solids if r["law"] == law and _num(r["psi_deg"]) == psi]
        hs = sorted({_num(r["h_m"]) for r in fam})
        if len(hs) < 2:
            continue
        u = {(_num(r["h_m"]), _num(r["load_N"])): _num(r["soleus_ux_m"]) for r in fam}
        ch = [abs(u[(hs[0], F)] - u[(hs[1], F)]) / abs(u[(hs[0], F)]) for (h, F) in u if h == hs[0] and (hs[1], F) in u]
        unc = [_num(r["uncertainty_rel"]) for r in rows if r["model"] == REF and r["law"] == law
               and _num(r["psi_deg"]) == psi]
        out[(law, psi)] = {"change": max(ch) if ch else float("nan"), "unc": max(unc) if unc else float("nan"),
                           "h": hs[:2], "hows": sorted({r["note"] for r in rows if r["model"] == REF
                                                        and r["law"] == law and _num(r["psi_deg"]) == psi})}
    return out


def limits_md(rows: list, errs: dict) -> str:
    """What limits the agreement, from the rows: the free soleus' error (beam kinematics of the
    loaded body alone) against the bundle's (the contact coupling on top), and the unilateral
    law against the sliding one at the lowest load (how much the soleus gains by separating)."""
    L = []
    psis = sorted({_num(k[0]) for k in errs})
    pairs = []
    for psi in psis:
        for ne in sorted({k[2] for k in errs if _num(k[0]) == psi}):
            f = [errs[k] for k in errs if _num(k[0]) == psi and k[1] == "free" and k[2] == ne]
            sl = [errs[k] for k in errs if _num(k[0]) == psi and k[1] == "sliding" and k[2] == ne]
            if f and sl:
                common = sorted(set(f[0]) & set(sl[0]))
                if common:
                    pairs.append((psi, ne, max((f[0][F] for F in common), key=abs),
                                  max((sl[0][F] for F in common), key=abs)))
    if pairs:
        L.append("### Beam kinematics or contact coupling\n")
        L.append("The same comparison for the soleus alone (no neighbours, same clamp and load) separates "
                 "what the 3363 beam makes of the loaded body from what the contact coupling adds.  Worst "
                 "signed error over the common loads:\n")
        L.append("| ψ | elements | soleus alone | three subtendons, sliding | difference |")
        L.append("|---:|---:|---:|---:|---:|")
        for psi, ne, ef, es in pairs:
            L.append(f"| {psi:g}° | {ne} | {_fmt_pct(ef)} | {_fmt_pct(es)} | {_fmt_pct(es - ef)} |")
        L.append("")
    # unilateral against sliding at the lowest common load
    uni = [r for r in rows if r["law"] == "unilateral" and r["model"] in (REF, ANCF) and r["load_N"] not in ("", None)]
    if uni:
        L.append("### Separation at low load (unilateral against sliding)\n")
        L.append("(u_unilateral − u_sliding)/u_sliding of the soleus elongation: how much the soleus gains by "
                 "being free to lift off its neighbours.\n")
        L.append("| ψ | model | load [N] | sliding [mm] | unilateral [mm] | gain |")
        L.append("|---:|---|---:|---:|---:|---:|")
        for r in sorted(uni, key=lambda r: (_num(r["psi_deg"]), r["model"] != REF, _num(r["elements"] or 0),
                                            _num(r["load_N"]))):
            if _num(r["load_N"]) > 40.0:
                continue
            s = [x for x in rows if x["law"] == "sliding" and x["model"] == r["model"]
                 and _num(x["psi_deg"]) == _num(r["psi_deg"]) and _num(x["load_N"]) == _num(r["load_N"])
                 and (r["model"] == REF or x["elements"] == r["elements"])]
            if not s:
                continue
            us, uu = _num(s[0]["soleus_ux_m"]), _num(r["soleus_ux_m"])
            name = "solid reference" if r["model"] == REF else f"ANCF {r['elements']} el."
            L.append(f"| {_num(r['psi_deg']):g}° | {name} | {_num(r['load_N']):g} | {1e3 * us:.5f} | {1e3 * uu:.5f} | "
                     f"{_fmt_pct((uu - us) / us, 2)} |")
        L.append("")
    return "\n".join(L)


def summary_md(rows: list, target: float = 0.003) -> str:
    """Summary sentences computed from the rows: mesh convergence and the ANCF errors."""
    L = ["## Summary (computed from the CSV)\n"]
    mc = mesh_changes(rows)
    for (law, psi), m in mc.items():
        L.append(f"* Solid, {law}, ψ = {psi:g}°: the soleus elongation changes by at most {100 * m['change']:.3f} % "
                 f"between h = {1e3 * m['h'][1]:.2f} and {1e3 * m['h'][0]:.2f} mm (over the loads); the reference's "
                 f"uncertainty is at most {100 * m['unc']:.3f} % ({'; '.join(m['hows'])}).")
    errs = ancf_errors(rows)
    for law in ("sliding", "unilateral", "free"):
        ks = sorted(k for k in errs if k[1] == law)
        if not ks:
            continue
        by_el = {}
        for k in ks:
            nref = len(ref_loads(rows, k[0], law))
            if len(errs[k]) != nref:
                continue
            w = max(errs[k].values(), key=abs)
            by_el.setdefault(k[2], []).append((abs(w), w, _num(k[0])))
        if not by_el:
            continue
        parts = []
        for ne in sorted(by_el):
            a, w, psi = max(by_el[ne])
            parts.append(f"{ne} el. {100 * w:+.3f} % (ψ = {psi:g}°)")
        L.append(f"* ANCF {law}, worst error of the soleus elongation over all ψ and loads: " + ", ".join(parts) + ".")
        big = [ne for ne in sorted(by_el) if ne >= 4]
        if big:
            ok = all(max(by_el[ne])[0] <= target for ne in big)
            worst = [max(by_el[ne])[0] for ne in big]
            grows = all(b >= a for a, b in zip(worst, worst[1:]))
            L.append(f"  Target |error| ≤ {100 * target:.1f} % at {', '.join(str(n) for n in big)} elements at every ψ "
                     f"and load: **{'met' if ok else 'not met'}**"
                     + (f"; the worst error grows with the element count ({' → '.join(f'{100 * x:.3f} %' for x in worst)})."
                        if grows and len(worst) > 1 else
                        f"; worst |error| by element count: {' → '.join(f'{100 * x:.3f} %' for x in worst)}."))
    L.append("")
    return "\n".join(L)


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
    gen = ("Generated by `scripts/verify_solid_contact.py` (`make verify-solid-contact`) from "
           "`docs/solid_contact.csv`; `--report` redraws this page and the figure from the CSV")
    if meta.get("argv") is not None:
        gen += f" (last invocation: `{meta['argv']}`"
        gen += f", {meta['total'] / 60:.0f} min, 1 core, {platform.machine()})" if meta.get("total") else ")"
    gen += "."
    src = sorted({r["note"] for r in rows if r["model"] == ANCF and str(r.get("note", "")).startswith("ancf_petsc")})
    if src:
        gen += "  ANCF: " + "; ".join(src) + "."
    L.append(gen + "\n")
    loads_text = ", ".join(f"{F:g}" for F in sorted({_num(r["load_N"]) for r in solids}))
    L.append(summary_md(rows))
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
  P2 tessellations of a curved interface differ from point to point, and a body sliding over
  several elements rides over that washboard; the layers avoid it.)
* **Material.** Ψ = μ/2 (J^(−2/3) I1 − 3) + K/2 (J − 1)², μ = 103.1 / 143.2 / 226.7 MPa (soleus /
  medial / lateral), K = 0.86 GPa.
* **Supports and load.** Root faces x = 0 of all three bodies clamped (u = 0).  Soleus end face
  x = L: uniform dead traction F/A along +x (A = that face's area in the mesh), F = LOADS_TEXT N
  (the ANCF columns run all 13 of Table 1's levels; they are compared at these).  Gastrocnemius
  end faces free.
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
  factorisation every iteration.  The closest master face is chosen without memory of the
  previous iteration (the closest of the k nearest faces for feet near a face edge).
  **unilateral**: augmented-Lagrangian (Uzawa) iterations with ε = κ μ/h until the active set
  settles, then that set is solved again with exact multipliers and accepted only if its
  pressures are ≥ 0 and no free constraint penetrates: the answer does not depend on ε.
  There is no penalty in the answers: the checks below change the multipliers' unit k_s (and κ).
* **Kink floor.** Where the deformed P2 master surface has a kink between two faces, the closest
  face of a slave point can switch during a Newton solve; the contact force then jumps by (point
  force) × (kink angle) and Newton can cycle between the two sides.  Such a solve is accepted
  when five iterations no longer halve the residual and |R| < 10⁻⁴ of the applied force (counted
  in the run table below).
* **Quantities.** u_x at the reference end-section centroid place(L, c) of each body (the
  soleus' is the soleus elongation), and the mean u_x of the soleus end face.  The converged
  solid answer per (ψ, law, load) is `verify_solid.richardson` over the meshes (h ∝ DOFs^(−1/3),
  fitted order) or, when the changes do not shrink, the finest mesh with its last change as the
  uncertainty.
""".replace("LOADS_TEXT", loads_text or "—"))
    # runs
    if solids:
        L.append("## Solid runs\n")
        L.append("One core, serial; wall time of the load path (meshing excluded).  Kink floor: Newton solves "
                 "accepted at the kink floor (see above).\n")
        L.append("| ψ | law | h [mm] | DOFs | multipliers | Newton its | wall [s] | kink floor | stopped |")
        L.append("|---:|---|---:|---:|---:|---:|---:|---:|---|")
        for law in laws:
            for psi in psis:
                for h in hs:
                    fam = [r for r in solids if r["law"] == law and _num(r["psi_deg"]) == psi and _num(r["h_m"]) == h]
                    if not fam:
                        continue
                    stop = [r["note"] for r in rows if r["model"] == SOLID and r["law"] == law
                            and _num(r["psi_deg"]) == psi and _num(r["h_m"]) == h and r["load_N"] in ("", None)]
                    L.append(f"| {psi:g}° | {law} | {1e3 * h:.2f} | {fam[0]['dofs']} | {fam[0].get('multipliers', '')} | "
                             f"{sum(int(_num(r['newton_its'])) for r in fam)} | {max(_num(r['wall_s']) for r in fam):.0f} | "
                             f"{fam[0].get('kink_floor', '')} | {stop[0] if stop else ''} |")
        L.append("")
    # checks
    if checks:
        L.append("## Checks of the contact implementation\n")
        L.append("| check | number | details |\n|---|---:|---|")
        for c in checks:
            L.append(f"| {c['resolution']} | {_num(c['uncertainty_rel']):.1e} | {c['note'].replace('|', '∣')} |")
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
                 "|error| over the solid's load levels (signed value shown).\n")
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
                    nref = len(ref_loads(rows, psi, law))
                    worst = max(e.values(), key=abs) if len(e) == nref else float("nan")
                    note = "" if len(e) == nref else f" (only {len(e)} of {nref} levels)"
                    L.append(f"| {psi:g}° | {law} | {k[2]} | {_fmt_pct(worst)}{note} | {_fmt_pct(e.get(10.0, np.nan))} | "
                             f"{_fmt_pct(e.get(100.0, np.nan))} | {_fmt_pct(e.get(400.0, np.nan))} | "
                             f"{100 * max(unc):.3f} % |")
                for (p, l, ne), note in sorted(fails.items()):
                    if _num(p) == psi and l == law and not any(k[2] == int(_num(ne)) for k in ks):
                        L.append(f"| {psi:g}° | {law} | {ne} | {note} | | | | |")
        L.append("")
        L.append("![ANCF error vs elements](figures/solid_contact.png)\n")
        L.append(limits_md(rows, errs))
    notes = os.path.join(ROOT, "docs", "solid_contact.notes")
    if os.path.exists(notes):
        with open(notes, encoding="utf-8") as fh:
            L.append(fh.read().rstrip() + "\n")
    return "\n".join(L) + "\n"


if __name__ == "__main__":
    try:
        sys.exit(main())
    except ContactError as exc:
        print(f"verify_solid_contact: {exc}", file=sys.stderr)
        sys.exit(1)
