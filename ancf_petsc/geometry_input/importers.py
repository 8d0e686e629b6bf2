"""Outlines from the files labs have: point lists (CSV/YAML), SVG paths, label masks, NIfTI slices.

Every reader returns the outline in the FILE's coordinates (u, v) and units; ``build`` applies the
declared units and axes.  The libraries are imported lazily, only when a reader runs:
Pillow (PNG/TIFF labels), scikit-image (``measure.find_contours``: marching squares at the 0.5
level of the label's mask), nibabel (NIfTI) and svgelements (SVG paths, with their transforms).

Image coordinates: u = column index, v = row index (pixel centres at integers, v downwards);
NIfTI slices: u, v = the indices along the two remaining voxel axes, in increasing axis order.
Errors are :class:`OutlineReadError` with one line naming the file and the fix.
"""
from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from ..physics.spline import SectionError

__all__ = ["OutlineReadError", "RawOutline", "read_point_list", "read_svg_path", "label_image",
           "nifti_slice", "mask_outline"]

#: components (and holes) of a label smaller than this fraction of its largest region are dropped
SPECKLE = 0.01
#: samples per curved SVG segment (Bézier, arc); straight segments keep their two end points
SVG_SAMPLES = 64


class OutlineReadError(SectionError):
    """A source file cannot give the requested outline; the message names the file and the fix."""


@dataclass
class RawOutline:
    points: np.ndarray          # (n, 2) in file coordinates (u, v)
    closed: bool                # the source says the outline is closed
    notes: list = field(default_factory=list)


def _name(path: str) -> str:
    return os.path.basename(path)


# ------------------------------------------------------------------------------- point lists
def read_point_list(path: str) -> RawOutline:
    """Points from a CSV/TXT file (two numeric columns u, v; an optional header row; comma,
    semicolon, tab or space separated) or a YAML file (a list of [u, v] pairs, or {points: ...})."""
    low = path.lower()
    try:
        with open(path, newline="") as fh:
            text = fh.read()
    except OSError as exc:
        raise OutlineReadError(f"cannot read {_name(path)} ({exc.strerror})") from None
    if low.endswith((".yaml", ".yml")):
        import yaml

        from .. import yamlio
        try:
            data = yamlio.load(text)
        except yaml.YAMLError as exc:
            problem = getattr(exc, "problem", None)
            raise OutlineReadError(f"{_name(path)} is not valid YAML"
                                   + (f" ({problem})" if problem else "")) from None
        if isinstance(data, dict) and "points" in data:
            data = data["points"]
        try:
            P = np.array(data, dtype=float)
        except (TypeError, ValueError):
            P = np.zeros((0, 0))
        if P.ndim != 2 or P.shape[1] != 2:
            raise OutlineReadError(f"{_name(path)} must hold a list of [u, v] pairs (or points: [...])")
    else:
        # MATLAB ends each row with ';' ("1.5, 2.0;" or "1.5 2.0;"): a row terminator, not a column
        lines = [ln.rstrip() for ln in text.splitlines()]
        lines = [ln[:-1] if ln.endswith(";") else ln for ln in lines]
        try:
            dialect = csv.Sniffer().sniff("\n".join(lines)[:4096], delimiters=",;\t ")
            delim = dialect.delimiter
        except csv.Error:
            delim = ","
        rows, header = [], None
        for k, row in enumerate(csv.reader(lines, delimiter=delim)):
            row = [c.strip() for c in row if c.strip()]
            if not row or row[0].startswith("#"):
                continue
            try:
                vals = [float(c) for c in row[:2]]
            except ValueError:
                if not rows and header is None:
                    header = k                     # one header line, before the numbers
                    continue
                raise OutlineReadError(
                    f"{_name(path)} line {k + 1}: {row!r} is not two numbers u, v (one header "
                    "line is allowed, before the numbers; columns separated by a comma, "
                    "semicolon, tab or spaces)") from None
            if len(vals) != 2:
                raise OutlineReadError(f"{_name(path)} line {k + 1}: expected two columns u, v")
            rows.append(vals)
        P = np.array(rows, dtype=float).reshape(-1, 2)
    if len(P) < 3:
        raise OutlineReadError(f"{_name(path)} has {len(P)} points; an outline needs at least 3")
    if not np.all(np.isfinite(P)):
        raise OutlineReadError(f"{_name(path)} has non-finite coordinates")
    return RawOutline(P, closed=False)


# ------------------------------------------------------------------------------- SVG
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
        raise OutlineReadError(f"{_name(path)} is not a readable SVG ({type(exc).__name__})") from None
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
    return shapes


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
    """The closed path (or shape: rect, circle, ellipse, polygon) with id ``element_id``; without an
    id, the file's only closed path.  Curved segments are sampled (``SVG_SAMPLES`` each)."""
    import svgelements as se
    shapes = _svg_shapes(path, os.path.getmtime(path))
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
        raise OutlineReadError(f"{_name(path)} has no path with id '{element_id}' "
                               f"(ids: {', '.join(ids) or 'none'})")
    closed = [f for f in found if f[2] or np.linalg.norm(f[1][0] - f[1][-1]) <= 1e-9 * np.ptp(f[1], axis=0).max()]
    if not closed:
        what = f"path '{element_id}' is" if element_id else f"none of its {len(found)} path(s) is"
        raise OutlineReadError(f"{_name(path)}: {what} closed; close the outline (end the path with Z) "
                               "in the drawing program")
    if len(closed) > 1:
        which = f"path '{element_id}' has {len(closed)} closed subpaths" if element_id else \
            f"{len(closed)} closed paths ({', '.join(c[0] for c in closed[:5])})"
        raise OutlineReadError(f"{_name(path)}: {which}; name one outline per subtendon with path: <id>")
    return RawOutline(closed[0][1], closed=True)


# ------------------------------------------------------------------------------- masks
@lru_cache(maxsize=8)
def _image(path: str, mtime: float) -> np.ndarray:
    try:
        from PIL import Image
    except ImportError:
        raise OutlineReadError("reading label images needs Pillow (Debian python3-pil)") from None
    try:
        im = Image.open(path)
    except Exception:
        raise OutlineReadError(f"{_name(path)} is not an image Pillow can read") from None
    if getattr(im, "n_frames", 1) > 1:
        raise OutlineReadError(f"{_name(path)} has {im.n_frames} pages; save the slice as a single image "
                               "(or use a NIfTI volume with slice:)")
    if im.mode not in ("1", "L", "P", "I", "I;16", "I;16B", "I;16L", "F"):
        raise OutlineReadError(f"{_name(path)} is a {im.mode} image; a label mask has one channel "
                               "(grayscale or palette) holding the label values")
    a = np.array(im)
    if a.dtype.kind == "f":
        if not np.all(a == np.round(a)):
            raise OutlineReadError(f"{_name(path)} holds non-integer values; a label mask holds labels")
    return a.astype(np.int64)


def label_image(path: str) -> np.ndarray:
    """A 2D label image (PNG/TIFF), rows × columns."""
    return _image(path, os.path.getmtime(path))


@lru_cache(maxsize=4)
def _nifti(path: str, mtime: float):
    try:
        import nibabel as nib
    except ImportError:
        raise OutlineReadError("reading NIfTI needs nibabel (Debian python3-nibabel; run make setup)") from None
    try:
        img = nib.load(path)
        data = np.asanyarray(img.dataobj)
    except Exception:
        raise OutlineReadError(f"{_name(path)} is not a NIfTI file nibabel can read") from None
    zooms = tuple(float(z) for z in img.header.get_zooms()[:3])
    unit = img.header.get_xyzt_units()[0]
    return data, zooms, unit


NIFTI_UNITS = {"meter": 1.0, "mm": 1e-3, "micron": 1e-6}


def nifti_slice(path: str, axis: int, index: int) -> tuple[np.ndarray, tuple[float, float] | None, str]:
    """Slice ``index`` across voxel axis ``axis`` of a NIfTI label volume: the 2D labels (u, v
    = remaining axes in order), the in-slice voxel size in metres (None if the header has no
    spatial unit) and a description."""
    data, zooms, unit = _nifti(path, os.path.getmtime(path))
    while data.ndim > 3 and data.shape[-1] == 1:
        data = data[..., 0]
    if data.ndim != 3:
        raise OutlineReadError(f"{_name(path)} is a {data.ndim}D volume; expected 3D labels")
    if not 0 <= index < data.shape[axis]:
        raise OutlineReadError(f"{_name(path)}: slice index {index} is outside 0..{data.shape[axis] - 1} "
                               f"along axis {axis}")
    if data.dtype.kind == "f" and not np.all(np.take(data, index, axis=axis) == np.round(np.take(data, index, axis=axis))):
        raise OutlineReadError(f"{_name(path)} holds non-integer values; a label volume holds labels")
    sl = np.take(data, index, axis=axis).astype(np.int64)
    keep = [a for a in range(3) if a != axis]
    scale = None
    if unit in NIFTI_UNITS:
        scale = (zooms[keep[0]] * NIFTI_UNITS[unit], zooms[keep[1]] * NIFTI_UNITS[unit])
    return sl, scale, f"{_name(path)} axis {axis} slice {index}"


def _ring_area(C: np.ndarray) -> float:
    y, z = C[:, 0], C[:, 1]
    return 0.5 * float(np.sum(y * np.roll(z, -1) - np.roll(y, -1) * z))


def mask_outline(labels: np.ndarray, label: int, what: str) -> RawOutline:
    """Outline of the region ``labels == label``: the marching-squares contour at level 0.5
    (skimage.measure.find_contours) of its mask, in array index coordinates (first, second index).

    The largest region is kept; other regions and holes smaller than ``SPECKLE`` of it are
    dropped (noted); larger ones are an error (a subtendon is one region without holes)."""
    mask = labels == label
    if not mask.any():
        present = np.unique(labels)
        shown = ", ".join(str(v) for v in present[:12]) + (" ..." if present.size > 12 else "")
        raise OutlineReadError(f"{what}: no pixel has label {label} (labels present: {shown}); "
                               "check the label value of this subtendon")
    try:
        from skimage import measure
    except ImportError:
        raise OutlineReadError("tracing masks needs scikit-image (Debian python3-skimage; run make setup)") from None
    padded = np.pad(mask.astype(float), 1)
    contours = [c - 1.0 for c in measure.find_contours(padded, 0.5)]
    rings = [c[:-1] if np.allclose(c[0], c[-1]) else c for c in contours]
    areas = np.array([_ring_area(r) for r in rings])
    big = int(np.argmax(np.abs(areas)))
    sign = np.sign(areas[big])
    notes = []
    outer = [i for i in range(len(rings)) if np.sign(areas[i]) == sign and i != big]
    holes = [i for i in range(len(rings)) if np.sign(areas[i]) != sign]
    ref = abs(areas[big])
    for kind, idx in (("separate region", outer), ("hole", holes)):
        large = [i for i in idx if abs(areas[i]) > SPECKLE * ref]
        if large:
            raise OutlineReadError(f"{what}: label {label} has a {kind} of {abs(areas[large[0]]):.0f} px^2 "
                                   f"beside its main region of {ref:.0f} px^2; a subtendon is one region "
                                   "without holes: fix the mask")
        if idx:
            notes.append(f"dropped {len(idx)} {kind}(s) below {SPECKLE:.0%} of the region")
    return RawOutline(rings[big], closed=True, notes=notes)
