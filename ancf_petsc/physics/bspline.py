"""Interpolating B-splines (paper Sec. 2.2) in numpy: ``scipy.interpolate``'s arithmetic, not its import.

``interpolating_spline`` builds the knots and coefficients ``scipy.interpolate.make_interp_spline``
builds (not-a-knot; the same collocation rows and LAPACK ``gbsv``), and ``BSpline`` evaluates them
with the same de Boor–Cox recursion and summation order as scipy's ``BSpline`` (its derivatives on
the coefficients of ``splder``), vectorised over the points: the values are scipy's to the last
bit (tests/physics/test_bspline.py).  Importing ``scipy.interpolate`` imports ``scipy.optimize``
too, ~0.1 s of every run's start-up; evaluating one here costs a few numpy calls, not a Python
loop per curve call.
"""
from __future__ import annotations

import numpy as np


def _basis(t: np.ndarray, k: int, x: np.ndarray, ell: np.ndarray) -> list[np.ndarray]:
    """The k + 1 B-splines non-zero on [t_ell, t_ell+1), at x: scipy's ``_deBoor_D`` (m = 0),
    operation for operation, over all points at once."""
    h = [np.ones_like(x)] + [np.zeros_like(x) for _ in range(k)]
    with np.errstate(divide="ignore", invalid="ignore"):
        for j in range(1, k + 1):
            hh = h[:j]
            h = [np.zeros_like(x)] + h[1:]
            for n in range(1, j + 1):
                xb, xa = t[ell + n], t[ell + n - j]
                same = xb == xa
                w = hh[n - 1] / (xb - xa)
                h[n - 1] = np.where(same, h[n - 1], h[n - 1] + w * (xb - x))
                h[n] = np.where(same, 0.0, w * (x - xa))
    return h


class BSpline:
    """S(x) = Σ c_j B_j(x) of degree k on knots t, extrapolated beyond them (as scipy's)."""

    def __init__(self, t: np.ndarray, c: np.ndarray, k: int):
        self.t, self.c, self.k = np.asarray(t, dtype=float), np.asarray(c, dtype=float), int(k)

    def interval(self, x: np.ndarray) -> np.ndarray:
        """ℓ with t_ℓ <= x < t_ℓ+1, kept within [k, n − 1] (scipy's ``find_interval``)."""
        n = len(self.t) - self.k - 1
        ell = np.searchsorted(self.t, x, side="right") - 1
        return np.minimum(np.maximum(ell, self.k), n - 1)

    def __call__(self, x) -> np.ndarray:
        """S(x), shape x.shape + c.shape[1:] (NaN where x is NaN); derivatives: ``derivative``."""
        x = np.asarray(x, dtype=float)
        shape = x.shape
        x = x.reshape(-1)
        nan = np.isnan(x)
        ell = self.interval(np.where(nan, self.t[self.k], x))
        h = _basis(self.t, self.k, x, ell)
        c = self.c.reshape(len(self.c), -1)
        out = np.zeros((len(x), c.shape[1]))
        for a in range(self.k + 1):
            out = out + c[ell + a - self.k] * h[a][:, None]
        out[nan] = np.nan
        return out.reshape(shape + self.c.shape[1:])

    def derivative(self, nu: int = 1) -> "BSpline":
        """The nu-th derivative as a spline of degree k − nu (scipy's ``splder`` coefficients)."""
        t, c, k = self.t, self.c, self.k
        ct = len(t) - len(c)
        if ct > 0:
            c = np.r_[c, np.zeros((ct,) + c.shape[1:])]
        sh = (slice(None),) + (None,) * len(c.shape[1:])
        for _ in range(nu):
            dt = t[k + 1:-1] - t[1:-k - 1]
            c = (c[1:-1 - k] - c[:-2 - k]) * k / dt[sh]
            c = np.r_[c, np.zeros((k,) + c.shape[1:])]
            t = t[1:-1]
            k -= 1
        return BSpline(t, c, k)


def interpolating_spline(x: np.ndarray, y: np.ndarray, k: int) -> BSpline:
    """The spline of degree k through (x_i, y_i) with not-a-knot ends (``make_interp_spline``'s
    knots, collocation rows and banded LU solve); x strictly increasing, y (len(x), d)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if k == 1:
        return BSpline(np.r_[x[0], x, x[-1]], y.copy(), 1)
    if k == 2:
        m = (x[1:] + x[:-1]) / 2.0
        t = np.r_[(x[0],) * 3, m[1:-1], (x[-1],) * 3]
    elif k % 2 == 1:
        m = (k - 1) // 2
        t = np.r_[(x[0],) * (k + 1), x[m + 1:-m - 1], (x[-1],) * (k + 1)]
    else:
        raise ValueError(f"Odd degree for now only. Got {k}.")
    from scipy.linalg import lapack     # scipy.sparse imports it anyway; not scipy.interpolate

    nt = len(t) - k - 1
    spline = BSpline(t, np.zeros(0), k)
    ell = spline.interval(x)
    rows = _basis(t, k, x, ell)
    ab = np.zeros((3 * k + 1, nt), order="F")
    j = np.arange(len(x))
    for a in range(k + 1):
        clmn = ell - k + a
        ab[2 * k + j - clmn, clmn] = rows[a]
    rhs = y.reshape(len(x), -1).copy()
    _, _, c, info = lapack.dgbsv(k, k, ab, rhs, overwrite_ab=True, overwrite_b=True)
    if info > 0:
        raise np.linalg.LinAlgError("Collocation matrix is singular.")
    return BSpline(t, np.ascontiguousarray(c.reshape((nt,) + y.shape[1:])), k)
