"""Closed and open polylines in the (y, z) section plane: the raw material of traced outlines.

Pure numpy/scipy, vectorised over points (no loop per point).  A closed polyline is an (n, 2)
array whose closing segment from the last point back to the first is implied (the first point is
not repeated).  Areas and centroids are the shoelace formulas; distances to a polyline are exact
point-to-segment distances, with candidate segments from a k-d tree of its vertices.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..physics.polygon import first_self_intersection, points_in_polygon

__all__ = ["signed_area", "centroid", "perimeter", "drop_duplicates", "canonical_start", "densify",
           "resample", "smooth", "PolylineDistance", "douglas_peucker", "self_intersection", "inside"]


def signed_area(P: np.ndarray) -> float:
    """Shoelace area of a closed polyline: positive when counter-clockwise."""
    y, z = P[:, 0], P[:, 1]
    return 0.5 * float(np.sum(y * np.roll(z, -1) - np.roll(y, -1) * z))


def centroid(P: np.ndarray) -> np.ndarray:
    """Area centroid of the polygon bounded by a closed polyline."""
    y, z = P[:, 0], P[:, 1]
    y1, z1 = np.roll(y, -1), np.roll(z, -1)
    cr = y * z1 - y1 * z
    a = 0.5 * cr.sum()
    return np.array([np.sum((y + y1) * cr), np.sum((z + z1) * cr)]) / (6.0 * a)


def perimeter(P: np.ndarray, closed: bool = True) -> float:
    Q = np.vstack([P, P[:1]]) if closed else P
    return float(np.linalg.norm(np.diff(Q, axis=0), axis=1).sum())


def smallest_width(P: np.ndarray) -> float:
    """The least distance between two parallel lines enclosing the polyline (on a hull edge)."""
    from scipy.spatial import ConvexHull
    hull = P[ConvexHull(P).vertices]
    edge = np.roll(hull, -1, axis=0) - hull
    normal = np.column_stack([edge[:, 1], -edge[:, 0]]) / np.linalg.norm(edge, axis=1)[:, None]
    heights = hull @ normal.T
    return float((heights.max(axis=0) - heights.min(axis=0)).min())


def drop_duplicates(P: np.ndarray, tol: float, closed: bool = True) -> np.ndarray:
    """Remove points closer than ``tol`` to their predecessor (and a repeated closing point)."""
    P = np.asarray(P, dtype=float)
    keep = np.r_[True, np.linalg.norm(np.diff(P, axis=0), axis=1) > tol]
    P = P[keep]
    if closed and len(P) > 1 and np.linalg.norm(P[-1] - P[0]) <= tol:
        P = P[:-1]
    return P


def canonical_start(P: np.ndarray) -> np.ndarray:
    """The closed polyline P started at its vertex farthest from its area centroid: where the
    tracing started (a mask's scan order, a click) then changes nothing that is built from it."""
    d = np.linalg.norm(P - centroid(P)[None, :], axis=1)
    return np.roll(P, -int(np.argmax(d)), axis=0)


def densify(P: np.ndarray, h: float, closed: bool = True,
            vertices: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Subdivide every segment into pieces no longer than ``h``; the vertices are kept (with
    ``vertices``, also a mask of which output points are the input's vertices)."""
    Q = np.vstack([P, P[:1]]) if closed else P
    seg = np.diff(Q, axis=0)
    n = np.maximum(1, np.ceil(np.linalg.norm(seg, axis=1) / h).astype(int))
    k = np.repeat(np.arange(len(seg)), n)
    first = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
    out = Q[k] + (first / np.repeat(n, n))[:, None] * seg[k]
    is_vertex = first == 0
    if not closed:
        out, is_vertex = np.vstack([out, Q[-1:]]), np.r_[is_vertex, True]
    return (out, is_vertex) if vertices else out


def arclength(Q: np.ndarray) -> np.ndarray:
    return np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(Q, axis=0), axis=1))]


def resample(P: np.ndarray, n: int, closed: bool = True) -> np.ndarray:
    """``n`` points equally spaced in arc length, starting at P[0] (and ending at P[-1] if open)."""
    Q = np.vstack([P, P[:1]]) if closed else P
    s = arclength(Q)
    t = np.linspace(0.0, s[-1], n + 1 if closed else n)
    t = t[:-1] if closed else t
    return np.column_stack([np.interp(t, s, Q[:, 0]), np.interp(t, s, Q[:, 1])])


def smooth(P: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing of a closed polyline along its arc length (standard deviation ``sigma``),
    compensated for shrinkage.

    A Gaussian alone pulls a curve of curvature κ inwards by about σ²κ/2 (a disc of radius R loses
    σ²/R² of its area).  With g(f) = exp(-2π²σ²f²) the Gaussian's transfer function, the filter
    g (2 - g) (smooth, then add back what a second smoothing would remove) keeps the low
    frequencies to O(σ⁴) and still damps the pixel staircase and tracing noise.  The outline is
    resampled at spacing ≤ sigma/3 (at least 64 points) and filtered periodically (FFT).
    Returns the smoothed, uniformly spaced closed polyline."""
    L = perimeter(P)
    n = int(max(64, np.ceil(3.0 * L / sigma)))
    n = min(n, 1 << 16)
    U = resample(P, n)
    h = L / n
    f = np.fft.rfftfreq(n, d=h)
    g = np.exp(-2.0 * (np.pi * f * sigma) ** 2)
    kernel = g * (2.0 - g)
    return np.fft.irfft(np.fft.rfft(U, axis=0) * kernel[:, None], n=n, axis=0)


class PolylineDistance:
    """Exact distances from points to a polyline (closed by default), its nearest segment and
    the closest point on it.  Candidates: the segments at the k nearest vertices."""

    def __init__(self, P: np.ndarray, closed: bool = True) -> None:
        self.P = np.asarray(P, dtype=float)
        self.closed = closed
        self.A = self.P if closed else self.P[:-1]
        self.E = (np.roll(self.P, -1, axis=0) - self.P) if closed else np.diff(self.P, axis=0)
        self.tree = cKDTree(self.P)

    def query(self, Q: np.ndarray, k: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(distance (m,), segment index (m,), closest point (m, 2)) for points Q (m, 2)."""
        Q = np.asarray(Q, dtype=float).reshape(-1, 2)
        k = min(k, len(self.P))
        _, idx = self.tree.query(Q, k=k)
        idx = idx.reshape(len(Q), k)
        nseg = len(self.A)
        cand = np.concatenate([idx, idx - 1], axis=1)
        cand = cand % nseg if self.closed else np.clip(cand, 0, nseg - 1)
        a, e = self.A[cand], self.E[cand]                       # (m, 2k, 2)
        ee = np.maximum(np.einsum("mki,mki->mk", e, e), np.finfo(float).tiny)
        s = np.clip(np.einsum("mki,mki->mk", Q[:, None, :] - a, e) / ee, 0.0, 1.0)
        foot = a + s[..., None] * e
        d = np.linalg.norm(Q[:, None, :] - foot, axis=2)
        j = np.argmin(d, axis=1)
        rows = np.arange(len(Q))
        return d[rows, j], cand[rows, j], foot[rows, j]


def douglas_peucker(P: np.ndarray, eps: float) -> np.ndarray:
    """Indices of the Douglas-Peucker simplification of an open polyline (ends always kept)."""
    n = len(P)
    keep = np.zeros(n, dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    while stack:
        i, j = stack.pop()
        if j <= i + 1:
            continue
        a, b = P[i], P[j]
        e = b - a
        ee = float(e @ e)
        Q = P[i + 1:j] - a
        if ee == 0.0:
            d = np.linalg.norm(Q, axis=1)
        else:
            d = np.abs(Q[:, 0] * e[1] - Q[:, 1] * e[0]) / np.sqrt(ee)
        k = int(np.argmax(d))
        if d[k] > eps:
            m = i + 1 + k
            keep[m] = True
            stack += [(i, m), (m, j)]
    return np.flatnonzero(keep)


def _to_segment(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance from q to the segment ab."""
    e = b - a
    s = float(np.clip((q - a) @ e / max(float(e @ e), np.finfo(float).tiny), 0.0, 1.0))
    return float(np.linalg.norm(q - a - s * e))


def self_intersection(P: np.ndarray, tol: float) -> np.ndarray | None:
    """A point where the closed polyline crosses or touches itself, or None."""
    hit = first_self_intersection(P, tol)
    if hit is None:
        return None
    a, b = P[hit[0]], P[(hit[0] + 1) % len(P)]
    c, d = P[hit[1]], P[(hit[1] + 1) % len(P)]
    M = np.column_stack([b - a, c - d])
    if abs(np.linalg.det(M)) <= 1e-300:     # parallel, touching: the end nearest the other segment
        ends = [(q, c, d) for q in (a, b)] + [(q, a, b) for q in (c, d)]   # (not c: a segment away)
        return min(ends, key=lambda e: _to_segment(*e))[0]
    s = np.linalg.solve(M, c - a)[0]
    return a + np.clip(s, 0.0, 1.0) * (b - a)


def inside(Q: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Points Q strictly inside the closed polyline P (crossing number)."""
    return points_in_polygon(np.asarray(Q, dtype=float).reshape(-1, 2), P)
