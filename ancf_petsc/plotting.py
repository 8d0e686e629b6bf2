"""Figures from run outputs (matplotlib, Agg canvas only; no PETSc).

* :func:`render_surfaces` — shaded 3D render of a ``surface_NNNN.vtu`` (beam surfaces + end caps),
  faces coloured by a point field, optionally over the reference configuration.
* :func:`render_pair` — two renders side by side with one shared colour scale.
* :func:`plot_load_elongation` — load-elongation curves against a paper table, with relative errors.
* :func:`plot_convergence` — elongation vs elements per subtendon (log2 axis), ours and the paper's.
* :func:`read_csv_table`, :func:`curve_from_summary` — small readers for the inputs of the above.

The surface reader relies on the layout written by :class:`ancf_petsc.output.SurfaceSampler`: per
beam a contiguous block of ``stations x ring`` points, quads between consecutive stations, and
two polygon caps (first and last station).
"""
from __future__ import annotations

import csv
import json
from dataclasses import dataclass

import numpy as np
from matplotlib import cm, colors
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
        raise ValueError(f"{vtu_path}: no quad cells (not a surface_NNNN.vtu written by ancf-solve?)")
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


def _view_vector(view: tuple[float, float]) -> np.ndarray:
    elev, azim = np.radians(view)
    return np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])


def _shade(polys_box: np.ndarray, view: tuple[float, float]) -> np.ndarray:
    """Two-sided Lambert shading factor per quad (box coordinates, light above-left of the eye)."""
    n = np.cross(polys_box[:, 2] - polys_box[:, 0], polys_box[:, 3] - polys_box[:, 1])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    light = _view_vector((view[0] + 35.0, view[1] - 25.0))
    return 0.5 + 0.5 * np.abs(n @ light)


def _seam_columns(mesh: SurfaceMesh, grids: list[np.ndarray], corner_deg: float = 30.0
                  ) -> list[np.ndarray]:
    """Per beam the ring indices of its longitudinal edges: sharp corners of the section outline
    and the ends of stretches shared with another beam (both judged at the first station)."""
    p = mesh.points
    rings = [p[g[0]] for g in grids]
    size = max(float(np.ptp(np.concatenate(rings), axis=0).max()), 1e-30)
    out = []
    for b, r in enumerate(rings):
        t = np.roll(r, -1, axis=0) - r
        t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-30)
        turn = np.degrees(np.arccos(np.clip(np.sum(t * np.roll(t, 1, axis=0), axis=1), -1, 1)))
        cols = turn > corner_deg
        others = [o for k, o in enumerate(rings) if k != b]
        if others:
            d = np.linalg.norm(r[:, None, :] - np.concatenate(others)[None], axis=-1).min(1)
            shared = d < 1e-4 * size
            cols |= shared & ~(np.roll(shared, 1) & np.roll(shared, -1))
        out.append(np.flatnonzero(cols))
    return out


def _line_segments(mesh: SurfaceMesh, grids: list[np.ndarray], cols: list[np.ndarray]
                   ) -> np.ndarray:
    """Segments (k, 2, 3) along the stations at the given ring indices of every beam."""
    segs = [np.stack([mesh.points[g[:-1, j]], mesh.points[g[1:, j]]], axis=1)
            for g, c in zip(grids, cols) for j in c]
    return np.concatenate(segs) if segs else np.zeros((0, 2, 3))


def _reference_lines(ref: SurfaceMesh, n_rings: int = 6, n_long: int = 8) -> np.ndarray:
    """Segments (k, 2, 3) of a coarse wireframe of the reference surface: a few cross-section
    rings (always both ends) and longitudinal lines, following the sampled surface."""
    grids = ref.grids()
    p = ref.points
    if grids is None:  # unknown layout: the edges of every quad
        q = ref.quads
        e = np.stack([q, np.roll(q, -1, axis=1)], axis=-1).reshape(-1, 2)
        return p[np.unique(np.sort(e, axis=1), axis=0)]
    segs = []
    for g in grids:
        ns, m = g.shape
        for s in np.unique(np.linspace(0, ns - 1, min(n_rings, ns)).round().astype(int)):
            segs.append(np.stack([p[g[s]], p[np.roll(g[s], -1)]], axis=1))
    cols = [np.unique(np.linspace(0, g.shape[1], min(n_long, g.shape[1]), endpoint=False)
                      .astype(int)) for g in grids]
    segs.append(_line_segments(ref, grids, cols))
    return np.concatenate(segs)


def _draw(ax, mesh: SurfaceMesh, fvals: np.ndarray, norm: colors.Normalize, cmap: str,
          view: tuple[float, float], lo: np.ndarray, hi: np.ndarray, scale: float,
          reference: SurfaceMesh | None) -> None:
    """Put one surface (caps, beam edges, reference wireframe) on a 3D axes as one collection,
    so that mplot3d depth-sorts all faces and lines together."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    aspect = (hi - lo) * np.array([1.0, scale, scale])
    pts = mesh.points * MM
    quads = pts[mesh.quads]
    cmap_ = cm.get_cmap(cmap)
    rgba = cmap_(norm(fvals))
    rgba[:, :3] *= _shade((quads - lo) / (hi - lo) * aspect, view)[:, None]
    polys, face, edge, width = list(quads), [rgba], [rgba.copy()], [np.full(len(quads), 0.3)]

    def add(items: list, fc: np.ndarray, ec, lw: float) -> None:
        polys.extend(items)
        face.append(fc)
        edge.append(np.broadcast_to(colors.to_rgba(*ec) if isinstance(ec, tuple) else ec,
                                    (len(items), 4)))
        width.append(np.full(len(items), lw))

    if mesh.caps:  # end caps: coloured by their mean value, outlined
        crgba = cmap_(norm(np.array([mesh.values[c].mean() for c in mesh.caps])))
        crgba[:, :3] *= 0.85
        add([pts[c] for c in mesh.caps], crgba, ("0.15", 1.0), 0.8)
    grids = mesh.grids()
    if grids is not None:  # the beams' longitudinal edges
        segs = _line_segments(mesh, grids, _seam_columns(mesh, grids)) * MM
        add(list(segs), np.zeros((len(segs), 4)), ("0.1", 0.8), 0.7)
    if reference is not None:
        segs = _reference_lines(reference) * MM
        add(list(segs), np.zeros((len(segs), 4)), ("0.45", 0.6), 0.5)
    ax.add_collection3d(Poly3DCollection(polys, facecolors=np.concatenate(face),
                                         edgecolors=np.concatenate(edge),
                                         linewidths=np.concatenate(width)))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(aspect)
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


def _render(panels: list[tuple[SurfaceMesh, np.ndarray, SurfaceMesh | None, str]], out_png: str,
            cmap: str, clim: tuple | None, view: tuple[float, float],
            section_scale: float | None, vertical: bool, panel_in: float = 8.0) -> str:
    """Render 3D panels, crop each to its drawn content and lay them out tightly with titles,
    one colour bar and a footnote (exaggeration, reference)."""
    dpi = 150
    pts = [p[0].points * MM for p in panels] + [p[2].points * MM for p in panels if p[2]]
    lo, hi, scale = _box(pts, section_scale)
    norm = _norm([p[1] for p in panels], clim)
    n = len(panels)
    cell = 1.5 * panel_in  # the axes square in the middle of a larger cell: nothing is clipped
    fig = Figure(figsize=(n * cell, cell), dpi=dpi, facecolor="white")
    canvas = FigureCanvasAgg(fig)
    axes = []
    for i, (mesh, fv, ref, _) in enumerate(panels):
        ax = fig.add_axes([(i * cell + (cell - panel_in) / 2) / (n * cell),
                           (cell - panel_in) / 2 / cell, panel_in / (n * cell), panel_in / cell],
                          projection="3d")
        _draw(ax, mesh, fv, norm, cmap, view, lo, hi, scale, ref)
        axes.append(ax)
    canvas.draw()
    img = np.asarray(canvas.buffer_rgba())
    px, off = int(round(cell * dpi)), (cell - panel_in) / 2
    boxes = [tuple(v - off for v in _content_box(img, (0, px, i * px, (i + 1) * px), dpi))
             for i in range(n)]
    # layout in inches: margin, title band, colour bar band, footnote band
    m, gap, cbw = 0.1, 0.25, 1.25
    title_h = 0.3 if any(p[3] for p in panels) else 0.0
    notes = ([f"y and z stretched {scale:g}x"] if scale != 1 else []) \
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
                    view: tuple[float, float] = (20.0, -60.0), cmap: str = "viridis",
                    clim: tuple | None = None, reference_vtu: str | None = None, *,
                    section_scale: float | None = None) -> str:
    """Shaded 3D render of a surface VTU, faces coloured by ``color_by`` (per-face mean).

    ``clim`` is in display units (strain in %).  ``reference_vtu`` (e.g. surface_0000.vtu) is
    drawn as a grey wireframe.  ``section_scale`` stretches y and z in the box aspect (default:
    automatic, 1-3x; stated in a footnote).  Dark lines mark each beam's longitudinal edges and
    end-cap outlines.  Returns ``out_png``.
    """
    mesh, fv = _prepare(vtu_path, color_by)
    ref = read_surface(reference_vtu) if reference_vtu else None
    return _render([(mesh, fv, ref, title)], out_png, cmap, clim, view, section_scale, False)


def render_pair(vtu_a: str, vtu_b: str, out_png: str, titles: tuple[str, str] = ("", ""),
                color_by: str = "E_xx", view: tuple[float, float] = (20.0, -60.0),
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
    cycle = cm.get_cmap("tab10").colors
    return {lab: cycle[i % len(cycle)] for i, lab in enumerate(dict.fromkeys(labels))}


def plot_load_elongation(curves: dict[str, tuple[list[float], list[float]]], paper_csv: str,
                         out_png: str, columns: dict[str, str], *, load_column: str = "load_N",
                         title: str = "") -> str:
    """Our load-elongation curves (lines) against the paper's points (markers), plus the relative
    error [%] at the paper's loads (ours interpolated) in a lower panel.

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
                label=f"{lab} (paper, {columns[lab]})")
        inside = (loads_p >= loads.min() - 1e-9) & (loads_p <= loads.max() + 1e-9)
        if inside.any():
            ours = np.interp(loads_p[inside], *(lambda o: (loads[o], elong[o]))(np.argsort(loads)))
            err = 100.0 * (ours - ref[inside]) / ref[inside]
            axe.plot(loads_p[inside], err, "o-", color=col[lab], ms=3.5, lw=1.0)
    axe.axhline(0.0, color="0.5", lw=0.6)
    ax.set_ylabel("elongation [mm]")
    axe.set_ylabel("rel. error [%]")
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
                     title: str = "", ylabel: str = "elongation at 400 N [mm]") -> str:
    """Elongation vs elements per subtendon (log2 x axis): ours lines + markers, the paper's open
    markers.  Entries with the same label in ``table`` and ``paper`` share a colour."""
    col = _colours(list(table) + list(paper))
    fig = Figure(figsize=(5.2, 3.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ticks: set[int] = set()
    for lab, pts in table.items():
        n, v = np.array(sorted(pts), dtype=float).T
        ax.plot(n, v, "-s", color=col[lab], ms=5, lw=1.5, label=f"{lab} (this code)")
        ticks.update(int(x) for x in n)
    for lab, pts in paper.items():
        n, v = np.array(sorted(pts), dtype=float).T
        ax.plot(n, v, "o", mfc="none", color=col[lab], ms=8, mew=1.3, label=f"{lab} (paper)")
        ticks.update(int(x) for x in n)
    ax.set_xscale("log", base=2)
    ax.xaxis.set_major_locator(FixedLocator(sorted(ticks)))
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_locator(FixedLocator([]))
    ax.set_xlabel("elements per subtendon")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, frameon=False)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return _save(fig, out_png)
