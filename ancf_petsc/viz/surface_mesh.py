"""The surfaces of a run's surface_NNNN.vtu as a mesh: per-beam grids of stations x ring points, the
faces between beams, normals and the lines drawn on them."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..io.surface_fields import SURFACE_FIELDS

MM = 1.0e3  # model units are metres; figures are in millimetres


_COMPONENTS = {"x": 0, "y": 1, "z": 2}


@dataclass
class SurfaceMesh:
    """Surface of all beams as read from one VTU file (coordinates in metres)."""

    points: np.ndarray                 # (n, 3)
    quads: np.ndarray                  # (k, 4)
    caps: list[np.ndarray]             # polygon point index lists
    point_data: dict[str, np.ndarray]
    path: str
    values: np.ndarray | None = None   # colouring field per point (display units), once chosen
    label: str = ""                    # its colour-bar label

    def grids(self) -> list[np.ndarray] | None:
        """Per beam the (stations, ring) point-index grid, or None if the layout is not the
        one SurfaceSampler writes (the reference is then drawn from its quads)."""
        beam = self.point_data.get("beam")
        if beam is None or len(self.caps) % 2:
            return None
        out = []
        for first, last in zip(self.caps[0::2], self.caps[1::2]):
            m = len(first)
            start, stop = int(first.min()), int(last.max()) + 1
            n = stop - start
            if n % m or len(last) != m:
                return None
            grid = np.arange(start, stop).reshape(n // m, m)
            if not np.array_equal(np.sort(first), grid[0]) or not np.array_equal(np.sort(last),
                                                                                 grid[-1]):
                return None
            out.append(grid)
        return out or None


def read_surface(vtu_path: str) -> SurfaceMesh:
    """Read a ``surface_NNNN.vtu`` (quads + polygon caps) with meshio."""
    import meshio
    mesh = meshio.read(vtu_path)
    quads, caps = [], []
    for block in mesh.cells:
        if block.type == "quad":
            quads.append(np.asarray(block.data, dtype=np.int64))
        elif block.type.startswith("polygon"):
            caps.extend(np.asarray(c, dtype=np.int64) for c in block.data)
    if not quads:
        raise ValueError(f"{vtu_path}: no quad cells (not a surface_NNNN.vtu of ancf-solve?)")
    caps.sort(key=lambda c: int(c.min()))
    return SurfaceMesh(np.asarray(mesh.points, dtype=float), np.concatenate(quads), caps,
                       {k: np.asarray(v, dtype=float) for k, v in mesh.point_data.items()},
                       vtu_path)


def field_values(mesh: SurfaceMesh, color_by: str) -> tuple[np.ndarray, str]:
    """Point values of ``color_by`` in display units and the colour-bar label
    (``io.surface_fields.SURFACE_FIELDS``: label, unit, factor; a field it does not know is
    drawn as stored).

    Scalar fields as stored (scaled, e.g. strain in %); a vector field gives its magnitude, or a
    component with the suffix ``_x``, ``_y``, ``_z`` (e.g. ``displacement_x``).
    """
    data = mesh.point_data
    name, comp = color_by, None
    if color_by not in data and color_by[-2:-1] == "_" and color_by[-1] in _COMPONENTS:
        name, comp = color_by[:-2], _COMPONENTS[color_by[-1]]
    if name not in data or (comp is not None and data[name].ndim != 2):
        avail = sorted(data) + [f"{k}_{c}" for k in sorted(data) if data[k].ndim == 2
                                for c in _COMPONENTS]
        known = SURFACE_FIELDS.get(name)
        why = f"; {name} is written for {known.where} only" if known and name not in data else ""
        raise ValueError(f"color_by={color_by!r}: no such point field in {mesh.path}; "
                         f"available: {', '.join(avail)}{why}")
    known = SURFACE_FIELDS.get(name)
    label, unit, factor = (known.label, known.unit, known.factor) if known else (name, "-", 1.0)
    v = data[name]
    if v.ndim == 2:
        if comp is None:
            v = np.linalg.norm(v, axis=1)
        else:
            v = v[:, comp]
            label = f"{name} {color_by[-1]}"
    return factor * v, f"{label} [{unit}]"


def topology(mesh: SurfaceMesh, grids: list[np.ndarray], corner_deg: float = 30.0
              ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per beam, judged on the first station: the ring indices of its longitudinal edges (sharp
    outline corners and the ends of stretches shared with another beam) and a mask of the ring
    segments j -> j+1 that lie on an interface with another beam (covered by it, except where
    the beams have slid along each other)."""
    rings = [mesh.points[g[0]] for g in grids]
    seams, iface = [], []
    for b, r in enumerate(rings):
        t = np.roll(r, -1, axis=0) - r
        seg = np.linalg.norm(t, axis=1)
        t /= np.maximum(seg, 1e-30)[:, None]
        turn = np.degrees(np.arccos(np.clip(np.sum(t * np.roll(t, 1, axis=0), axis=1), -1, 1)))
        cols = turn > corner_deg
        shared = np.zeros(len(r), dtype=bool)
        others = [o for k, o in enumerate(rings) if k != b]
        if others:
            d = np.linalg.norm(r[:, None, :] - np.concatenate(others)[None], axis=-1).min(1)
            shared = d < 0.5 * np.median(seg)
            cols |= shared & ~(np.roll(shared, 1) & np.roll(shared, -1))
        seams.append(np.flatnonzero(cols))
        iface.append(shared & np.roll(shared, -1))
    return seams, iface


def quad_index(quads: np.ndarray, grids: list[np.ndarray]) -> list[np.ndarray]:
    """Per beam a (stations - 1, ring) array of quad indices: the quad between stations s, s+1
    starting at ring point j (-1 where the file has none)."""
    out = []
    a = quads[:, 0]
    for g in grids:
        start, m = g[0, 0], g.shape[1]
        idx = np.full((g.shape[0] - 1, m), -1)
        inside = np.flatnonzero((a >= start) & (a < start + g.size - m))
        idx.ravel()[a[inside] - start] = inside
        out.append(idx)
    return out


def face_normals(polys: list[np.ndarray] | np.ndarray) -> np.ndarray:
    """Area-weighted polygon normals (Newell), (k, 3)."""
    if isinstance(polys, np.ndarray):  # (k, n, 3), all the same size
        p, q = polys, np.roll(polys, -1, axis=1)
        return 0.5 * np.cross(p, q).sum(axis=1)
    return np.array([0.5 * np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0) for p in polys])


def outward_signs(normals: np.ndarray, centres: np.ndarray, group: np.ndarray) -> np.ndarray:
    """+1/-1 per face so that normals point out of each closed body (faces grouped by beam):
    the flux of (x - c) through the surface, 3 x volume, must be positive."""
    sign = np.ones(len(normals))
    for g in np.unique(group):
        sel = group == g
        c = centres[sel].mean(axis=0)
        if np.sum(normals[sel] * (centres[sel] - c)) < 0:
            sign[sel] = -1.0
    return sign


def line_segments(mesh: SurfaceMesh, grids: list[np.ndarray], cols: list[np.ndarray]
                   ) -> np.ndarray:
    """Segments (k, 2, 3) along the stations at the given ring indices of every beam."""
    segs = [np.stack([mesh.points[g[:-1, j]], mesh.points[g[1:, j]]], axis=1)
            for g, c in zip(grids, cols) for j in c]
    return np.concatenate(segs) if segs else np.zeros((0, 2, 3))


def reference_lines(ref: SurfaceMesh) -> np.ndarray:
    """Segments (k, 2, 3) outlining the reference configuration: every beam's section outline
    at both ends and its longitudinal edges (the pretwisted seams between the beams)."""
    grids = ref.grids()
    p = ref.points
    if grids is None:  # unknown layout: the edges of every quad
        q = ref.quads
        e = np.stack([q, np.roll(q, -1, axis=1)], axis=-1).reshape(-1, 2)
        return p[np.unique(np.sort(e, axis=1), axis=0)]
    segs = [np.stack([p[g[s]], p[np.roll(g[s], -1)]], axis=1) for g in grids for s in (0, -1)]
    seams = topology(ref, grids)[0]
    cols = [c if len(c) else generator_columns(g.shape[1], 4) for g, c in zip(grids, seams)]
    segs.append(line_segments(ref, grids, cols))
    return np.concatenate(segs)


def generator_columns(m: int, n: int) -> np.ndarray:
    """n ring indices evenly spaced around a ring of m points."""
    return np.unique(np.linspace(0, m, min(n, m), endpoint=False).astype(int))
