"""Interpolating B-splines (paper Sec. 2.2) in numpy: ``scipy.interpolate``'s arithmetic, not its import.

``interpolating_spline`` builds the knots and coefficients ``scipy.interpolate.make_interp_spline``
builds (not-a-knot; the same collocation rows and LAPACK ``gbsv``), and ``BSpline`` evaluates them
with the same de Boor–Cox recursion and summation order as scipy's ``BSpline`` (its derivatives on
the coefficients of ``splder``), vectorised over the points: the values are scipy's to the last
bit (tests/physics/test_bspline.py).  Importing ``scipy.interpolate`` imports ``scipy.optimize``
too, ~0.1 s of every run's start-up.  One spline is evaluated by scipy's compiled routine itself
(``_bspl.evaluate_spline``, what ``scipy.interpolate.BSpline`` calls), loaded by its path without
the package (``compiled``); ``SplineSet`` evaluates many splines in one vectorised recursion.
"""
from __future__ import annotations

import functools

import numpy as np

from . import scipy_extension


@functools.lru_cache(maxsize=1)
def compiled():
    """scipy's compiled B-spline module ``scipy.interpolate._bspl`` (not through
    ``scipy.interpolate``), or None where there is none (then numpy evaluates)."""
    return scipy_extension.load("interpolate", "_bspl", "evaluate_spline")


def _basis(t: np.ndarray, k: np.ndarray | int, x: np.ndarray, ell: np.ndarray) -> np.ndarray:
    """The k + 1 B-splines non-zero on [t_ell, t_ell+1) at x, (max k + 1, len(x)): scipy's
    ``_deBoor_D`` (m = 0) operation for operation, one level of the recursion at a time over all
    points and all j of the level.  ``k`` may differ per point (several splines' knots in one
    ``t``): a point's rows past its own k stay as its recursion left them (zero)."""
    k = np.broadcast_to(k, x.shape)
    top = int(k.max(initial=0))
    h = np.zeros((top + 1, len(x)))
    h[0] = 1.0
    last = len(t) - 1
    with np.errstate(divide="ignore", invalid="ignore"):
        for j in range(1, top + 1):
            idx = np.minimum(ell + np.arange(1, j + 1)[:, None], last)     # (j, points)
            xb, xa = t[idx], t[np.maximum(idx - j, 0)]
            same = xb == xa
            w = h[:j] / (xb - xa)
            new = np.empty((j + 1, len(x)))
            new[0] = 0.0
            new[1:] = np.where(same, 0.0, w * (x - xa))                  # h[n] = w (x − x_a)
            new[:j] = np.where(same, new[:j], new[:j] + w * (xb - x))    # h[n−1] += w (x_b − x)
            h[:j + 1] = np.where(k >= j, new, h[:j + 1])
    return h


def _combine(c: np.ndarray, k: np.ndarray | int, ell: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Σ_a c[ell − k + a] h_a (points, d), summed from a = 0 up as scipy does."""
    k = np.broadcast_to(k, ell.shape)
    out = np.zeros((len(ell), c.shape[1]))
    for a in range(h.shape[0]):
        term = out + c[np.minimum(np.maximum(ell - k + a, 0), len(c) - 1)] * h[a][:, None]
        out = np.where((a <= k)[:, None], term, out)
    return out


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
        c = self.c.reshape(len(self.c), -1)
        fast = compiled()
        if fast is not None:                   # scipy's own loop over the points
            out = np.empty((len(x), c.shape[1]))
            fast.evaluate_spline(self.t, np.ascontiguousarray(c), self.k, np.ascontiguousarray(x), 0, True, out)
            return out.reshape(shape + self.c.shape[1:])
        nan = np.isnan(x)
        ell = self.interval(np.where(nan, self.t[self.k], x))
        out = _combine(c, self.k, ell, _basis(self.t, self.k, x, ell))
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
    ab = np.zeros((3 * k + 1, nt), order="F")
    j = np.arange(len(x))
    rows = _basis(t, k, x, ell)
    for a in range(k + 1):
        clmn = ell - k + a
        ab[2 * k + j - clmn, clmn] = rows[a]
    rhs = y.reshape(len(x), -1).copy()
    _, _, c, info = lapack.dgbsv(k, k, ab, rhs, overwrite_ab=True, overwrite_b=True)
    if info > 0:
        raise np.linalg.LinAlgError("Collocation matrix is singular.")
    return BSpline(t, np.ascontiguousarray(c.reshape((nt,) + y.shape[1:])), k)


def periodic_spline(x: np.ndarray, y: np.ndarray, k: int) -> BSpline:
    """The periodic spline of degree k through (x_i, y_i), y[-1] = y[0]: a closed curve smooth
    (C^(k-1)) at its first point too; x strictly increasing.  Knots: odd k at the x_i (scipy's
    ``make_interp_spline(..., bc_type="periodic")``), even k at the midpoints all round (scipy's
    leave x_0 a knot, and the curve then depends on the way round: 11 um at 8 points on an
    ellipse); solved densely, the first coefficients repeating one period on."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    m, period = len(x) - 1, x[-1] - x[0]                # distinct points, parameter period
    if k % 2:
        dx = np.diff(x)
        t = np.zeros(len(x) + 2 * k)
        t[k:-k] = x
        for i in range(k):
            t[k - i - 1] = t[k - i] - dx[-(i % m) - 1]
            t[-k + i] = t[-k + i - 1] + dx[i % m]
    else:
        mids = (x[:-1] + x[1:]) / 2.0
        laps = k // m + 2
        ext = np.concatenate([mids + j * period for j in range(-laps, laps + 1)])
        first = np.searchsorted(ext, x[0], side="right") - 1 - k
        t = ext[first:np.searchsorted(ext, x[-1]) + k + 1]
    nt = len(t) - k - 1
    ell = BSpline(t, np.zeros(0), k).interval(x[:m])
    rows = _basis(t, k, x[:m], ell)
    A = np.zeros((m, m))
    for a in range(k + 1):
        np.add.at(A, (np.arange(m), (ell - k + a) % m), rows[a])
    free = np.linalg.solve(A, y[:m].reshape(m, -1))
    return BSpline(t, np.ascontiguousarray(free[np.arange(nt) % m].reshape((nt,) + y.shape[1:])), k)

class SplineSet:
    """Several splines evaluated in one vectorised pass (``__call__(which, x)``: point i on spline
    ``which[i]``), each value bitwise equal to that spline's own: the contact projection's curves
    and their derivatives, a few numpy calls per evaluation instead of several per curve."""

    def __init__(self, splines: list[BSpline]):
        self.splines = list(splines)
        dims = {s.c.reshape(len(s.c), -1).shape[1] for s in self.splines}
        if len(dims) != 1:
            raise ValueError("the splines of a SplineSet must have values of one dimension")
        self.t = np.concatenate([s.t for s in self.splines])
        self.c = np.concatenate([s.c.reshape(len(s.c), -1) for s in self.splines])
        self.t_start = np.cumsum([0] + [len(s.t) for s in self.splines])[:-1]
        self.c_start = np.cumsum([0] + [len(s.c) for s in self.splines])[:-1]
        self.k = np.array([s.k for s in self.splines])
        self.n = np.array([len(s.t) - s.k - 1 for s in self.splines])
        width = max(len(s.t) for s in self.splines)
        self.knots = np.full((len(self.splines), width), np.inf)   # padded: ℓ by one comparison
        for i, s in enumerate(self.splines):
            self.knots[i, :len(s.t)] = s.t

    def __call__(self, which: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Values (len(x), d) of splines ``which`` (indices) at x (NaN where x is NaN)."""
        x = np.asarray(x, dtype=float)
        nan = np.isnan(x)
        xs = np.where(nan, 0.0, x)
        k = self.k[which]
        # BSpline.interval of each point's spline: the knots <= x, less one, within [k, n − 1]
        ell = np.count_nonzero(self.knots[which] <= xs[:, None], axis=1) - 1
        ell = np.minimum(np.maximum(ell, k), self.n[which] - 1)
        out = _combine(self.c, k, ell + self.c_start[which],
                       _basis(self.t, k, xs, ell + self.t_start[which]))
        out[nan] = np.nan
        return out
