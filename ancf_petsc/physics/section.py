"""Beam cross-sections: analytic shapes and spline outlines (paper Sec. 2.2, eqs. 9-11).

Coordinates are (y, z) in the tendon frame, in metres.  A :class:`Section` carries its
area centroid (tendon frame), area, second moments about the centroid and a cubature rule
(points in CENTROIDAL coordinates, weights in m^2).

Outlines are closed loops of :class:`SplineCurve` objects: interpolating splines through
control points with the cumulative chordal parametrisation of Sec. 2.2.  Their rule is the
Gauss-Green cubature of eq. (11), compressed to positive interior weights.  Interfaces
between neighbouring sections are ONE curve object used by both (once reversed), so the
two sides coincide exactly.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
from scipy.interpolate import make_interp_spline

from .cubature import (CompressionError, CurvePiece, compress_rule, ellipse_rule, gauss_green_rule,
    rectangle_rule)

__all__ = [
    "SectionError",
    "SplineCurve",
    "Section",
    "SectionsFile",
    "make_ellipse",
    "make_circle",
    "make_rectangle",
    "make_outline",
    "inline_loop",
    "load_sections_file",
]

DEFAULT_SPLINE_DEGREE = 3
DEFAULT_CUBATURE_DEGREE = 6
_JOIN_RTOL = 1e-9
_MAX_SEGMENTS = 4096          # cap on the fine polyline used for geometric checks


class SectionError(ValueError):
    """Invalid cross-section input; the message says what is wrong and how to fix it."""


# --------------------------------------------------------------------------------------
# Spline curves
# --------------------------------------------------------------------------------------
class SplineCurve:
    """Interpolating spline S(t) = (S_1(t), S_2(t)) through control points (Sec. 2.2).

    Parameter: cumulative chordal, t_1 = 0, t_{j+1} = t_j + |P_{j+1} - P_j|.  Degree
    p = min(degree, m - 1) (``scipy.interpolate.make_interp_spline``, not-a-knot; p = 1
    is the polygon through the points).  ``breakpoints`` are the parameters between which
    the spline is one polynomial; :meth:`pieces` hands them to the Gauss-Green rule (eq. 11).

    :meth:`reversed` returns the same geometry traversed backwards, t' = t_end - t, built on
    the SAME underlying spline object.
    """

    name: str
    points: np.ndarray
    degree: int
    t_end: float
    params: np.ndarray
    breakpoints: np.ndarray

    def __init__(self, points: Any, degree: int = DEFAULT_SPLINE_DEGREE,
                 name: str = "curve") -> None:
        name = str(name)
        try:
            P = np.array(points, dtype=float)
        except (TypeError, ValueError):
            raise SectionError(f"the control points of curve '{name}' are not numbers; "
                               "give them as a list of [y, z] pairs") from None
        if P.ndim != 2 or P.shape[1] != 2 or P.shape[0] < 2:
            raise SectionError(f"curve '{name}' needs at least two control points given as "
                               f"[y, z] pairs, got an array of shape {P.shape}")
        if not np.all(np.isfinite(P)):
            raise SectionError(f"curve '{name}' has non-finite control points; "
                               "replace them by finite coordinates")
        if isinstance(degree, bool) or int(degree) != degree or int(degree) < 1:
            raise SectionError(f"the spline degree of curve '{name}' must be an integer >= 1, "
                               f"got {degree!r}")
        chords = np.linalg.norm(np.diff(P, axis=0), axis=1)
        size = float(np.ptp(P, axis=0).max())
        if size == 0.0 or np.any(chords <= 1e-12 * size):
            j = int(np.argmin(chords)) if size > 0 else 0
            raise SectionError(f"curve '{name}' repeats control point {j + 1} "
                               f"({P[j, 0]:g}, {P[j, 1]:g}) consecutively; "
                               "remove the duplicate")
        t = np.concatenate([[0.0], np.cumsum(chords)])
        p = min(int(degree), P.shape[0] - 1)
        spl = make_interp_spline(t, P, k=p)
        t_end = float(t[-1])
        bp = np.unique(np.concatenate([spl.t, t]))
        bp = bp[(bp >= 0.0) & (bp <= t_end)]
        keep = np.r_[True, np.diff(bp) > 1e-13 * t_end]
        bp = bp[keep]
        bp[0], bp[-1] = 0.0, t_end

        self.name = name
        self.points = P
        self.degree = p
        self.t_end = t_end
        self.params = t
        self.breakpoints = bp
        self._spline = spl
        self._derivs = {0: spl}
        self._flipped = False
        self._base: SplineCurve = self
        self._reverse: SplineCurve | None = None

    # -- evaluation ----------------------------------------------------------------
    def _forward(self, s: np.ndarray, nu: int = 0) -> np.ndarray:
        """Evaluate the underlying (forward) spline or its nu-th derivative."""
        base = self._base
        if nu not in base._derivs:
            base._derivs[nu] = base._spline.derivative(nu)
        return np.asarray(base._derivs[nu](np.asarray(s, dtype=float)), dtype=float)

    def _forward_deriv(self, s: np.ndarray) -> np.ndarray:
        return self._forward(s, 1)

    def __call__(self, t: Any, nu: int = 0) -> np.ndarray:
        """Points (nu = 0) or nu-th derivatives w.r.t. this curve's parameter, shape (len(t), 2)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if not self._flipped:
            return self._forward(t, nu).reshape(-1, 2)
        out = self._forward(self.t_end - t, nu).reshape(-1, 2)
        return -out if nu % 2 else out

    @property
    def start(self) -> np.ndarray:
        """First control point of this traversal."""
        return self.points[0]

    @property
    def end(self) -> np.ndarray:
        """Last control point of this traversal."""
        return self.points[-1]

    @property
    def is_reversed(self) -> bool:
        return self._flipped

    def reversed(self) -> "SplineCurve":
        """The same curve traversed backwards (t' = t_end - t), sharing the underlying spline."""
        if self._flipped:
            return self._base
        if self._reverse is None:
            r = object.__new__(SplineCurve)
            r.name = "-" + self.name
            r.points = self.points[::-1]
            r.degree = self.degree
            r.t_end = self.t_end
            r.params = (self.t_end - self.params)[::-1]
            r.breakpoints = (self.t_end - self.breakpoints)[::-1]
            r.breakpoints[0], r.breakpoints[-1] = 0.0, self.t_end
            r._spline = self._spline
            r._derivs = self._derivs
            r._flipped = True
            r._base = self
            r._reverse = self
            self._reverse = r
        return self._reverse

    def _forward_intervals(self) -> list[tuple[float, float]]:
        """Piece intervals in the FORWARD parameter of the base spline, in traversal order."""
        bp = self._base.breakpoints
        iv = list(zip(bp[:-1].tolist(), bp[1:].tolist()))
        if self._flipped:
            return [(b, a) for a, b in reversed(iv)]
        return iv

    def pieces(self) -> list[CurvePiece]:
        """Polynomial pieces for :func:`gauss_green_rule` (eq. 11), in traversal order.

        Each piece evaluates the underlying forward spline; a reversed curve gives the
        intervals descending (t0 > t1), so both neighbours of an interface use the very same
        spline at the same parameters.
        """
        return [CurvePiece(self._forward, self._forward_deriv, a, b, self.degree)
                for a, b in self._forward_intervals()]

    def sample(self, n_per_piece: int = 8) -> np.ndarray:
        """Points along the curve in traversal order, n_per_piece segments per polynomial
        piece, both end points included; a reversed curve returns exactly the same points
        as its forward curve, in reverse order."""
        n = max(1, int(n_per_piece))
        bp = self._base.breakpoints
        s = np.linspace(0.0, 1.0, n + 1)[:-1]
        ts = np.concatenate([(bp[:-1, None] + np.diff(bp)[:, None] * s[None, :]).ravel(),
                             [bp[-1]]])
        pts = self._forward(ts).reshape(-1, 2)
        pts[0], pts[-1] = self._base.points[0], self._base.points[-1]
        return pts[::-1].copy() if self._flipped else pts

    def __repr__(self) -> str:
        return (f"SplineCurve(name={self.name!r}, m={len(self.points)}, degree={self.degree}, "
                f"pieces={len(self.breakpoints) - 1})")


# --------------------------------------------------------------------------------------
# Geometry helpers (vectorised; candidate pairs by sorting, no N x M arrays)
# --------------------------------------------------------------------------------------
def _interval_hits(lo: np.ndarray, hi: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All pairs (k, i) with lo[k] <= v[i] <= hi[k], found by sorting v (no N x M arrays)."""
    order = np.argsort(v, kind="stable")
    vs = v[order]
    s = np.searchsorted(vs, lo, side="left")
    e = np.searchsorted(vs, hi, side="right")
    cnt = np.maximum(e - s, 0)
    total = int(cnt.sum())
    k = np.repeat(np.arange(lo.size), cnt)
    first = np.cumsum(cnt) - cnt
    pos = np.repeat(s, cnt) + (np.arange(total) - np.repeat(first, cnt))
    return k, order[pos]


def _points_in_polygon(P: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Crossing-number test of points P (N,2) against the closed polygon poly (M,2)."""
    a = poly
    b = np.roll(poly, -1, axis=0)
    k, i = _interval_hits(np.minimum(a[:, 1], b[:, 1]), np.maximum(a[:, 1], b[:, 1]), P[:, 1])
    ak, bk, pi = a[k], b[k], P[i]
    straddle = (ak[:, 1] > pi[:, 1]) != (bk[:, 1] > pi[:, 1])
    ak, bk, pi, i = ak[straddle], bk[straddle], pi[straddle], i[straddle]
    x = ak[:, 0] + (pi[:, 1] - ak[:, 1]) * (bk[:, 0] - ak[:, 0]) / (bk[:, 1] - ak[:, 1])
    crossings = np.bincount(i[pi[:, 0] < x], minlength=P.shape[0])
    return (crossings % 2) == 1


def _near_polyline(P: np.ndarray, poly: np.ndarray, dist: float) -> np.ndarray:
    """Mask of points P (N,2) within distance ``dist`` of the closed polyline poly (M,2)."""
    a = poly
    e = np.roll(poly, -1, axis=0) - a
    lo = np.minimum(a[:, 1], a[:, 1] + e[:, 1]) - dist
    hi = np.maximum(a[:, 1], a[:, 1] + e[:, 1]) + dist
    k, i = _interval_hits(lo, hi, P[:, 1])
    d = P[i] - a[k]
    ek = e[k]
    ee = np.maximum(np.einsum("ij,ij->i", ek, ek), np.finfo(float).tiny)
    s = np.clip(np.einsum("ij,ij->i", d, ek) / ee, 0.0, 1.0)
    r = d - s[:, None] * ek
    near = np.einsum("ij,ij->i", r, r) <= dist * dist
    out = np.zeros(P.shape[0], dtype=bool)
    out[i[near]] = True
    return out


def _first_self_intersection(poly: np.ndarray, tol: float) -> tuple[int, int] | None:
    """Indices (i, j) of two non-adjacent crossing or touching segments of a closed
    polyline (vectorised; candidate pairs from overlapping bounding boxes)."""
    a = poly
    b = np.roll(poly, -1, axis=0)
    M = a.shape[0]
    lo = np.minimum(a, b) - tol
    hi = np.maximum(a, b) + tol
    # pairs with overlapping z-ranges: lo_z of one segment inside the other's z-range
    ii, jj = _interval_hits(lo[:, 1], hi[:, 1], lo[:, 1])
    gap = (jj - ii) % M
    keep = (gap > 1) & (gap < M - 1)
    keep &= (lo[ii, 0] <= hi[jj, 0]) & (lo[jj, 0] <= hi[ii, 0])
    ii, jj = ii[keep], jj[keep]
    if ii.size == 0:
        return None

    def orient(p, q, r):
        return (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0])

    A, B, C, D = a[ii], b[ii], a[jj], b[jj]
    d1, d2 = orient(A, B, C), orient(A, B, D)
    d3, d4 = orient(C, D, A), orient(C, D, B)
    t1 = tol * np.linalg.norm(B - A, axis=1)
    t2 = tol * np.linalg.norm(D - C, axis=1)
    proper = (((d1 > t1) & (d2 < -t1)) | ((d1 < -t1) & (d2 > t1))) & \
             (((d3 > t2) & (d4 < -t2)) | ((d3 < -t2) & (d4 > t2)))

    def on_seg(p, q, r, o, t):
        # r (nearly) collinear with p-q and inside its box: an end point touching a segment
        return (np.abs(o) <= t) & np.all((np.minimum(p, q) - tol <= r) &
                                          (r <= np.maximum(p, q) + tol), axis=1)

    touch = on_seg(A, B, C, d1, t1) | on_seg(A, B, D, d2, t1) | \
        on_seg(C, D, A, d3, t2) | on_seg(C, D, B, d4, t2)
    hit = np.flatnonzero(proper | touch)
    if hit.size == 0:
        return None
    k = hit[0]
    return int(min(ii[k], jj[k])), int(max(ii[k], jj[k]))


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
                poly, sag = _loop_polyline(eff)
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
        return _inside_with_margin(P, poly, margin)

    def describe(self) -> str:
        """One line: kind, area [mm^2], centroid [mm], second moments [mm^4], point count."""
        return (f"{self.kind}: area {self.area * 1e6:.4g} mm^2, centroid "
                f"({self.centroid[0] * 1e3:.4g}, {self.centroid[1] * 1e3:.4g}) mm, "
                f"Syy {self.Syy * 1e12:.4g} Szz {self.Szz * 1e12:.4g} "
                f"Syz {self.Syz * 1e12:.4g} mm^4, {self.n_points} cubature points "
                f"(degree {self.degree})")

    def __repr__(self) -> str:
        return f"<Section {self.describe()}>"


def _inside_with_margin(P: np.ndarray, poly: np.ndarray, margin: float) -> np.ndarray:
    ins = _points_in_polygon(P, poly)
    if margin > 0.0 and ins.any():
        idx = np.flatnonzero(ins)
        ins[idx] = ~_near_polyline(P[idx], poly, margin)
    return ins


def _loop_polyline(eff: Sequence[SplineCurve]) -> tuple[np.ndarray, float]:
    """Fine closed polyline of a loop (about 32 segments per piece, capped) and twice the
    largest distance between a chord midpoint and the curve point at its mid-parameter."""
    n_pieces = sum(len(cv.breakpoints) - 1 for cv in eff)
    n = int(min(32, max(4, math.ceil(_MAX_SEGMENTS / max(1, n_pieces)))))
    parts, sag = [], 0.0
    for cv in eff:
        pts = cv.sample(n)
        if cv.degree > 1:
            bp = cv._base.breakpoints
            s = (np.arange(n) + 0.5) / n
            tm = (bp[:-1, None] + np.diff(bp)[:, None] * s[None, :]).ravel()
            mid = cv._forward(tm).reshape(-1, 2)
            fwd = pts[::-1] if cv.is_reversed else pts
            chord_mid = 0.5 * (fwd[:-1] + fwd[1:])
            sag = max(sag, float(np.linalg.norm(mid - chord_mid, axis=1).max()))
        parts.append(pts[:-1])
    return np.vstack(parts), 2.0 * sag


def _polyline_segment_owner(eff: Sequence[SplineCurve], n_total: int) -> list[str]:
    n_pieces = sum(len(cv.breakpoints) - 1 for cv in eff)
    n = int(min(32, max(4, math.ceil(_MAX_SEGMENTS / max(1, n_pieces)))))
    owner: list[str] = []
    for cv in eff:
        owner += [cv.name] * (n * (len(cv.breakpoints) - 1))
    return owner[:n_total]


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

    poly, sag = _loop_polyline(eff)
    hit = _first_self_intersection(poly, 1e-12 * size)
    if hit is not None:
        owner = _polyline_segment_owner(eff, poly.shape[0])
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
                                   lambda P: _inside_with_margin(P, poly, sag))
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


# --------------------------------------------------------------------------------------
# Config-style data
# --------------------------------------------------------------------------------------
def inline_loop(curves: Sequence[Mapping[str, Any]],
                spline_degree: int = DEFAULT_SPLINE_DEGREE) -> list[tuple[SplineCurve, bool]]:
    """Loop from config data ``[{name: str (optional), points: [[y, z], ...]}, ...]``.

    The curves are taken in order around a closed boundary; names default to ``curve<i>``
    (1-based).  Returns the list of (SplineCurve, False) for :func:`make_outline`.
    """
    if isinstance(curves, (str, bytes, Mapping)) or not isinstance(curves, Sequence):
        raise SectionError("the outline curves must be a list of {name, points} entries")
    if not curves:
        raise SectionError("the outline has no curves; give at least one {points: [...]} entry")
    out = []
    for i, entry in enumerate(curves, start=1):
        if not isinstance(entry, Mapping) or "points" not in entry:
            raise SectionError(f"outline curve {i} must be a mapping with a 'points' list of "
                               "[y, z] pairs")
        unknown = set(entry) - {"name", "points"}
        if unknown:
            raise SectionError(f"outline curve {i} has unknown keys {sorted(unknown)}; only "
                               "'name' and 'points' are allowed")
        name = str(entry.get("name", f"curve{i}"))
        out.append((SplineCurve(entry["points"], spline_degree, name), False))
    return out


@dataclass
class SectionsFile:
    """Contents of a sections file (e.g. configs/data/achilles_type3_sections.yaml).

    ``curves``: each named curve built once (in metres, tendon frame), shared by both
    neighbours; ``loops``: per sub-section a list of (SplineCurve, reversed_flag);
    ``twist_axis``: the triple point [m]; ``length_m``; ``c10_MPa`` per sub-section;
    ``scale`` in metres per pixel.
    """

    path: str
    scale: float
    curves: dict[str, SplineCurve]
    loops: dict[str, list[tuple[SplineCurve, bool]]]
    twist_axis: np.ndarray
    length_m: float
    c10_MPa: dict[str, float]
    spline_degree: int = DEFAULT_SPLINE_DEGREE
    notes: list[str] = field(default_factory=list)

    def section(self, name: str, degree: int = DEFAULT_CUBATURE_DEGREE,
                compress: bool = True) -> Section:
        """The outline section of loop ``name`` (see :func:`make_outline`)."""
        if name not in self.loops:
            raise SectionError(f"the sections file has no loop '{name}'; choose one of "
                               f"{sorted(self.loops)}")
        return make_outline(self.loops[name], degree=degree, compress=compress)


def _px_to_m(value: Any, scale: float, what: str) -> np.ndarray:
    try:
        P = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise SectionError(f"{what} must be a list of [px_x, px_y] pairs") from None
    if P.ndim == 1:
        P = P.reshape(1, -1)
    if P.ndim != 2 or P.shape[1] != 2 or not np.all(np.isfinite(P)):
        raise SectionError(f"{what} must be a list of finite [px_x, px_y] pairs")
    return np.column_stack([P[:, 0] * scale, -P[:, 1] * scale])


def _positive_number(value: Any, what: str) -> float:
    if isinstance(value, bool):
        value = None
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = float("nan")
    if not (np.isfinite(v) and v > 0):
        raise SectionError(f"{what} must be a positive number, got {value!r}")
    return v


def load_sections_file(path: str | Path,
                       spline_degree: int = DEFAULT_SPLINE_DEGREE) -> SectionsFile:
    """Load a sections file: pixel control points (y = px_x * scale, z = -px_y * scale),
    named ``curves``, loops under ``subtendons`` ('-name' = reversed), ``triple_point_px``,
    ``scale_m_per_px``, ``length_m``, ``c10_MPa``.  Each curve becomes ONE SplineCurve of
    degree ``spline_degree`` (Sec. 2.2) shared by every loop that uses it."""
    import yaml

    p = Path(path)
    try:
        text = p.read_text()
    except OSError as exc:
        raise SectionError(f"cannot read the sections file '{p}' ({exc.strerror}); "
                           "check the path") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise SectionError(f"the sections file '{p}' is not valid YAML ({exc}); "
                           "fix its syntax") from None
    if not isinstance(data, Mapping):
        raise SectionError(f"the sections file '{p}' must be a YAML mapping with the keys "
                           "scale_m_per_px, triple_point_px, curves, subtendons, c10_MPa, "
                           "length_m")
    required = ["scale_m_per_px", "triple_point_px", "curves", "subtendons", "c10_MPa",
                "length_m"]
    missing = [k for k in required if k not in data]
    if missing:
        raise SectionError(f"the sections file '{p}' lacks the key(s) {', '.join(missing)}; "
                           "add them (see configs/data/achilles_type3_sections.yaml)")
    scale = _positive_number(data["scale_m_per_px"], f"scale_m_per_px in '{p}'")
    length = _positive_number(data["length_m"], f"length_m in '{p}'")
    twist = _px_to_m(data["triple_point_px"], scale, f"triple_point_px in '{p}'")
    if twist.shape[0] != 1:
        raise SectionError(f"triple_point_px in '{p}' must be one [px_x, px_y] pair")

    raw_curves = data["curves"]
    if not isinstance(raw_curves, Mapping) or not raw_curves:
        raise SectionError(f"'curves' in '{p}' must be a non-empty mapping name -> list of "
                           "[px_x, px_y] points")
    curves: dict[str, SplineCurve] = {}
    for name, pts in raw_curves.items():
        name = str(name)
        if name.startswith("-"):
            raise SectionError(f"curve name '{name}' in '{p}' starts with '-', which marks "
                               "reversal in loops; rename the curve")
        P = _px_to_m(pts, scale, f"curve '{name}' in '{p}'")
        curves[name] = SplineCurve(P, spline_degree, name)

    raw_loops = data["subtendons"]
    if not isinstance(raw_loops, Mapping) or not raw_loops:
        raise SectionError(f"'subtendons' in '{p}' must be a non-empty mapping name -> list "
                           "of curve names")
    loops: dict[str, list[tuple[SplineCurve, bool]]] = {}
    for lname, refs in raw_loops.items():
        lname = str(lname)
        if isinstance(refs, (str, bytes)) or not isinstance(refs, Sequence) or not refs:
            raise SectionError(f"subtendon '{lname}' in '{p}' must list its boundary curves, "
                               "e.g. [a, -b, c]")
        loop = []
        for ref in refs:
            ref = str(ref).strip()
            flip = ref.startswith("-")
            key = ref[1:].strip() if flip else ref
            if key not in curves:
                raise SectionError(f"subtendon '{lname}' in '{p}' uses the unknown curve "
                                   f"'{key}'; define it under 'curves' (known: "
                                   f"{', '.join(sorted(curves))})")
            loop.append((curves[key], flip))
        loops[lname] = loop

    raw_c10 = data["c10_MPa"]
    if not isinstance(raw_c10, Mapping):
        raise SectionError(f"'c10_MPa' in '{p}' must map subtendon names to moduli in MPa")
    c10: dict[str, float] = {}
    for k, v in raw_c10.items():
        k = str(k)
        if k not in loops:
            raise SectionError(f"'c10_MPa' in '{p}' names the unknown subtendon '{k}'; use "
                               f"one of {', '.join(sorted(loops))}")
        c10[k] = _positive_number(v, f"c10_MPa.{k} in '{p}'")

    return SectionsFile(path=str(p), scale=scale, curves=curves, loops=loops,
                        twist_axis=twist[0], length_m=length, c10_MPa=c10,
                        spline_degree=int(spline_degree))
