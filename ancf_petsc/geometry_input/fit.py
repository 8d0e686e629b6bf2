"""Traced polylines → interpolating spline curves with few control points (paper Sec. 2.2).

A traced outline has one point per pixel or per click; the cubature of eq. (11) wants few spline
pieces.  :func:`fit_curve` keeps the Douglas-Peucker points of the trace (tolerance ``tol``), caps
the spacing between control points, builds the interpolating spline (cumulative chordal, as the
paper's) and inserts trace points where the spline strays farther than ``tol`` from the trace,
until it does not.  :func:`corners` finds the vertices where a curve must break (a polygon's
corners), so that the spline does not round them off.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..physics.spline import SplineCurve
from .polyline import PolylineDistance, arclength, douglas_peucker

__all__ = ["FittedCurve", "fit_curve", "corners"]

MAX_REFINEMENTS = 12
CHORD_FACTOR = 4.0
CORNER_DEG = 45.0
#: arc lengths closer than this (relative to the trace's) are one: a spacing target that falls on a
#: trace point within rounding takes it, whichever way the section is turned, and one midway between
#: two takes both
TIE = 1e-9


@dataclass
class FittedCurve:
    curve: SplineCurve
    deviation: float          # largest distance between the spline and the trace [m]


def corners(Q: np.ndarray, closed: bool, angle_deg: float = CORNER_DEG) -> np.ndarray:
    """Indices of vertices where the polyline turns by more than ``angle_deg`` (ends excluded
    for open polylines)."""
    if closed:
        a, b = Q - np.roll(Q, 1, axis=0), np.roll(Q, -1, axis=0) - Q
    else:
        a, b = (Q[1:-1] - Q[:-2]), (Q[2:] - Q[1:-1])
    na, nb = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
    ok = (na > 0) & (nb > 0)
    cos = np.ones(len(a))
    cos[ok] = np.einsum("ij,ij->i", a[ok], b[ok]) / (na[ok] * nb[ok])
    idx = np.flatnonzero(cos < np.cos(np.deg2rad(angle_deg)))
    return idx if closed else idx + 1


def _deviation(curve: SplineCurve, Q: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per span (control point j to j+1): largest distance trace→spline and spline→trace, and the
    trace index of the worst trace point of each span."""
    n_span = len(idx) - 1
    S = curve.sample(16)                                  # 16 segments per polynomial piece
    # spline parameter of every sample → span
    bp = curve.breakpoints
    s = np.linspace(0.0, 1.0, 17)[:-1]
    ts = np.r_[(bp[:-1, None] + np.diff(bp)[:, None] * s[None, :]).ravel(), bp[-1]]
    span_of_sample = np.clip(np.searchsorted(curve.params, ts, side="right") - 1, 0, n_span - 1)
    d_q, _, _ = PolylineDistance(S, closed=False).query(Q)
    d_s, _, _ = PolylineDistance(Q, closed=False).query(S)
    span_of_q = np.clip(np.searchsorted(idx, np.arange(len(Q)), side="right") - 1, 0, n_span - 1)
    worst = np.zeros(n_span)
    np.maximum.at(worst, span_of_q, d_q)
    np.maximum.at(worst, span_of_sample, d_s)
    arg = np.full(n_span, -1)
    order = np.lexsort((d_q, span_of_q))                 # last of each span = its largest d_q
    last = np.r_[span_of_q[order][1:] != span_of_q[order][:-1], True]
    arg[span_of_q[order][last]] = order[last]
    return worst, arg


def _local_means(Q: np.ndarray, s: np.ndarray, idx: np.ndarray, traced: np.ndarray) -> np.ndarray:
    """Control points: the trace points ``Q[idx]``, each interior one moved onto the local
    least-squares parabola of the traced points (``traced``: not those added between them) within
    half the distance to its neighbours (arc length ``s``) on either side (at least 5 of
    them, else it stays).

    Douglas-Peucker keeps the points farthest from the chords, which on a noisy trace are the
    noise peaks (on a convex outline mostly outwards: a spline through them gains area).  The
    local parabola n(t) = a + b t + c t² (t along the chord of the window, n across) removes that
    bias without the curvature bias of a plain mean (κ w²/6 for a half-window w): the point moves
    by a along the normal."""
    P = Q[idx].copy()
    if len(idx) <= 2:
        return P
    si = s[idx]
    w = 0.5 * np.minimum(si[1:-1] - si[:-2], si[2:] - si[1:-1])
    lo = np.searchsorted(s, si[1:-1] - w, side="left")
    hi = np.searchsorted(s, si[1:-1] + w, side="right")
    count = np.r_[0, np.cumsum(traced)]
    for k in np.flatnonzero(count[hi] - count[lo] >= 5):
        W = Q[lo[k]:hi[k]][traced[lo[k]:hi[k]]]
        T = W[-1] - W[0]
        T /= np.linalg.norm(T)
        d = W - P[k + 1]
        t, n = d @ T, d @ np.array([-T[1], T[0]])
        coef = np.linalg.lstsq(np.column_stack([np.ones_like(t), t, t * t]), n, rcond=None)[0]
        P[k + 1] += coef[0] * np.array([-T[1], T[0]])
    return P


def _nearest(s: np.ndarray, targets: np.ndarray, tie: float) -> np.ndarray:
    """Indices of the trace points nearest the arc lengths ``targets``, both where two are equally
    near (within ``tie``): the same points whichever way the trace runs (a mirrored section) and
    however it is turned (a target on a point within rounding takes it)."""
    hi = np.clip(np.searchsorted(s, targets), 1, len(s) - 1)
    lo = hi - 1
    d_lo, d_hi = targets - s[lo], s[hi] - targets
    return np.r_[lo[d_lo <= d_hi + tie], hi[d_hi <= d_lo + tie]]


def fit_curve(Q: np.ndarray, degree: int, tol: float, name: str,
              max_spacing: float | None = None, min_points: int = 2,
              traced: np.ndarray | None = None, periodic: bool = False) -> FittedCurve:
    """Interpolating spline through a few points of the open polyline ``Q`` (ends kept exactly),
    within ``tol`` of it (Hausdorff distance, sampled), control points at most ``max_spacing``
    apart along the trace and at least ``min_points`` of them; ``traced`` marks the points of
    Q that were traced (the others were added on the chords between them).  ``periodic``: Q is
    a whole closed outline without a corner (Q[-1] = Q[0]), fitted by the periodic spline, smooth
    where it closes (``SplineCurve``)."""
    Q = np.asarray(Q, dtype=float)
    traced = np.ones(len(Q), dtype=bool) if traced is None else np.asarray(traced, dtype=bool)
    s = arclength(Q)
    # a spline follows a smooth trace far closer than the chords Douglas-Peucker measures: start
    # coarse for splines (CHORD_FACTOR x tol) and let the refinement add points where needed
    idx = douglas_peucker(Q, tol * (CHORD_FACTOR if degree > 1 else 1.0))
    spacing = s[-1] / max(1, min_points - 1)
    if max_spacing is not None:
        spacing = min(spacing, max_spacing)
    extra = []
    for i, j in zip(idx[:-1], idx[1:]):
        k = int(np.ceil((s[j] - s[i]) / spacing - 1e-9))
        if k > 1:
            targets = s[i] + (s[j] - s[i]) * np.arange(1, k) / k
            extra.append(_nearest(s, targets, TIE * s[-1]))
    if extra:
        idx = np.unique(np.concatenate([idx] + extra))
    curve = SplineCurve(_local_means(Q, s, idx, traced), degree, name, periodic=periodic)
    worst = np.zeros(1)
    for _ in range(MAX_REFINEMENTS):
        worst, arg = _deviation(curve, Q, idx)
        bad = np.flatnonzero(worst > tol)
        if bad.size == 0:
            break
        new = []
        for j in bad:
            i0, i1 = idx[j], idx[j + 1]
            if i1 - i0 < 2:
                continue
            a = arg[j]
            new.append(a if i0 < a < i1 else (i0 + i1) // 2)
        if not new:
            break
        idx = np.unique(np.r_[idx, new])
        curve = SplineCurve(_local_means(Q, s, idx, traced), degree, name, periodic=periodic)
    else:
        worst, _ = _deviation(curve, Q, idx)
    return FittedCurve(curve, float(worst.max()))
