"""3D Slicer markups files (``*.mrk.json``): a cross-section drawn in Slicer with the closed-curve
(or curve) tool on an axial, sagittal or coronal slice.

The format, as Slicer's JSON schema (Modules/Loadable/Markups/Resources/Schema/markups-schema-
v1.0.3.json) and reader (vtkMRMLMarkupsJsonStorageNode) define it: ``{"@schema": ..., "markups":
[{"type": "ClosedCurve", "name": ..., "coordinateSystem": "LPS" | "RAS" (default LPS),
"coordinateUnits": "mm" | "um" (default mm; or a UCUM code triple), "controlPoints": [{"position":
[x, y, z], "positionStatus": "defined" | "preview" | "undefined" (default defined), ...}, ...]},
...]}``.  Slicer itself loads a file's first markup and saves no ``name``; files holding several
named markups come from scripts, and ``markup: <name>`` picks one.

A curve is not its control points: Slicer draws (and measures) the curve through them, by default
(vtkCurveGenerator, vtkAddon) a vtkCardinalSpline per coordinate over the point index (parameter
not by length): a C2 periodic cubic for a closed curve, end slopes 0 for an open one (vtkSpline's
default constraint).  The curve type lives in the scene, not in the .mrk.json, so that default is
assumed; the outline is that curve, sampled ``SAMPLES`` times per segment (scipy's CubicSpline
gives the same cubic).  With few control points the polygon through them would miss its area by
percents (16 points on an ellipse: -2.5 %).

The points are turned into RAS (LPS: x and y negated, as Slicer's reader does); they must lie in
one plane normal to a patient axis (their spread along it at most ``PLANE_TOLERANCE`` of their
extent); (u, v) are the two in-plane RAS coordinates in R, A, S order (axial: u = R, v = A;
coronal: R, S; sagittal: A, S), in the file's unit, which the importer gives as its scale (the
description's ``units`` must say the same)."""
from __future__ import annotations

import json

import numpy as np

from .base import Description, Importer, OutlineKey, OutlineReadError, RawOutline, file_name

__all__ = ["IMPORTER", "PLANE_TOLERANCE", "SAMPLES", "SlicerMarkups", "slicer_curve"]

#: the markup types that are outlines (Slicer's curve and closed-curve tools)
CURVE_TYPES = ("Curve", "ClosedCurve")
#: coordinate system → the signs that turn its positions into RAS
TO_RAS = {"LPS": np.array([-1.0, -1.0, 1.0]), "RAS": np.array([1.0, 1.0, 1.0])}
#: coordinateUnits (UCUM codes of the schema) → metres
UNIT_METRES = {"mm": 1e-3, "um": 1e-6}
AXES = ("R", "A", "S")
PLANES = ("sagittal", "coronal", "axial")           # by the axis normal to them
#: largest spread of the points along the plane's normal, relative to their largest extent
PLANE_TOLERANCE = 1e-3
#: samples of the curve per segment between control points (Slicer draws 10)
SAMPLES = 64


def slicer_curve(P: np.ndarray, closed: bool) -> np.ndarray:
    """Slicer's default curve through control points P (n, d), sampled ``SAMPLES`` times per
    segment (closed: without repeating the first point)."""
    from scipy.interpolate import CubicSpline    # only here: scipy.interpolate takes ~0.1 s to import
    n = len(P)
    if closed:
        spline = CubicSpline(np.arange(n + 1), np.vstack([P, P[:1]]), bc_type="periodic")
        return spline(np.arange(n * SAMPLES) / SAMPLES)
    spline = CubicSpline(np.arange(n), P, bc_type="clamped")
    return spline(np.arange((n - 1) * SAMPLES + 1) / SAMPLES)


def _load(path: str) -> dict:
    name = file_name(path)
    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except OSError as exc:
        raise OutlineReadError(f"cannot read {name} ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise OutlineReadError(f"{name} is not a text (UTF-8) JSON file") from None
    except json.JSONDecodeError as exc:
        raise OutlineReadError(f"{name} is not valid JSON (line {exc.lineno}: {exc.msg})") from None
    if not isinstance(data, dict) or not isinstance(data.get("markups"), list):
        raise OutlineReadError(f"{name} is not a 3D Slicer markups file (no 'markups' list); save the "
                               "curve from Slicer as Markups JSON (.mrk.json)")
    return data


def _title(k: int, m: dict) -> str:
    return f"'{m['name']}'" if isinstance(m.get("name"), str) else f"#{k} (unnamed)"


def _select(data: dict, wanted: str | None, name: str) -> tuple[str, dict]:
    """The curve markup named ``wanted``, or the file's only curve markup."""
    marks = [(k, m) for k, m in enumerate(data["markups"]) if isinstance(m, dict)]
    curves = [(k, m) for k, m in marks if m.get("type") in CURVE_TYPES]
    if not curves:
        types = sorted({str(m.get("type")) for _, m in marks})
        raise OutlineReadError(f"{name} holds no curve markup (types: {', '.join(types) or 'none'}); draw "
                               "the outline with Slicer's closed curve tool")
    names = ", ".join(_title(k, m) for k, m in curves)
    if wanted is None:
        if len(curves) > 1:
            raise OutlineReadError(f"{name} holds {len(curves)} curve markups ({names}); name one per "
                                   "subtendon with markup: <name>")
        return _title(*curves[0]), curves[0][1]
    hits = [(k, m) for k, m in curves if m.get("name") == wanted]
    if len(hits) != 1:
        what = "no curve markup" if not hits else f"{len(hits)} curve markups"
        raise OutlineReadError(f"{name} has {what} named '{wanted}' (curve markups: {names}); give each "
                               "markup its own \"name\" in the file, or save one markup per file")
    return _title(*hits[0]), hits[0][1]


def _unit(m: dict, where: str) -> str:
    """The markup's coordinateUnits as a UCUM code (a string, or the code of a coded entry)."""
    unit = m.get("coordinateUnits", "mm")
    if isinstance(unit, list) and len(unit) == 3 and unit[1] == "UCUM":
        unit = unit[0]
    if unit not in UNIT_METRES:
        raise OutlineReadError(f"{where}: coordinateUnits {unit!r} is not one of the schema's "
                               f"{', '.join(UNIT_METRES)}")
    return unit


def _ras_points(m: dict, where: str) -> tuple[np.ndarray, int]:
    """RAS positions of the defined control points, and how many were not defined."""
    system = m.get("coordinateSystem", "LPS")
    if system not in TO_RAS:
        raise OutlineReadError(f"{where}: coordinateSystem {system!r} is not LPS or RAS")
    cps = m.get("controlPoints", [])
    if not isinstance(cps, list):
        raise OutlineReadError(f"{where}: controlPoints is not a list")
    pts, skipped = [], 0
    for j, cp in enumerate(cps):
        cp = cp if isinstance(cp, dict) else {}
        if cp.get("positionStatus", "defined") != "defined" or "position" not in cp:
            skipped += 1                                # not placed (Slicer: an undefined position)
            continue
        pos = cp["position"]
        if not (isinstance(pos, list) and len(pos) == 3 and all(isinstance(x, (int, float)) for x in pos)
                and np.all(np.isfinite(pos))):
            raise OutlineReadError(f"{where}: control point {j + 1}'s position is not 3 numbers")
        pts.append(pos)
    if len(pts) < 3:
        raise OutlineReadError(f"{where} has {len(pts)} placed control points; an outline needs at least 3")
    return np.array(pts, dtype=float) * TO_RAS[system], skipped


def _in_plane(P: np.ndarray, where: str, unit: str) -> tuple[np.ndarray, str]:
    """(u, v) of points in one plane normal to a patient axis, and that plane in words."""
    spread = np.ptp(P, axis=0)
    normal = int(np.argmin(spread))
    extent = float(spread.max())
    if extent == 0.0:
        raise OutlineReadError(f"{where}: all control points coincide")
    if spread[normal] > PLANE_TOLERANCE * extent:
        raise OutlineReadError(f"{where} does not lie in a plane normal to a patient axis: its points "
                               f"spread {spread[normal]:.4g} {unit} along {AXES[normal]} (the least) over "
                               f"{extent:.4g} {unit}; draw the curve in Slicer's Axial, Sagittal or Coronal "
                               "slice view (not a reformatted, oblique one)")
    keep = [a for a in range(3) if a != normal]
    plane = (f"{PLANES[normal]} plane {AXES[normal]} = {np.median(P[:, normal]):.6g} {unit}, "
             f"u = {AXES[keep[0]]}, v = {AXES[keep[1]]} (RAS)")
    return P[:, keep], plane


class SlicerMarkups(Importer):
    name = "slicer_markups"
    title = "3D Slicer markups file"
    extensions = (".mrk.json",)
    keys = (OutlineKey("markup", str, "the name of the curve markup in the file, e.g. markup: soleus"),)

    def read(self, path: str, keys: dict, desc: Description) -> RawOutline:
        name = file_name(path)
        label, m = _select(_load(path), keys.get("markup"), name)
        where = f"{name} markup {label}"
        unit = _unit(m, where)
        s = UNIT_METRES[unit]
        if desc.units == "px" or desc.scale is None or not np.allclose(desc.scale, (s, s), rtol=1e-12, atol=0.0):
            raise OutlineReadError(f"{name}: its coordinates are in {unit} (coordinateUnits); declare "
                                   f"units: {unit} (the description says units: {desc.units})")
        P, skipped = _ras_points(m, where)
        uv, plane = _in_plane(P, where, unit)
        closed = m["type"] == "ClosedCurve"
        notes = [f"{where}: {len(uv)} control points in the {plane}; the curve through them as Slicer "
                 f"draws it (cardinal spline, {SAMPLES} samples per segment)"]
        if skipped:
            notes.append(f"{where}: {skipped} control point(s) not placed (positionStatus), left out")
        return RawOutline(slicer_curve(uv, closed), closed=closed, notes=notes, scale=(s, s))


IMPORTER = SlicerMarkups()
