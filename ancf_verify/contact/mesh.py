"""gmsh meshes of the three bodies (conforming interfaces, axial layers) and of the two-block patch tests."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ancf_verify.bars.mesh import checked_size, gmsh_section
from ancf_verify.contact.tendon import AXIS, ContactError, LENGTH, curve_names


@dataclass(frozen=True)
class LocalSize:
    """Local refinement of the tendon mesh around one interface curve of the section: element
    size ``h`` within ``band`` (default 2 h) of the curve, growing by ``growth`` per unit
    distance beyond it up to the bulk size; the axial layers follow ``h`` (``tendon_mesh``).

    The size is a function of the section position only (the distance to the curve, sampled
    from the ANCF outline), so every body's gmsh model sees the same size on a shared curve and
    the interfaces keep the same 1D mesh on both sides."""
    curve: str
    h: float
    band: float | None = None
    growth: float = 0.5

    def label(self) -> str:
        """What the CSV's resolution column says after the bulk size: '0.70 mm at mg_sol'."""
        return f"{self.h * 1e3:.2f} mm at {self.curve}"

    def polyline(self, secs) -> np.ndarray:
        """The curve in gmsh's section plane (the tendon's (y, z)), 400 points."""
        for sec in secs:
            for cv, _ in sec.loop:
                if cv.name == self.curve:
                    return cv.sample(400) + sec.shape_params["offset"]
        raise ContactError(f"local refinement: no curve {self.curve!r} in the sections")

    def sizes(self, pts: np.ndarray, line: np.ndarray, h_bulk: float) -> np.ndarray:
        """Element size at section points pts (n, 2) for the curve's polyline ``line``."""
        a, d = line[:-1], np.diff(line, axis=0)
        t = np.clip(np.einsum("nsi,si->ns", pts[:, None, :] - a[None], d) / np.einsum("si,si->s", d, d), 0.0, 1.0)
        dist = np.linalg.norm(pts[:, None, :] - (a[None] + t[:, :, None] * d[None]), axis=2).min(axis=1)
        band = 2.0 * self.h if self.band is None else self.band
        return np.minimum(h_bulk, self.h + self.growth * np.maximum(dist - band, 0.0))


def tendon_mesh(secs, h: float, psi: float, bodies=(0, 1, 2), layered: bool = True,
                local: LocalSize | None = None):
    """P2 tets of the chosen bodies as separate volumes (duplicated interface nodes), twisted.

    local: a LocalSize (finer elements around one interface curve of the section, h the bulk
    size; the axial layers of every body at the local size, graded as ``axial_layers``).

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
    checked_size(h)
    parts = [gmsh_body(secs, b, h, layered, local) for b in bodies]
    msh, ct, ft = merge_to_dolfinx(parts)
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


def gmsh_body(secs, b: int, h: float, layered, local: LocalSize | None = None) -> dict:
    """Mesh one body in its own gmsh model; nodes, P2 tets and tagged P2 triangles (gmsh order);
    ``local``: the section's size from LocalSize.sizes (a gmsh size callback), layers at its h."""
    import gmsh
    from dolfinx.io import gmshio
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(f"body{b}")
        occ = gmsh.model.occ
        srf = gmsh_section(occ, secs[b])
        if layered:
            out = occ.extrude([(2, srf)], 0.0, 0.0, LENGTH, recombine=False,
                              **axial_layers(local.h if local else h, layered))
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
        if local is not None:
            line = local.polyline(secs)
            gmsh.model.mesh.setSizeCallback(
                lambda dim, tag, x, y, z: float(local.sizes(np.array([[x, y]]), line, h)[0]))
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


def merge_to_dolfinx(parts: list):
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
    return 100 * (body + 1) + curve_names(secs[body]).index(curve)


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
