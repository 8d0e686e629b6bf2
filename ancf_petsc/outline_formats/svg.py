"""SVG: the closed path (or shape: rect, circle, ellipse, polygon) with a given id, with its
transforms, in the document's user units (the viewBox's), read with svgelements (imported only
when a file is read).  Curved segments are sampled (``SVG_SAMPLES`` each)."""
from __future__ import annotations

import os
import re
from functools import lru_cache

import numpy as np

from .base import Description, Importer, OutlineKey, OutlineReadError, RawOutline, file_name

__all__ = ["IMPORTER", "SVG_SAMPLES", "SvgPath", "read_svg_path"]

#: samples per curved SVG segment (Bézier, arc); straight segments keep their two end points
SVG_SAMPLES = 64
#: metres per unit of the absolute lengths an SVG's width may be given in
ABSOLUTE = {"mm": 1e-3, "cm": 1e-2, "q": 0.25e-3, "in": 0.0254, "pt": 0.0254 / 72, "pc": 0.0254 / 6}


def _stated_unit(svg, path: str) -> tuple[float, str] | None:
    """Metres per user unit that the document states (an absolute width over its viewBox's), and how."""
    values = getattr(svg, "values", {}) or {}
    width, box = str(values.get("width", "")).strip(), str(values.get("viewBox", "")).replace(",", " ").split()
    m = re.fullmatch(r"(.*?)\s*(mm|cm|q|in|pt|pc)", width, re.IGNORECASE)
    if m and not re.fullmatch(r"\+?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?", m.group(1)):
        raise OutlineReadError(f"{file_name(path)}: its width {width!r} is not a length (a number and a unit, "
                               "e.g. 40mm): correct it in the file")
    try:
        wide = float(box[2]) if m and len(box) == 4 else 0.0
    except ValueError:
        wide = 0.0
    if wide <= 0.0 or float(m.group(1)) <= 0.0:
        return None
    return float(m.group(1)) * ABSOLUTE[m.group(2).lower()] / wide, f"width {width} over a viewBox {wide:g} wide"


@lru_cache(maxsize=8)
def _svg_shapes(path: str, mtime: float):
    try:
        import svgelements as se
    except ImportError:
        raise OutlineReadError("reading SVG needs the svgelements package (Debian python3-svgelements; "
                               "run make setup)") from None
    try:
        svg = se.SVG.parse(path, reify=True)
    except Exception as exc:                        # malformed XML and the like
        raise OutlineReadError(f"{file_name(path)} is not a readable SVG ({type(exc).__name__})") from None
    # svgelements maps user units to CSS px through the viewBox; undo it: coordinates are user units
    inv = ~se.Matrix(svg.viewbox_transform) if getattr(svg, "viewbox_transform", None) else None
    shapes = []
    for k, e in enumerate(svg.elements()):
        if not isinstance(e, se.Shape) or isinstance(e, se.SVG):
            continue
        p = se.Path(e)
        if inv is not None:
            p = p * inv
            p.reify()
        shapes.append((e.id or f"<{type(e).__name__.lower()} #{k}>", p))
    return shapes, _stated_unit(svg, path)


def _subpath_points(sub) -> tuple[np.ndarray, bool]:
    import svgelements as se
    pts, closed = [], False
    for seg in sub.segments():
        if isinstance(seg, se.Move):
            pts.append([seg.end.x, seg.end.y])
        elif isinstance(seg, se.Close):
            closed = True
        elif isinstance(seg, se.Line):
            pts.append([seg.end.x, seg.end.y])
        else:
            t = np.linspace(0.0, 1.0, SVG_SAMPLES + 1)[1:]
            pts.extend(np.asarray(seg.npoint(t), dtype=float).tolist())
    P = np.array(pts, dtype=float).reshape(-1, 2)
    return P, closed


def read_svg_path(path: str, element_id: str | None) -> RawOutline:
    """The closed path with id ``element_id``; without an id, the file's only closed path."""
    import svgelements as se
    shapes, _ = _svg_shapes(path, os.path.getmtime(path))
    found = []
    for sid, p in shapes:
        if element_id is not None and sid != element_id:
            continue
        for sub in p.as_subpaths():
            P, closed = _subpath_points(se.Path(sub))
            if len(P) >= 2:
                found.append((sid, P, closed))
    if element_id is not None and not found:
        ids = sorted({sid for sid, _ in shapes})
        raise OutlineReadError(f"{file_name(path)} has no path with id '{element_id}' "
                               f"(ids: {', '.join(ids) or 'none'})")
    closed = [f for f in found if f[2] or np.linalg.norm(f[1][0] - f[1][-1]) <= 1e-9 * np.ptp(f[1], axis=0).max()]
    if not closed:
        what = f"path '{element_id}' is" if element_id else f"none of its {len(found)} path(s) is"
        raise OutlineReadError(f"{file_name(path)}: {what} closed; close the outline (end the path with Z) "
                               "in the drawing program")
    if len(closed) > 1:
        which = f"path '{element_id}' has {len(closed)} closed subpaths" if element_id else \
            f"{len(closed)} closed paths ({', '.join(c[0] for c in closed[:5])})"
        raise OutlineReadError(f"{file_name(path)}: {which}; name one outline per subtendon with path: <id>")
    return RawOutline(closed[0][1], closed=True)


class SvgPath(Importer):
    name = "svg"
    title = "SVG drawing"
    extensions = (".svg",)
    keys = (OutlineKey("path", str, "the id of the SVG element, e.g. path: soleus"),)

    def read(self, path: str, keys: dict, desc: Description) -> RawOutline:
        out = read_svg_path(path, keys.get("path"))
        stated = _svg_shapes(path, os.path.getmtime(path))[1]
        if stated is not None and desc.units != "px" and desc.scale is not None:
            ratio = desc.scale[0] / stated[0]
            if abs(ratio - 1.0) > 1e-3:      # a drawing of 40 mm over a viewBox of 400 read as units: mm
                out.notes.append(f"warning: {file_name(path)} states a user unit of {stated[0] * 1e3:.4g} mm "
                                 f"({stated[1]}); units: {desc.units} reads it as {ratio:.4g} x that: check "
                                 f"units (or give units: px, pixel_size: {stated[0] * 1e3:.4g} mm)")
        return out


IMPORTER = SvgPath()
