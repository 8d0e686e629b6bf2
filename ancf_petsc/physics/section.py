"""Beam cross-sections: analytic shapes and spline outlines (paper Sec. 2.2, eqs. 9-11).

Coordinates are (y, z) in the tendon frame, in metres.  A :class:`Section` carries its
area centroid (tendon frame), area, second moments about the centroid and a cubature rule
(points in CENTROIDAL coordinates, weights in m^2).

Outlines are closed loops of :class:`SplineCurve` objects (spline.py): interpolating splines
through control points with the cumulative chordal parametrisation of Sec. 2.2.  Their rule is the
Gauss-Green cubature of eq. (11), compressed to positive interior weights.  Interfaces
between neighbouring sections are ONE curve object used by both (once reversed), so the
two sides coincide exactly.
"""
from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

from .cubature import CompressionError, compress_rule, ellipse_rule, gauss_green_rule, rectangle_rule
from .polygon import first_self_intersection, inside_with_margin, loop_polyline, segment_owner
from .spline import SectionError, SplineCurve

__all__ = ["SectionError", "SplineCurve", "Section", "make_ellipse", "make_circle", "make_rectangle",
           "make_outline"]

DEFAULT_CUBATURE_DEGREE = 6
_JOIN_RTOL = 1e-9


def _moments(pts: np.ndarray, w: np.ndarray) -> tuple[float, np.ndarray, float, float, float]:
    """Area, centroid and second moments about the centroid of a rule (exact if degree >= 2)."""
    area = float(w.sum())
    c = (w @ pts) / area
    d = pts - c
    Syy = float(w @ (d[:, 0] ** 2))
    Szz = float(w @ (d[:, 1] ** 2))
    Syz = float(w @ (d[:, 0] * d[:, 1]))
    return area, c, Syy, Szz, Syz


def _check_degree(degree: Any) -> int:
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or degree < 0:
        raise SectionError(f"the cubature degree must be a non-negative integer, got {degree!r}")
    return int(degree)


def _check_pair(value: Any, what: str, positive: bool) -> np.ndarray:
    try:
        v = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        v = np.empty(0)
    if v.shape != (2,) or not np.all(np.isfinite(v)) or (positive and not np.all(v > 0)):
        need = "two positive numbers" if positive else "two finite numbers [y, z]"
        raise SectionError(f"the {what} must be {need}, got {value!r}")
    return v


# --------------------------------------------------------------------------------------
# Section
# --------------------------------------------------------------------------------------
class Section:
    """A beam cross-section with its cubature rule (eqs. 9-11).

    Attributes: ``kind`` ('ellipse' | 'circle' | 'rectangle' | 'outline'), ``centroid`` (2,)
    area centroid in the tendon frame [m], ``area`` [m^2], ``Syy``, ``Szz``, ``Syz``
    (integrals of y'^2, z'^2, y'z' about the centroid) [m^4], ``points`` (n, 2) cubature
    points in centroidal coordinates [m], ``weights`` (n,) [m^2], ``loop`` (outline curves
    with reversed flags, counter-clockwise; None for analytic shapes), ``extent`` (2,)
    half-widths max|y'|, max|z'| of the section about its centroid [m], ``degree`` of
    exactness of the rule, ``notes`` (warnings, e.g. compression fall-back).
    """

    def __init__(self, kind: str, centroid: np.ndarray, area: float, Syy: float, Szz: float,
                 Syz: float, points: np.ndarray, weights: np.ndarray, extent: np.ndarray,
                 degree: int, loop: list[tuple[SplineCurve, bool]] | None = None,
                 shape_params: Mapping[str, Any] | None = None,
                 notes: list[str] | None = None) -> None:
        self.kind = kind
        self.centroid = np.asarray(centroid, dtype=float)
        self.area = float(area)
        self.Syy = float(Syy)
        self.Szz = float(Szz)
        self.Syz = float(Syz)
        self.points = np.asarray(points, dtype=float)
        self.weights = np.asarray(weights, dtype=float)
        self.extent = np.asarray(extent, dtype=float)
        self.degree = int(degree)
        self.loop = loop
        self.shape_params = dict(shape_params or {})
        self.notes = list(notes or [])
        self._poly_cache: tuple[np.ndarray, float] | None = None

    @property
    def n_points(self) -> int:
        return int(self.weights.shape[0])

    def boundary_polyline(self, n_per_piece: int = 8) -> np.ndarray:
        """Closed counter-clockwise boundary polyline (k, 2) in centroidal coordinates.

        The closing segment from the last point back to the first is implied (the first
        point is not repeated).  For outlines each spline piece contributes ``n_per_piece``
        segments and points on a shared interface curve are bit-identical on both sides;
        analytic shapes are sampled on their exact boundary.
        """
        n = max(1, int(n_per_piece))
        c = self.centroid
        if self.kind in ("ellipse", "circle"):
            a, b = self.shape_params["semi_axes"]
            th = 2.0 * np.pi * np.arange(8 * n) / (8 * n)
            return np.column_stack([a * np.cos(th), b * np.sin(th)])
        if self.kind == "rectangle":
            wdt, hgt = self.shape_params["size"]
            corners = 0.5 * np.array([[-wdt, -hgt], [wdt, -hgt], [wdt, hgt], [-wdt, hgt]])
            s = np.arange(n) / n
            nxt = np.roll(corners, -1, axis=0)
            return (corners[:, None, :] + s[None, :, None] * (nxt - corners)[:, None, :]
                    ).reshape(-1, 2)
        parts = [(cv.reversed() if flip else cv).sample(n)[:-1] for cv, flip in self.loop]
        return np.vstack(parts) + self.shape_params["offset"] - c

    def _fine_polygon(self) -> tuple[np.ndarray, float]:
        """Fine polyline (centroidal coordinates) and a margin bounding its distance to
        the true boundary (twice the largest chord sagitta)."""
        if self._poly_cache is None:
            if self.loop is None:
                self._poly_cache = (self.boundary_polyline(32), 0.0)
            else:
                eff = [cv.reversed() if flip else cv for cv, flip in self.loop]
                poly, sag = loop_polyline(eff)
                self._poly_cache = (poly + self.shape_params["offset"] - self.centroid, sag)
        return self._poly_cache

    def contains(self, pts: Any) -> np.ndarray:
        """Boolean mask of the (centroidal) points strictly inside the section.

        Exact for analytic shapes; for outlines, points inside a fine polyline of the
        boundary and farther from it than its maximal deviation from the splines.
        """
        P = np.asarray(pts, dtype=float).reshape(-1, 2)
        if self.kind in ("ellipse", "circle"):
            a, b = self.shape_params["semi_axes"]
            return (P[:, 0] / a) ** 2 + (P[:, 1] / b) ** 2 < 1.0
        if self.kind == "rectangle":
            wdt, hgt = self.shape_params["size"]
            return (np.abs(P[:, 0]) < 0.5 * wdt) & (np.abs(P[:, 1]) < 0.5 * hgt)
        poly, margin = self._fine_polygon()
        return inside_with_margin(P, poly, margin)

    @property
    def smallest_width(self) -> float:
        """The section's smallest width [m]: the least distance between two parallel lines that
        enclose it (its convex hull's, attained with one line on a hull edge)."""
        from scipy.spatial import ConvexHull
        pts, _ = self._fine_polygon()
        hull = pts[ConvexHull(pts).vertices]
        edge = np.roll(hull, -1, axis=0) - hull
        normal = np.column_stack([edge[:, 1], -edge[:, 0]]) / np.linalg.norm(edge, axis=1)[:, None]
        heights = hull @ normal.T
        return float((heights.max(axis=0) - heights.min(axis=0)).min())

    def describe(self) -> str:
        """One line: kind, area [mm^2], centroid [mm], second moments [mm^4], point count."""
        return (f"{self.kind}: area {self.area * 1e6:.4g} mm^2, centroid "
                f"({self.centroid[0] * 1e3:.4g}, {self.centroid[1] * 1e3:.4g}) mm, "
                f"Syy {self.Syy * 1e12:.4g} Szz {self.Szz * 1e12:.4g} "
                f"Syz {self.Syz * 1e12:.4g} mm^4, {self.n_points} cubature points "
                f"(degree {self.degree})")

    def __repr__(self) -> str:
        return f"<Section {self.describe()}>"


def _fmt_mm(p: np.ndarray) -> str:
    return f"({p[0] * 1e3:.6g}, {p[1] * 1e3:.6g}) mm"


# --------------------------------------------------------------------------------------
# Constructors
# --------------------------------------------------------------------------------------
def make_ellipse(semi_axes: Sequence[float], center: Sequence[float] = (0.0, 0.0),
                 degree: int = DEFAULT_CUBATURE_DEGREE) -> Section:
    """Elliptic section with semi-axes (a along y, b along z) centred at ``center`` [m];
    polar cubature exact for total degree ``degree``."""
    ab = _check_pair(semi_axes, "ellipse semi-axes [a, b]", positive=True)
    c = _check_pair(center, "section centre", positive=False)
    return _analytic("ellipse", ab, c, _check_degree(degree))


def make_circle(radius: float, center: Sequence[float] = (0.0, 0.0),
                degree: int = DEFAULT_CUBATURE_DEGREE) -> Section:
    """Circular section of radius ``radius`` centred at ``center`` [m]."""
    try:
        r = float(radius)
    except (TypeError, ValueError):
        r = float("nan")
    if not (np.isfinite(r) and r > 0):
        raise SectionError(f"the circle radius must be a positive number, got {radius!r}")
    c = _check_pair(center, "section centre", positive=False)
    return _analytic("circle", np.array([r, r]), c, _check_degree(degree))


def make_rectangle(size: Sequence[float], center: Sequence[float] = (0.0, 0.0),
                   degree: int = DEFAULT_CUBATURE_DEGREE) -> Section:
    """Rectangular section, ``size`` = [width along y, height along z] [m], centred at
    ``center``; tensor Gauss rule (eq. 9) exact for total degree ``degree``."""
    wh = _check_pair(size, "rectangle size [width, height]", positive=True)
    c = _check_pair(center, "section centre", positive=False)
    return _analytic("rectangle", wh, c, _check_degree(degree))


def _analytic(kind: str, dims: np.ndarray, c: np.ndarray, degree: int) -> Section:
    if kind == "rectangle":
        pts, w = rectangle_rule(dims[0], dims[1], degree)
        gp, gw = rectangle_rule(dims[0], dims[1], max(degree, 2))
        params = {"size": (float(dims[0]), float(dims[1]))}
        extent = 0.5 * dims
    else:
        pts, w = ellipse_rule(dims[0], dims[1], degree)
        gp, gw = ellipse_rule(dims[0], dims[1], max(degree, 2))
        params = {"semi_axes": (float(dims[0]), float(dims[1]))}
        extent = dims.copy()
    area, cl, Syy, Szz, Syz = _moments(gp, gw)
    # The rules are symmetric about 0: the centroid is the given centre (cl is round-off).
    return Section(kind, c.copy(), area, Syy, Szz, Syz, pts, w, extent, degree,
                   loop=None, shape_params=params)


def _normalise_loop(loop: Any) -> list[tuple[SplineCurve, bool]]:
    try:
        items = list(loop)
    except TypeError:
        raise SectionError("an outline must be a list of (curve, reversed) pairs; "
                           "build it with inline_loop() or load_sections_file()") from None
    if not items:
        raise SectionError("the outline has no curves; give at least one closed curve")
    out = []
    for k, item in enumerate(items):
        if isinstance(item, SplineCurve):
            cv, flip = item, False
        else:
            try:
                cv, flip = item
            except (TypeError, ValueError):
                raise SectionError(f"outline entry {k + 1} is not a (curve, reversed) pair; "
                                   "build the loop with inline_loop()") from None
        if not isinstance(cv, SplineCurve):
            raise SectionError(f"outline entry {k + 1} is not a SplineCurve; "
                               "build the loop with inline_loop()")
        out.append((cv, bool(flip)))
    return out


def make_outline(loop: Sequence[tuple[SplineCurve, bool]],
                 degree: int = DEFAULT_CUBATURE_DEGREE, compress: bool = True,
                 center: Sequence[float] = (0.0, 0.0)) -> Section:
    """Section bounded by a closed loop of spline curves (eqs. 10-11).

    ``loop`` is a list of (SplineCurve, reversed_flag) in order around the boundary, either
    orientation (stored counter-clockwise).  The curves' coordinates are shifted by
    ``center`` into the tendon frame.  The rule is the Gauss-Green cubature of eq. (11) of
    degree ``degree``, compressed (``compress=True``) to positive weights on interior nodes;
    if compression fails the raw rule is kept and a note is added to ``Section.notes``.
    """
    degree = _check_degree(degree)
    offset = _check_pair(center, "outline centre offset", positive=False)
    items = _normalise_loop(loop)
    eff = [cv.reversed() if flip else cv for cv, flip in items]

    allp = np.vstack([cv.points for cv in eff])
    size = float(np.hypot(*np.ptp(allp, axis=0)))
    if size == 0.0:
        raise SectionError("the outline has zero size; give curves with distinct points")
    for k, cv in enumerate(eff):
        nxt = eff[(k + 1) % len(eff)]
        gap = float(np.linalg.norm(cv.end - nxt.start))
        if gap > _JOIN_RTOL * size:
            if len(eff) == 1:
                raise SectionError(
                    f"curve '{cv.name}' does not close: it ends at {_fmt_mm(cv.end)} but "
                    f"starts at {_fmt_mm(cv.start)}; repeat its first point at the end")
            raise SectionError(
                f"curve '{cv.name}' ends at {_fmt_mm(cv.end)} but the next curve "
                f"'{nxt.name}' starts at {_fmt_mm(nxt.start)}; list the curves in order "
                "around the boundary (prefix a name with '-' to reverse it) so that "
                "consecutive curves share their end points")

    poly, sag = loop_polyline(eff)
    hit = first_self_intersection(poly, 1e-12 * size)
    if hit is not None:
        owner = segment_owner(eff, poly.shape[0])
        a, b = owner[hit[0]], owner[hit[1]]
        where = f"curve '{a}' crosses itself" if a == b else \
            f"curves '{a}' and '{b}' cross"
        raise SectionError(
            f"the outline intersects itself ({where} near {_fmt_mm(poly[hit[0]])}); move the "
            "control points or lower the spline degree so that the boundary is a simple loop")

    gdeg = max(degree, 2)
    pieces = [pc for cv in eff for pc in cv.pieces()]
    gp, gw = gauss_green_rule(pieces, gdeg)
    signed = float(gw.sum())
    if abs(signed) <= 1e-10 * size * size:
        raise SectionError("the outline encloses no area; give a loop around a region")
    if signed < 0:
        items = [(cv, not flip) for cv, flip in reversed(items)]
        eff = [cv.reversed() if flip else cv for cv, flip in items]
        poly = poly[::-1].copy()
        pieces = [pc for cv in eff for pc in cv.pieces()]
        gp, gw = gauss_green_rule(pieces, gdeg)
    area, c_loc, Syy, Szz, Syz = _moments(gp, gw)
    if degree == gdeg:
        pts, w = gp, gw
    else:
        pts, w = gauss_green_rule(pieces, degree)

    notes: list[str] = []
    if compress:
        try:
            pts, w = compress_rule(pts, w, degree,
                                   lambda P: inside_with_margin(P, poly, sag))
        except CompressionError as exc:
            notes.append(f"cubature compression failed ({exc}); using the raw Gauss-Green "
                         f"rule with {w.size} points, some possibly outside the section or "
                         "with negative weights")

    dev = poly - c_loc
    extent = np.abs(dev).max(axis=0)
    sec = Section("outline", c_loc + offset, area, Syy, Szz, Syz, pts - c_loc, w, extent,
                  degree, loop=items, shape_params={"offset": offset}, notes=notes)
    sec._poly_cache = (poly - c_loc, sag)
    return sec
