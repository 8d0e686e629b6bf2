"""Quadrature / cubature rules for beam cross-sections (paper Sec. 2.2, eqs. 9-11).

Pure numpy: every rule returns ``(pts, w)`` with ``pts`` of shape ``(n, 2)`` holding
(y, z) coordinates and ``w`` of shape ``(n,)`` holding the weights, so that
``sum(w * f(pts[:, 0], pts[:, 1]))`` approximates the integral of ``f`` over the domain.

* :func:`gauss_legendre` - 1D Gauss-Legendre nodes on [-1, 1].
* :func:`rectangle_rule` - tensor Gauss rule of eq. (9).
* :func:`ellipse_rule` - polar rule for ellipses / circles.
* :func:`gauss_green_rule` - the Gauss-Green cubature of eq. (11) over a domain bounded
  by polynomial curve pieces (eq. 10 and the spline construction of Sec. 2.2).
* :func:`compress_rule` - Tchakaloff / Caratheodory compression of any rule to at most
  (d+1)(d+2)/2 positive weights on nodes inside the domain.
"""
from __future__ import annotations

import math
from functools import lru_cache
from typing import Callable, NamedTuple, Sequence

import numpy as np
from numpy.polynomial import legendre as _leg

from .nnls import nnls

__all__ = [
    "CurvePiece",
    "CompressionError",
    "gauss_legendre",
    "rectangle_rule",
    "ellipse_rule",
    "gauss_green_rule",
    "compress_rule",
    "legendre_moment_basis",
]

CurveFn = Callable[[np.ndarray], np.ndarray]


class CurvePiece(NamedTuple):
    """One polynomial piece of a boundary curve for :func:`gauss_green_rule`.

    ``curve(t)`` and ``deriv(t)`` map parameters of shape ``(k,)`` to points / tangent
    vectors of shape ``(k, 2)``.  On the parameter interval between ``t0`` and ``t1`` the
    curve must be ONE polynomial of degree ``degree`` (a spline piece between two
    consecutive knots).  ``t1 < t0`` is allowed and traverses the piece backwards.
    """

    curve: CurveFn
    deriv: CurveFn
    t0: float
    t1: float
    degree: int


class CompressionError(ArithmeticError):
    """Raised by :func:`compress_rule` when the moments cannot be reproduced."""


@lru_cache(maxsize=128)
def _gl_cached(n: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = _leg.leggauss(n)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


def gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [-1, 1], exact for degree 2n-1 (eq. 9)."""
    n = int(n)
    if n < 1:
        raise ValueError(f"a Gauss-Legendre rule needs at least one point, got n={n}")
    x, w = _gl_cached(n)
    return x.copy(), w.copy()


def _n_for_degree(degree: int) -> int:
    """Smallest n with 2n-1 >= degree (at least 1)."""
    degree = int(degree)
    if degree < 0:
        raise ValueError(f"the polynomial degree of exactness must be >= 0, got {degree}")
    return max(1, math.ceil((degree + 1) / 2))


def rectangle_rule(width: float, height: float, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Tensor Gauss rule (eq. 9) on the rectangle [-width/2, width/2] x [-height/2, height/2].

    Exact for every polynomial of total degree ``degree`` (n = ceil((degree+1)/2) points
    per direction).
    """
    if not (width > 0 and height > 0):
        raise ValueError(f"rectangle sides must be positive, got {width} x {height}")
    n = _n_for_degree(degree)
    x, w = gauss_legendre(n)
    Y, Z = np.meshgrid(0.5 * width * x, 0.5 * height * x, indexing="ij")
    W = np.outer(0.5 * width * w, 0.5 * height * w)
    return np.column_stack([Y.ravel(), Z.ravel()]), W.ravel()


def ellipse_rule(a: float, b: float, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Polar rule on the ellipse (y/a)^2 + (z/b)^2 <= 1, exact for total degree ``degree``.

    y = a r cos(theta), z = b r sin(theta), dA = a b r dr dtheta.  A polynomial of degree d
    becomes a trigonometric polynomial of degree d in theta, integrated exactly by the
    trapezoid rule with d+1 equally spaced angles, times r^k with k <= d; with the Jacobian
    r the radial integrand has degree d+1, integrated by ceil((d+2)/2) Gauss points on [0, 1].
    All weights are positive and all points interior.
    """
    if not (a > 0 and b > 0):
        raise ValueError(f"ellipse semi-axes must be positive, got {a}, {b}")
    d = int(degree)
    if d < 0:
        raise ValueError(f"the polynomial degree of exactness must be >= 0, got {d}")
    m = d + 1
    nr = max(1, math.ceil((d + 2) / 2))
    xr, wr = gauss_legendre(nr)
    r = 0.5 * (xr + 1.0)
    wr = 0.5 * wr * r                       # includes the Jacobian r
    theta = 2.0 * np.pi * (np.arange(m) + 0.5) / m
    R, T = np.meshgrid(r, theta, indexing="ij")
    pts = np.column_stack([(a * R * np.cos(T)).ravel(), (b * R * np.sin(T)).ravel()])
    w = np.outer(wr, np.full(m, 2.0 * np.pi / m)).ravel() * (a * b)
    return pts, w


def _boundary_nodes_count(n: int, p: int) -> int:
    """n_i of eq. (11): n p + p/2 for even p, n p + (p+1)/2 for odd p."""
    return n * p + (p // 2 if p % 2 == 0 else (p + 1) // 2)


def gauss_green_rule(pieces: Sequence[CurvePiece | tuple], degree: int,
                     xi_line: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Green cubature of eq. (11) over a domain bounded by polynomial curve pieces.

    ``pieces`` form a closed loop (eq. 10), each a :class:`CurvePiece` or a tuple
    ``(curve, deriv, t0, t1, p)``; a counter-clockwise loop gives positive weights sum
    (= area), a clockwise one the negative.  With n = ceil((degree+1)/2) and, on a piece of
    degree p, n_i = n p + p/2 (p even) or n p + (p+1)/2 (p odd) Gauss points (tau_k, w_k)
    along the piece and n points (tau_h, w_h) along each horizontal segment from the line
    y = Xi to the boundary, the nodes and weights are (paper: eta = y, zeta = z)

        q_k   = dt/2 tau_k + (t0 + t1)/2,                dt = t1 - t0
        y_kh  = (S1(q_k) - Xi)/2 tau_h + (S1(q_k) + Xi)/2
        z_kh  = S2(q_k)
        w_kh  = dt/4 w_k w_h (S1(q_k) - Xi) S2'(q_k),

    exact for every polynomial of total degree ``degree`` when each piece is a polynomial
    of its stated degree.  Xi (``xi_line``) defaults to the midpoint of the y-range of the
    boundary.  Nodes may lie outside non-convex domains and weights may be negative; use
    :func:`compress_rule` to obtain a positive interior rule.  Nodes with exactly zero
    weight (horizontal pieces, points on the line Xi) are dropped.
    """
    pcs = [p if isinstance(p, CurvePiece) else CurvePiece(*p) for p in pieces]
    if not pcs:
        raise ValueError("gauss_green_rule needs at least one boundary piece")
    n = _n_for_degree(degree)
    tau_h, w_h = gauss_legendre(n)

    samples = []
    for pc in pcs:
        p = int(pc.degree)
        if p < 1:
            raise ValueError(f"boundary pieces must have polynomial degree >= 1, got {p}")
        ni = _boundary_nodes_count(n, p)
        tau_k, w_k = gauss_legendre(ni)
        t0, t1 = float(pc.t0), float(pc.t1)
        dt = t1 - t0
        q = 0.5 * dt * tau_k + 0.5 * (t0 + t1)
        S = np.asarray(pc.curve(q), dtype=float).reshape(ni, 2)
        dS = np.asarray(pc.deriv(q), dtype=float).reshape(ni, 2)
        ends = np.asarray(pc.curve(np.array([t0, t1])), dtype=float).reshape(2, 2)
        samples.append((dt, w_k, S, dS, ends))

    if xi_line is None:
        ys = np.concatenate([np.r_[s[2][:, 0], s[4][:, 0]] for s in samples])
        xi = 0.5 * (ys.min() + ys.max())
    else:
        xi = float(xi_line)

    all_pts, all_w = [], []
    for dt, w_k, S, dS, _ in samples:
        s1 = S[:, 0][:, None]                                        # (ni, 1)
        y = 0.5 * (s1 - xi) * tau_h[None, :] + 0.5 * (s1 + xi)       # (ni, n)
        z = np.broadcast_to(S[:, 1][:, None], y.shape)
        w = 0.25 * dt * (w_k * (S[:, 0] - xi) * dS[:, 1])[:, None] * w_h[None, :]
        all_pts.append(np.column_stack([y.ravel(), z.ravel()]))
        all_w.append(w.ravel())
    pts = np.concatenate(all_pts)
    w = np.concatenate(all_w)
    keep = w != 0.0
    return pts[keep], w[keep]


def legendre_moment_basis(pts: np.ndarray, degree: int, center: np.ndarray,
                          half: np.ndarray) -> np.ndarray:
    """Tensor Legendre basis P_i(u) P_j(v), i + j <= degree, u = (y - c_y)/h_y, v likewise.

    Returns the Vandermonde-like matrix of shape ``(len(pts), (d+1)(d+2)/2)``.
    """
    P = np.asarray(pts, dtype=float).reshape(-1, 2)
    u = (P - center) / half
    Ly = _leg.legvander(u[:, 0], degree)
    Lz = _leg.legvander(u[:, 1], degree)
    ii, jj = zip(*[(i, j) for k in range(degree + 1) for i in range(k + 1) for j in [k - i]])
    return Ly[:, list(ii)] * Lz[:, list(jj)]


def compress_rule(pts: np.ndarray, w: np.ndarray, degree: int,
                  inside: Callable[[np.ndarray], np.ndarray],
                  rtol: float = 1e-12) -> tuple[np.ndarray, np.ndarray]:
    """Tchakaloff / Caratheodory compression of a cubature rule (e.g. eq. 11).

    The moments of (``pts``, ``w``) are computed in the tensor Legendre basis of total degree
    ``degree`` scaled to the bounding box of ``pts``; nonnegative weights reproducing them are
    sought with ``scipy.optimize.nnls`` (``nnls.nnls``) on candidate nodes inside the domain (``inside(P)``
    returns a boolean mask): first the rule's own inside nodes, then increasingly fine
    inside tensor grids.  The Lawson-Hanson solution has at most (d+1)(d+2)/2 nonzero
    weights; the weights on that support are then refined by least squares.  Every moment
    must be reproduced to ``rtol`` times the area, else :class:`CompressionError` is raised.

    Returns ``(pts_c, w_c)``: all points inside, all weights > 0.
    """
    P = np.asarray(pts, dtype=float).reshape(-1, 2)
    W = np.asarray(w, dtype=float).ravel()
    if P.shape[0] != W.shape[0]:
        raise ValueError("pts and w have different lengths")
    d = int(degree)
    if d < 0:
        raise ValueError(f"the polynomial degree of exactness must be >= 0, got {d}")
    area = float(W.sum())
    if not area > 0.0:
        raise CompressionError(f"the rule has non-positive total weight {area:g}; "
                               "the domain must be counter-clockwise and non-degenerate")
    lo, hi = P.min(axis=0), P.max(axis=0)
    center = 0.5 * (lo + hi)
    half = 0.5 * (hi - lo)
    half = np.where(half > 0, half, 1.0)

    def basis(X: np.ndarray) -> np.ndarray:
        return legendre_moment_basis(X, d, center, half)

    mom = basis(P).T @ W
    tol = rtol * area
    n_mom = mom.size

    def mask_of(X: np.ndarray) -> np.ndarray:
        m = np.asarray(inside(X), dtype=bool).ravel()
        if m.shape[0] != X.shape[0]:
            raise ValueError("inside() must return one boolean per point")
        return m

    cand = P[mask_of(P)]
    best_err = np.inf
    for level in range(5):
        if level > 0:
            g = (d + 2) * (2 ** level)
            s = (np.arange(g) + 0.5) / g * 2.0 - 1.0
            GY, GZ = np.meshgrid(center[0] + half[0] * s, center[1] + half[1] * s,
                                 indexing="ij")
            G = np.column_stack([GY.ravel(), GZ.ravel()])
            cand = np.unique(np.vstack([cand, G[mask_of(G)]]), axis=0)
        if cand.shape[0] < 1:
            continue
        A = basis(cand).T                                  # (n_mom, n_cand)
        x, _ = nnls(A, mom, maxiter=max(50 * n_mom, 3 * A.shape[1]))
        supp = np.flatnonzero(x > 0.0)
        if supp.size == 0:
            continue
        wc = x[supp]
        # Least-squares refinement on the support (columns are independent by construction).
        ref, *_ = np.linalg.lstsq(A[:, supp], mom, rcond=None)
        if np.all(ref > 0.0):
            err_ref = np.abs(A[:, supp] @ ref - mom).max()
            err_nnls = np.abs(A[:, supp] @ wc - mom).max()
            if err_ref <= err_nnls:
                wc = ref
        err = np.abs(A[:, supp] @ wc - mom).max()
        best_err = min(best_err, err)
        if err <= tol and supp.size <= n_mom and np.all(wc > 0.0):
            return cand[supp].copy(), wc.copy()
    raise CompressionError(
        f"could not reproduce the degree-{d} moments with positive interior weights "
        f"(best max moment error {best_err / area:.3g} of the area, tolerance {rtol:g})")
