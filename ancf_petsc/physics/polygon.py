"""Polygon geometry for section checks: point in polygon, distance to a polyline, self-intersection."""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .spline import SplineCurve

_MAX_SEGMENTS = 4096          # cap on the fine polyline used for geometric checks


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


def points_in_polygon(P: np.ndarray, poly: np.ndarray) -> np.ndarray:
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


def near_polyline(P: np.ndarray, poly: np.ndarray, dist: float) -> np.ndarray:
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


def first_self_intersection(poly: np.ndarray, tol: float) -> tuple[int, int] | None:
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


def inside_with_margin(P: np.ndarray, poly: np.ndarray, margin: float) -> np.ndarray:
    ins = points_in_polygon(P, poly)
    if margin > 0.0 and ins.any():
        idx = np.flatnonzero(ins)
        ins[idx] = ~near_polyline(P[idx], poly, margin)
    return ins


def loop_polyline(eff: Sequence[SplineCurve]) -> tuple[np.ndarray, float]:
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


def segment_owner(eff: Sequence[SplineCurve], n_total: int) -> list[str]:
    n_pieces = sum(len(cv.breakpoints) - 1 for cv in eff)
    n = int(min(32, max(4, math.ceil(_MAX_SEGMENTS / max(1, n_pieces)))))
    owner: list[str] = []
    for cv in eff:
        owner += [cv.name] * (n * (len(cv.breakpoints) - 1))
    return owner[:n_total]
