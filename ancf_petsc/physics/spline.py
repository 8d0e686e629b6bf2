"""Spline curves through control points with the cumulative chordal parametrisation (paper Sec. 2.2)."""
from __future__ import annotations

from typing import Any

import numpy as np
from .bspline import interpolating_spline, periodic_spline
from .cubature import CurvePiece

DEFAULT_SPLINE_DEGREE = 3


def usable_degree(degree: int, n_points: int) -> int:
    """The spline degree built through ``n_points`` points: ``degree`` capped at n_points - 1, and
    an even cap above 2 lowered by one (not-a-knot interpolation has degrees 1, 2 and odd ones: 5
    points at degree 5 gave degree 4 and a ValueError 'Odd degree for now only')."""
    p = min(int(degree), n_points - 1)
    return p - 1 if p > 2 and p % 2 == 0 else p


class SectionError(ValueError):
    """Invalid cross-section input; the message says what is wrong and how to fix it."""


# --------------------------------------------------------------------------------------
# Spline curves
# --------------------------------------------------------------------------------------
class SplineCurve:
    """Interpolating spline S(t) = (S_1(t), S_2(t)) through control points (Sec. 2.2).

    Parameter: cumulative chordal, t_1 = 0, t_{j+1} = t_j + |P_{j+1} - P_j|.  Degree
    p = :func:`usable_degree` (degree, m) (``bspline.interpolating_spline``: scipy's ``make_interp_spline``,
    not-a-knot, to the last bit; p = 1
    is the polygon through the points).  ``periodic``: a curve whose last point is its first (within
    1e-9 of its size), a whole outline, is the periodic spline (``bspline.periodic_spline``), smooth
    where it closes too; not-a-knot ends left a kink there (8 points on a 4 x 2.5 mm ellipse: the
    centroid 17 um off, the area -0.3 %).  ``breakpoints`` are the parameters between which
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
    periodic: bool

    def __init__(self, points: Any, degree: int = DEFAULT_SPLINE_DEGREE,
                 name: str = "curve", periodic: bool = False) -> None:
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
        p = usable_degree(degree, P.shape[0])
        periodic = bool(periodic) and p >= 2 and P.shape[0] >= 4 and float(np.linalg.norm(P[-1] - P[0])) <= 1e-9 * size
        spl = periodic_spline(t, P, p) if periodic else interpolating_spline(t, P, p)
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
        self.periodic = periodic
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

    def bspline(self, nu: int = 0):
        """The forward spline's nu-th derivative (``bspline.BSpline``, what ``__call__`` evaluates;
        a reversed curve evaluates it at t_end − t, negated for odd nu)."""
        base = self._base
        if nu not in base._derivs:
            base._derivs[nu] = base._spline.derivative(nu)
        return base._derivs[nu]

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
            r.periodic = self.periodic
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
