"""Shaded 3D renders of a run's surfaces (matplotlib, Agg canvas only; no PETSc).

* :func:`render_surfaces` — a ``surface_NNNN.vtu`` (beam surfaces + end caps), faces coloured by a
  point field, optionally over the reference configuration.
* :func:`render_pair` — two renders side by side with one shared colour scale.

The surfaces are read by ``surface_mesh.read_surface``, which relies on the layout written by
:class:`ancf_petsc.io.vtk.SurfaceSampler`.
"""
from __future__ import annotations

import numpy as np
from matplotlib import cm, colormaps, colors
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .surface_mesh import (MM, SurfaceMesh, face_normals, field_values, generator_columns, outward_signs,
                           quad_index, read_surface, reference_lines, topology)

#: the colour of faces where the field has no value (NaN: fibre fields on beams without fibres)
NO_VALUE = "0.8"


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


def _draw(ax, mesh: SurfaceMesh, fvals: np.ndarray, norm: colors.Normalize, cmap: str,
          view: tuple[float, ...], lo: np.ndarray, hi: np.ndarray, scale: float,
          reference: SurfaceMesh | None, n_generators: int = 8) -> np.ndarray:
    """Put one surface on a 3D axes.  Faces on an interface between beams (mostly covered, but
    exposed where the beams slid along each other) are drawn first; the outer faces, end caps,
    beam edges and reference wireframe follow in one collection that mplot3d depth-sorts."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    aspect = (hi - lo) * np.array([1.0, scale, scale])
    box = lambda x: (x - lo) / (hi - lo) * aspect  # noqa: E731  (what mplot3d projects)
    eye = _view_vector(view)
    light = _light(view)
    pts = mesh.points * MM
    quads = pts[mesh.quads]
    grids = mesh.grids()
    qbeam, inner, seams, qidx = _faces_by_beam(mesh, grids, reference)
    # outward normals in box coordinates; back faces are culled (orthographic view)
    nq = face_normals(box(quads))
    nq *= outward_signs(nq, box(quads).mean(axis=1), qbeam)[:, None]
    nq /= np.maximum(np.linalg.norm(nq, axis=1, keepdims=True), 1e-30)
    front = nq @ eye > 0
    cmap_ = (colormaps[cmap] if isinstance(cmap, str) else cmap).with_extremes(bad=NO_VALUE)
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

    if mesh.caps:
        add(*_caps(mesh, pts, grids, box, eye, cmap_, norm), ("0.15", 1.0), 0.8)
    if reference is not None:
        segs = reference_lines(reference) * MM
        add(list(segs), np.zeros((len(segs), 4)), ("0.4", 0.7), 0.6)
    ax.add_collection3d(Poly3DCollection(polys, facecolors=np.concatenate(face),
                                         edgecolors=np.concatenate(edge),
                                         linewidths=np.concatenate(width), zorder=2))
    if grids is not None:
        _edge_lines(ax, pts, grids, qidx, seams, np.append(front & ~inner, False), n_generators)
    _style_axes(ax, lo, hi, aspect, view)
    return aspect


def _faces_by_beam(mesh: SurfaceMesh, grids, reference: SurfaceMesh | None):
    """Per quad its beam (1-based; 0 unknown) and whether it lies on an interface between beams,
    with the beams' seam columns and quad indices (topology from the reference when it has the
    same layout)."""
    qbeam = np.zeros(len(mesh.quads), dtype=int)
    inner = np.zeros(len(mesh.quads), dtype=bool)
    seams, qidx = None, None
    if grids is not None:
        ref_grids = reference.grids() if reference is not None else None
        same = ref_grids is not None and [g.shape for g in ref_grids] == [g.shape for g in grids]
        seams, iface = topology(reference if same else mesh, ref_grids if same else grids)
        qidx = quad_index(mesh.quads, grids)
        for b, (idx, f) in enumerate(zip(qidx, iface)):
            qbeam[idx[idx >= 0]] = b + 1
            inner[idx[:, f][idx[:, f] >= 0]] = True
    return qbeam, inner, seams, qidx


def _caps(mesh: SurfaceMesh, pts: np.ndarray, grids, box, eye: np.ndarray, cmap_, norm) -> tuple[list, np.ndarray]:
    """End caps facing the viewer (polygons) and their colours (each cap's mean value)."""
    cpts = [pts[c] for c in mesh.caps]
    if grids is not None and len(mesh.caps) == 2 * len(grids):
        nc = face_normals([box(c) for c in cpts])
        cen = np.array([box(c).mean(axis=0) for c in cpts])
        body = np.array([box(pts[g.ravel()]).mean(axis=0) for g in grids]).repeat(2, axis=0)
        show = np.sign(np.sum(nc * (cen - body), axis=1)) * (nc @ eye) > 0
    else:
        show = np.ones(len(cpts), dtype=bool)
    crgba = cmap_(norm(np.array([mesh.values[c].mean() for c in mesh.caps])))[show]
    crgba[:, :3] *= 0.85
    return [c for c, v in zip(cpts, show) if v], crgba


def _edge_lines(ax, pts: np.ndarray, grids, qidx, seams, seen: np.ndarray, n_generators: int) -> None:
    """Longitudinal lines where a face next to them is seen (``seen``, index −1: no quad): the
    beams' edges (dark) and a few generators (faint; they show the twist of round sections)."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    for lines, colour, lw in ((seams, ("0.1", 1.0), 0.9),
                              ([generator_columns(g.shape[1], n_generators) for g in grids],
                               ("0.1", 0.3), 0.5)):
        segs = []
        for g, idx, cols in zip(grids, qidx, lines):
            for j in cols:
                vis = seen[idx[:, j]] | seen[idx[:, j - 1]]
                segs.append(np.stack([pts[g[:-1, j]], pts[g[1:, j]]], axis=1)[vis])
        if segs:
            ax.add_collection3d(Line3DCollection(np.concatenate(segs), colors=[colors.to_rgba(*colour)],
                                                 linewidths=lw, zorder=3))


def _style_axes(ax, lo: np.ndarray, hi: np.ndarray, aspect: np.ndarray, view: tuple[float, ...]) -> None:
    """Limits, orthographic view, labels in mm and light panes."""
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


def _prepare(vtu_path: str, color_by: str) -> tuple[SurfaceMesh, np.ndarray]:
    """Read a surface and attach point values; returns (mesh, per-face mean values)."""
    mesh = read_surface(vtu_path)
    mesh.values, mesh.label = field_values(mesh, color_by)
    return mesh, mesh.values[mesh.quads].mean(axis=1)


def _norm(fvals: list[np.ndarray], clim: tuple | None) -> colors.Normalize:
    """The colour scale: ``clim``, else the range of the faces' values where the field has one
    (NaN where it is not defined, e.g. fibre fields on beams without fibres)."""
    if clim is not None:
        return colors.Normalize(*clim)
    finite = [v[np.isfinite(v)] for v in fvals]
    finite = [v for v in finite if v.size] or [np.zeros(1)]
    lo = min(float(v.min()) for v in finite)
    hi = max(float(v.max()) for v in finite)
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
        + (["grey wireframe: reference configuration"] if any(p[2] for p in panels) else []) \
        + (["light grey faces: no value there"] if any(np.isnan(p[1]).any() for p in panels) else [])
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
    ones follow a few generators (the twist).  Faces where the field has no value (fibre fields
    on beams without fibres) are light grey, outside the colour scale.  ``ValueError`` for an
    unknown ``color_by``.  Returns ``out_png``.
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
