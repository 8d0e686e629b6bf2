"""Figures from run outputs (matplotlib, Agg canvas only; no PETSc).

* :func:`render_surfaces` — shaded 3D render of a ``surface_NNNN.vtu`` (beam surfaces + end caps),
  faces coloured by a point field, optionally over the reference configuration.
* :func:`render_pair` — two renders side by side with one shared colour scale.
* :func:`plot_load_elongation` — load-elongation curves against a paper table + relative errors.
* :func:`plot_convergence` — elongation vs elements per subtendon (log2 axis), ours and paper's.
* :func:`plot_slip` — axial slip and contact pressure along the tendon per load level.
* :func:`read_csv_table`, :func:`curve_from_summary` — small readers for
  the inputs of the above.

The surface reader relies on the layout written by :class:`ancf_petsc.io.results.SurfaceSampler`: per
beam a contiguous block of ``stations x ring`` points, quads between consecutive stations, and
two polygon caps (first and last station).
"""
from __future__ import annotations

import csv
import json
from dataclasses import dataclass

import numpy as np
from matplotlib import cm, colormaps, colors
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, ScalarFormatter

MM = 1.0e3  # model units are metres; figures are in millimetres

# field name -> (label, unit, factor from the stored value to the displayed one)
FIELD_LABELS: dict[str, tuple[str, str, float]] = {
    "E_xx": ("axial Green-Lagrange strain $E_{xx}$", "%", 100.0),
    "J": ("volume ratio $J$", "-", 1.0),
    "displacement": ("displacement magnitude $|u|$", "mm", MM),
    "beam": ("beam index", "-", 1.0),
}
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
    """Point values of ``color_by`` in display units and the colour-bar label.

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
        raise ValueError(f"color_by={color_by!r}: no such point field in {mesh.path}; "
                         f"available: {', '.join(avail)}")
    label, unit, factor = FIELD_LABELS.get(name, (name, "-", 1.0))
    v = data[name]
    if v.ndim == 2:
        if comp is None:
            v = np.linalg.norm(v, axis=1)
        else:
            v = v[:, comp]
            label = f"{name} {color_by[-1]}"
    return factor * v, f"{label} [{unit}]"


def _box(points_mm: list[np.ndarray], section_scale: float | None) -> tuple[np.ndarray, np.ndarray,
                                                                             float]:
    """Data limits (lo, hi) in mm and the cross-section exaggeration for the box aspect."""
    allp = np.concatenate(points_mm)
    lo, hi = allp.min(0), allp.max(0)
    span = np.maximum(hi - lo, 1e-9)
    if section_scale is None:
        # long thin bodies: stretch y, z until the section spans ~1/3 of the length (at most 3x)
        section_scale = float(np.clip(0.35 * span[0] / max(span[1], span[2]), 1.0, 3.0))
        section_scale = round(section_scale * 2) / 2
    pad = 0.02 * span
    return lo - pad, hi + pad, section_scale


def _view_vector(view: tuple[float, ...]) -> np.ndarray:
    """Unit vector towards the eye for mplot3d's (elev, azim[, roll]) in box coordinates."""
    elev, azim = np.radians(view[:2])
    return np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])


def _light(view: tuple[float, ...]) -> np.ndarray:
    """Light direction: from above-left of the eye on the screen (``roll`` taken into account)."""
    eye = _view_vector(view)
    up = np.array([0.0, 0.0, 1.0]) - eye[2] * eye
    if np.linalg.norm(up) < 1e-6:  # looking straight down or up
        up = np.array([-np.cos(np.radians(view[1])), -np.sin(np.radians(view[1])), 0.0])
    up /= np.linalg.norm(up)
    right = np.cross(up, eye)
    roll = np.radians(view[2]) if len(view) > 2 else 0.0
    up, right = np.cos(roll) * up - np.sin(roll) * right, np.sin(roll) * up + np.cos(roll) * right
    light = eye + 0.6 * up - 0.5 * right
    return light / np.linalg.norm(light)


def _topology(mesh: SurfaceMesh, grids: list[np.ndarray], corner_deg: float = 30.0
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


def _quad_index(quads: np.ndarray, grids: list[np.ndarray]) -> list[np.ndarray]:
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


def _normals(polys: list[np.ndarray] | np.ndarray) -> np.ndarray:
    """Area-weighted polygon normals (Newell), (k, 3)."""
    if isinstance(polys, np.ndarray):  # (k, n, 3), all the same size
        p, q = polys, np.roll(polys, -1, axis=1)
        return 0.5 * np.cross(p, q).sum(axis=1)
    return np.array([0.5 * np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0) for p in polys])


def _outward(normals: np.ndarray, centres: np.ndarray, group: np.ndarray) -> np.ndarray:
    """+1/-1 per face so that normals point out of each closed body (faces grouped by beam):
    the flux of (x - c) through the surface, 3 x volume, must be positive."""
    sign = np.ones(len(normals))
    for g in np.unique(group):
        sel = group == g
        c = centres[sel].mean(axis=0)
        if np.sum(normals[sel] * (centres[sel] - c)) < 0:
            sign[sel] = -1.0
    return sign


def _line_segments(mesh: SurfaceMesh, grids: list[np.ndarray], cols: list[np.ndarray]
                   ) -> np.ndarray:
    """Segments (k, 2, 3) along the stations at the given ring indices of every beam."""
    segs = [np.stack([mesh.points[g[:-1, j]], mesh.points[g[1:, j]]], axis=1)
            for g, c in zip(grids, cols) for j in c]
    return np.concatenate(segs) if segs else np.zeros((0, 2, 3))


def _reference_lines(ref: SurfaceMesh) -> np.ndarray:
    """Segments (k, 2, 3) outlining the reference configuration: every beam's section outline
    at both ends and its longitudinal edges (the pretwisted seams between the beams)."""
    grids = ref.grids()
    p = ref.points
    if grids is None:  # unknown layout: the edges of every quad
        q = ref.quads
        e = np.stack([q, np.roll(q, -1, axis=1)], axis=-1).reshape(-1, 2)
        return p[np.unique(np.sort(e, axis=1), axis=0)]
    segs = [np.stack([p[g[s]], p[np.roll(g[s], -1)]], axis=1) for g in grids for s in (0, -1)]
    seams = _topology(ref, grids)[0]
    cols = [c if len(c) else _generators(g.shape[1], 4) for g, c in zip(grids, seams)]
    segs.append(_line_segments(ref, grids, cols))
    return np.concatenate(segs)


def _generators(m: int, n: int) -> np.ndarray:
    """n ring indices evenly spaced around a ring of m points."""
    return np.unique(np.linspace(0, m, min(n, m), endpoint=False).astype(int))


def _draw(ax, mesh: SurfaceMesh, fvals: np.ndarray, norm: colors.Normalize, cmap: str,
          view: tuple[float, ...], lo: np.ndarray, hi: np.ndarray, scale: float,
          reference: SurfaceMesh | None, n_generators: int = 8) -> np.ndarray:
    """Put one surface on a 3D axes.  Faces on an interface between beams (mostly covered, but
    exposed where the beams slid along each other) are drawn first; the outer faces, end caps,
    beam edges and reference wireframe follow in one collection that mplot3d depth-sorts."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    aspect = (hi - lo) * np.array([1.0, scale, scale])
    box = lambda x: (x - lo) / (hi - lo) * aspect  # noqa: E731  (what mplot3d projects)
    eye = _view_vector(view)
    light = _light(view)
    pts = mesh.points * MM
    quads = pts[mesh.quads]
    qbeam = np.zeros(len(quads), dtype=int)
    inner = np.zeros(len(quads), dtype=bool)
    grids = mesh.grids()
    if grids is not None:  # topology from the reference when it has the same layout
        ref_grids = reference.grids() if reference is not None else None
        same = ref_grids is not None and [g.shape for g in ref_grids] == [g.shape for g in grids]
        seams, iface = _topology(reference if same else mesh, ref_grids if same else grids)
        qidx = _quad_index(mesh.quads, grids)
        for b, (idx, f) in enumerate(zip(qidx, iface)):
            qbeam[idx[idx >= 0]] = b + 1
            inner[idx[:, f][idx[:, f] >= 0]] = True
    # outward normals in box coordinates; back faces are culled (orthographic view)
    nq = _normals(box(quads))
    nq *= _outward(nq, box(quads).mean(axis=1), qbeam)[:, None]
    nq /= np.maximum(np.linalg.norm(nq, axis=1, keepdims=True), 1e-30)
    front = nq @ eye > 0
    cmap_ = colormaps[cmap] if isinstance(cmap, str) else cmap
    rgba = cmap_(norm(fvals))
    rgba[:, :3] *= (0.55 + 0.45 * np.abs(nq @ light))[:, None]  # Lambert
    ax.computed_zorder = False  # collections in zorder: interfaces, surface, edges on top
    sel = front & inner
    ax.add_collection3d(Poly3DCollection(list(quads[sel]), facecolors=rgba[sel],
                                         edgecolors=rgba[sel], linewidths=0.3, zorder=1))
    sel = front & ~inner
    polys, face, edge, width = list(quads[sel]), [rgba[sel]], [rgba[sel]], [np.full(sel.sum(), 0.3)]

    def add(items: list, fc: np.ndarray, ec: tuple, lw: float) -> None:
        polys.extend(items)
        face.append(fc)
        edge.append(np.broadcast_to(colors.to_rgba(*ec), (len(items), 4)))
        width.append(np.full(len(items), lw))

    if mesh.caps:  # end caps facing the viewer: coloured by their mean value, outlined
        cpts = [pts[c] for c in mesh.caps]
        if grids is not None and len(mesh.caps) == 2 * len(grids):
            nc = _normals([box(c) for c in cpts])
            cen = np.array([box(c).mean(axis=0) for c in cpts])
            body = np.array([box(pts[g.ravel()]).mean(axis=0) for g in grids]).repeat(2, axis=0)
            show = np.sign(np.sum(nc * (cen - body), axis=1)) * (nc @ eye) > 0
        else:
            show = np.ones(len(cpts), dtype=bool)
        crgba = cmap_(norm(np.array([mesh.values[c].mean() for c in mesh.caps])))[show]
        crgba[:, :3] *= 0.85
        add([c for c, v in zip(cpts, show) if v], crgba, ("0.15", 1.0), 0.8)
    if reference is not None:
        segs = _reference_lines(reference) * MM
        add(list(segs), np.zeros((len(segs), 4)), ("0.4", 0.7), 0.6)
    ax.add_collection3d(Poly3DCollection(polys, facecolors=np.concatenate(face),
                                         edgecolors=np.concatenate(edge),
                                         linewidths=np.concatenate(width), zorder=2))
    if grids is not None:
        # longitudinal lines where a face next to them is seen: the beams' edges (dark) and a
        # few generators (faint; they show the twist of round sections)
        seen = np.append(front & ~inner, False)  # index -1: no quad
        for lines, colour, lw in ((seams, ("0.1", 1.0), 0.9),
                                  ([_generators(g.shape[1], n_generators) for g in grids],
                                   ("0.1", 0.3), 0.5)):
            segs = []
            for g, idx, cols in zip(grids, qidx, lines):
                for j in cols:
                    vis = seen[idx[:, j]] | seen[idx[:, j - 1]]
                    segs.append(np.stack([pts[g[:-1, j]], pts[g[1:, j]]], axis=1)[vis])
            if segs:
                ax.add_collection3d(Line3DCollection(np.concatenate(segs),
                                                     colors=[colors.to_rgba(*colour)],
                                                     linewidths=lw, zorder=3))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(aspect)
    ax.set_proj_type("ortho")
    ax.view_init(*view)
    ax.set_facecolor((1, 1, 1, 0))
    ax.set_xlabel("x [mm]", fontsize=8, labelpad=6)
    ax.set_ylabel("y [mm]", fontsize=8, labelpad=0)
    ax.set_zlabel("z [mm]", fontsize=8, labelpad=0)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.pane.set_facecolor((0.95, 0.95, 0.95, 1.0))
        axis.pane.set_edgecolor((0.8, 0.8, 0.8, 1.0))
        axis._axinfo["grid"]["linewidth"] = 0.4
        axis._axinfo["grid"]["color"] = (0.85, 0.85, 0.85, 1.0)
    ax.tick_params(labelsize=7, pad=0)
    return aspect


def _prepare(vtu_path: str, color_by: str) -> tuple[SurfaceMesh, np.ndarray]:
    """Read a surface and attach point values; returns (mesh, per-face mean values)."""
    mesh = read_surface(vtu_path)
    mesh.values, mesh.label = field_values(mesh, color_by)
    return mesh, mesh.values[mesh.quads].mean(axis=1)


def _norm(fvals: list[np.ndarray], clim: tuple | None) -> colors.Normalize:
    if clim is not None:
        return colors.Normalize(*clim)
    lo = min(float(v.min()) for v in fvals)
    hi = max(float(v.max()) for v in fvals)
    if hi - lo < 1e-12:
        lo, hi = lo - 0.5, hi + 0.5
    return colors.Normalize(lo, hi)


def _content_box(img: np.ndarray, cell: tuple[int, int, int, int], dpi: float
                 ) -> tuple[float, float, float, float]:
    """Bounding box (x0, y0, x1, y1) [in, from the cell's lower left] of non-white pixels."""
    r0, r1, c0, c1 = cell
    ink = (img[r0:r1, c0:c1, :3] < 250).any(axis=-1)
    rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    if not len(rows):
        return 0.0, 0.0, (c1 - c0) / dpi, (r1 - r0) / dpi
    h = r1 - r0
    return cols[0] / dpi, (h - rows[-1] - 1) / dpi, (cols[-1] + 1) / dpi, (h - rows[0]) / dpi


def _clipped(img: np.ndarray, extents: np.ndarray) -> bool:
    """Whether anything is drawn on the border of an axes (display extents x0, y0, x1, y1)."""
    h = img.shape[0]
    x0, y0, x1, y1 = extents
    c0, c1 = int(np.ceil(x0)) + 1, int(np.floor(x1)) - 2
    r0, r1 = h - int(np.floor(y1)) + 1, h - int(np.ceil(y0)) - 2
    ink = (img[r0:r1 + 1, c0:c1 + 1, :3] < 250).any(axis=-1)
    return bool(ink[0].any() or ink[-1].any() or ink[:, 0].any() or ink[:, -1].any())


def _render(panels: list[tuple[SurfaceMesh, np.ndarray, SurfaceMesh | None, str]], out_png: str,
            cmap: str, clim: tuple | None, view: tuple[float, ...],
            section_scale: float | None, vertical: bool, panel_in: float = 8.0) -> str:
    """Render 3D panels, crop each to its drawn content and lay them out tightly with titles,
    one colour bar and a footnote (exaggeration, reference)."""
    dpi = 150
    pts = [p[0].points * MM for p in panels] + [p[2].points * MM for p in panels if p[2]]
    lo, hi, scale = _box(pts, section_scale)
    norm = _norm([p[1] for p in panels], clim)
    n = len(panels)
    cell = 2.0 * panel_in  # the axes square in the middle of a larger cell: nothing is clipped
    fig = Figure(figsize=(n * cell, cell), dpi=dpi, facecolor="white")
    canvas = FigureCanvasAgg(fig)
    axes = []
    for i, (mesh, fv, ref, _) in enumerate(panels):
        ax = fig.add_axes([(i * cell + (cell - panel_in) / 2) / (n * cell),
                           (cell - panel_in) / 2 / cell, panel_in / (n * cell), panel_in / cell],
                          projection="3d")
        aspect = _draw(ax, mesh, fv, norm, cmap, view, lo, hi, scale, ref)
        axes.append(ax)
    zoom = 1.0
    for _ in range(5):  # views along a diagonal of a long box can overflow the axes: zoom out
        canvas.draw()
        img = np.asarray(canvas.buffer_rgba())
        if not any(_clipped(img, ax.bbox.extents) for ax in axes):
            break
        zoom *= 0.8
        for ax in axes:
            ax.set_box_aspect(aspect, zoom=zoom)
    px, off = int(round(cell * dpi)), (cell - panel_in) / 2
    boxes = [tuple(v - off for v in _content_box(img, (0, px, i * px, (i + 1) * px), dpi))
             for i in range(n)]
    # layout in inches: margin, title band, colour bar band, footnote band
    m, gap, cbw = 0.1, 0.25, 1.25
    title_h = 0.3 if any(p[3] for p in panels) else 0.0
    rolled = len(view) > 2 and abs((view[2] + 180.0) % 360.0 - 180.0) > 90.0
    notes = ([f"y and z stretched {scale:g}x"] if scale != 1 else []) \
        + (["camera rolled: z points down"] if rolled else []) \
        + (["grey wireframe: reference configuration"] if any(p[2] for p in panels) else [])
    note_h = 0.25 if notes else 0.0
    w = [b[2] - b[0] for b in boxes]
    h = [b[3] - b[1] for b in boxes]
    if vertical:
        W, H = m + max(w) + cbw + m, m + note_h + sum(h) + n * title_h + gap * (n - 1) + m
        x = [m + (max(w) - wi) / 2 for wi in w]
        y = [m + note_h + sum(h[j] + title_h + gap for j in range(i + 1, n)) for i in range(n)]
    else:
        W, H = m + sum(w) + gap * (n - 1) + cbw + m, m + note_h + max(h) + title_h + m
        x = [m + sum(w[j] + gap for j in range(i)) for i in range(n)]
        y = [m + note_h + (max(h) - hi_) / 2 for hi_ in h]
    fig.set_size_inches(W, H)
    for ax, b, xi, yi, (_, _, _, title), wi, hi_ in zip(axes, boxes, x, y, panels, w, h):
        ax.set_position([(xi - b[0]) / W, (yi - b[1]) / H, panel_in / W, panel_in / H])
        if title:
            fig.text((xi + wi / 2) / W, (yi + hi_ + 0.05) / H, title, ha="center", va="bottom",
                     fontsize=10)
    content_top = max(yi + hi_ for yi, hi_ in zip(y, h))
    content_h = content_top - (m + note_h)
    cb_h = min(max(0.7 * content_h, 1.2), content_h)
    cax = fig.add_axes([(W - m - cbw + 0.15) / W, (m + note_h + (content_h - cb_h) / 2) / H,
                        0.14 / W, cb_h / H])
    cb = fig.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), cax=cax)
    cb.set_label(_wrap(panels[0][0].label, cb_h), fontsize=8)
    cb.ax.tick_params(labelsize=7)
    if notes:
        fig.text(m / W, m / H, "; ".join(notes), fontsize=7.5, color="0.35", va="bottom")
    fig.savefig(out_png, dpi=dpi)
    return out_png


def _wrap(label: str, height_in: float) -> str:
    """Break a long colour-bar label in two lines when the bar is short."""
    if len(label) * 0.075 < height_in or " [" not in label:
        return label
    head, unit = label.rsplit(" [", 1)
    words = head.split(" ")
    k = max(1, len(words) // 2)
    return " ".join(words[:k]) + "\n" + " ".join(words[k:]) + " [" + unit


def render_surfaces(vtu_path: str, out_png: str, color_by: str = "E_xx", title: str = "",
                    view: tuple[float, ...] = (20.0, -60.0), cmap: str = "viridis",
                    clim: tuple | None = None, reference_vtu: str | None = None, *,
                    section_scale: float | None = None) -> str:
    """Shaded 3D render of a surface VTU, faces coloured by ``color_by`` (per-face mean).

    ``view`` is mplot3d's (elev, azim[, roll]) in degrees; orthographic projection, back faces
    culled.  ``clim`` is in display units (strain in %).  ``reference_vtu`` (e.g.
    surface_0000.vtu) is drawn as a grey wireframe (end outlines and longitudinal edges).
    ``section_scale`` stretches y and z in the box aspect (default: automatic, 1-3x; stated in
    a footnote).  Dark lines mark each beam's longitudinal edges and end-cap outlines; faint
    ones follow a few generators (the twist).  ``ValueError`` for an unknown ``color_by``.
    Returns ``out_png``.
    """
    mesh, fv = _prepare(vtu_path, color_by)
    ref = read_surface(reference_vtu) if reference_vtu else None
    return _render([(mesh, fv, ref, title)], out_png, cmap, clim, view, section_scale, False)


def render_pair(vtu_a: str, vtu_b: str, out_png: str, titles: tuple[str, str] = ("", ""),
                color_by: str = "E_xx", view: tuple[float, ...] = (20.0, -60.0),
                cmap: str = "viridis", clim: tuple | None = None,
                reference_vtu: tuple[str | None, str | None] | str | None = None, *,
                section_scale: float | None = None, vertical: bool = False) -> str:
    """Two renders side by side (``vertical``: stacked) with one colour scale and equal axes.

    ``reference_vtu`` is one path for both panels or a pair of paths.  Returns ``out_png``.
    """
    refs = reference_vtu if isinstance(reference_vtu, (tuple, list)) else (reference_vtu,) * 2
    panels = []
    for path, ref, title in zip((vtu_a, vtu_b), refs, titles):
        mesh, fv = _prepare(path, color_by)
        panels.append((mesh, fv, read_surface(ref) if ref else None, title))
    return _render(panels, out_png, cmap, clim, view, section_scale, vertical)


def _save(fig: Figure, out_png: str) -> str:
    fig.savefig(out_png, dpi=150, bbox_inches="tight", pad_inches=0.08)
    return out_png


def read_csv_table(path: str) -> dict[str, np.ndarray]:
    """Numeric CSV with a header row; lines starting with '#' are comments.  Column -> array."""
    with open(path, newline="") as fh:
        rows = [r for r in csv.reader(line for line in fh
                                      if line.strip() and not line.lstrip().startswith("#"))]
    if not rows:
        raise ValueError(f"{path}: no header row")
    header, body = [h.strip() for h in rows[0]], rows[1:]
    try:
        arr = np.array([[float(x) for x in r] for r in body], dtype=float).reshape(-1, len(header))
    except ValueError as exc:
        raise ValueError(f"{path}: non-numeric or ragged data ({exc})") from None
    return {h: arr[:, i] for i, h in enumerate(header)}


def curve_from_summary(summary_json: str, probe: str, component: int = 0,
                       scale: float = MM) -> tuple[list[float], list[float]]:
    """(load factors, probe displacement component x scale) per converged step of a run."""
    with open(summary_json) as fh:
        steps = json.load(fh)["steps"]
    return ([s["load_factor"] for s in steps],
            [scale * s["probes"][probe]["displacement"][component] for s in steps])


def _colours(labels: list[str]) -> dict[str, tuple]:
    cycle = colormaps["tab10"].colors
    return {lab: cycle[i % len(cycle)] for i, lab in enumerate(dict.fromkeys(labels))}


def plot_load_elongation(curves: dict[str, tuple[list[float], list[float]]], paper_csv: str,
                         out_png: str, columns: dict[str, str], *, load_column: str = "load_N",
                         title: str = "") -> str:
    """Our load-elongation curves (lines) against the paper's points (markers), plus the relative
    error [%] at the paper's loads within our range (ours interpolated) in a lower panel.

    ``curves``: label -> (loads [N], elongations [mm]); ``columns``: label -> CSV column.
    """
    table = read_csv_table(paper_csv)
    missing = [c for c in [load_column, *columns.values()] if c not in table]
    if missing:
        raise ValueError(f"{paper_csv}: no column(s) {missing}; available: {sorted(table)}")
    col = _colours(list(curves))
    fig = Figure(figsize=(6.0, 5.2))
    FigureCanvasAgg(fig)
    ax, axe = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [2.6, 1.0]})
    loads_p = table[load_column]
    for lab, (loads, elong) in curves.items():
        loads, elong = np.asarray(loads, float), np.asarray(elong, float)
        ax.plot(loads, elong, "-", color=col[lab], lw=1.6, label=f"{lab} (this code)")
        if lab not in columns:
            continue
        ref = table[columns[lab]]
        ax.plot(loads_p, ref, "o", mfc="none", color=col[lab], ms=5,
                label=f"{lab} (paper)")
        if not len(loads):
            continue
        inside = (loads_p >= loads.min() - 1e-9) & (loads_p <= loads.max() + 1e-9)
        if inside.any():
            order = np.argsort(loads)
            ours = np.interp(loads_p[inside], loads[order], elong[order])
            err = 100.0 * (ours - ref[inside]) / ref[inside]
            axe.plot(loads_p[inside], err, "o-", color=col[lab], ms=3.5, lw=1.0)
    axe.axhline(0.0, color="0.5", lw=0.6)
    ax.set_ylabel("elongation [mm]")
    axe.set_ylabel("ours vs paper [%]")
    axe.set_xlabel("load [N]")
    ax.legend(fontsize=8, frameon=False)
    for a in (ax, axe):
        a.grid(alpha=0.3)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return _save(fig, out_png)


def plot_convergence(table: dict[str, list[tuple[int, float]]],
                     paper: dict[str, list[tuple[int, float]]], out_png: str, *,
                     title: str = "", ylabel: str = "elongation at 400 N [mm]",
                     flagged: list[tuple[int, float]] | None = None) -> str:
    """Elongation vs elements per subtendon (log2 x axis): ours lines + markers, the paper's open
    markers.  A label of ``table`` shares the colour of the ``paper`` label it starts with
    (``"ψ = 0°, linear gap"`` goes with ``"ψ = 0°"``); variants after the comma get their own
    line style; ``flagged`` points get a black cross."""
    col = _colours(list(paper) + [lab.split(",")[0] for lab in table])
    variants = list(dict.fromkeys(lab.split(",", 1)[1].strip() for lab in table if "," in lab))
    styles = ["-s", "--^", ":o", "-.d"]
    fig = Figure(figsize=(7.4, 3.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ticks: set[int] = set()
    for lab, pts in table.items():
        if not pts:
            continue
        n, v = np.array(sorted(pts), dtype=float).T
        var = lab.split(",", 1)[1].strip() if "," in lab else ""
        style = styles[variants.index(var) % len(styles)] if var else styles[0]
        ax.plot(n, v, style, color=col[lab.split(",")[0]], ms=5, lw=1.5, label=f"{lab} (this code)")
        ticks.update(int(x) for x in n)
    for lab, pts in paper.items():
        n, v = np.array(sorted(pts), dtype=float).T
        ax.plot(n, v, "o", mfc="none", color=col[lab], ms=8, mew=1.3, label=f"{lab} (paper)")
        ticks.update(int(x) for x in n)
    if flagged:
        n, v = np.array(flagged, dtype=float).T
        ax.plot(n, v, "x", color="k", ms=9, mew=1.6, label="reached through unstable states")
    ax.set_xscale("log", base=2)
    ax.xaxis.set_major_locator(FixedLocator(sorted(ticks)))
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_locator(FixedLocator([]))
    ax.set_xlabel("elements per subtendon")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return _save(fig, out_png)


def plot_slip(levels: list[dict], names: list[str], out_png: str, interfaces: tuple[int, ...],
              length: float, title: str = "") -> str:
    """Axial slip (top) and contact pressure (bottom) of the contact points along the tendon,
    one colour per load level, one marker per interface: ``levels`` from ``io.reader.read_contact``."""
    fig = Figure(figsize=(8.0, 6.0))
    FigureCanvasAgg(fig)
    ax_s = fig.add_subplot(2, 1, 1)
    ax_p = fig.add_subplot(2, 1, 2, sharex=ax_s)
    cmap = colormaps["viridis"]
    markers = ("o", "s", "^", "D")
    for i, lev in enumerate(levels):
        c = cmap(i / max(len(levels) - 1, 1))
        for j, k in enumerate(interfaces):
            sel = lev["interface"] == k
            x = MM * lev["x0"][sel, 0]
            order = np.argsort(x)
            label = f"{lev['load_factor']:g} N" if j == 0 else None
            ax_s.plot(x[order], MM * lev["slip"][sel, 0][order], markers[j % 4], color=c, ms=3,
                      label=label)
            ax_p.plot(x[order], 1e-6 * lev["pressure"][sel][order], markers[j % 4], color=c, ms=3)
    for j, k in enumerate(interfaces):
        ax_s.plot([], [], markers[j % 4], color="0.4", ms=4, label=names[k])
    ax_s.set_ylabel("axial slip of the soleus past\nthe point [mm]")
    ax_p.set_ylabel("contact pressure [MPa]\n(> 0 presses, < 0 holds)")
    ax_p.set_xlabel("x along the tendon [mm] (0: supports, L: loaded end)")
    ax_p.set_xlim(0.0, MM * length)
    for ax in (ax_s, ax_p):
        ax.grid(alpha=0.3)
        ax.axhline(0.0, color="0.5", lw=0.8)
    ax_s.legend(fontsize=7, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    if title:
        ax_s.set_title(title, fontsize=10)
    fig.tight_layout()
    return _save(fig, out_png)
