"""Second starts of the closest-point descent (paper eqs. 26–27): where one descent's result
depends on where it started, a point descends again from a place fixed by the state, and the
nearer of the two results is kept, so that the projection is a function of the state.

- Across an element boundary (``closest``).  B's surface is only C0 across its element
  boundaries, and on either side of one a point may have a closest point of its own (two minima
  3.6e-4 apart in ξ, distances 4.83 and 4.74 μm, measured on a soft GOH column): which one the
  descent found depended on the iterate before, and Newton on the beams cycled between the two
  residuals.  A point ending within NEIGHBOUR_BAND of a boundary descends again from the mirror
  image of its place in the element across it.
- From the checkpoint (``from_checkpoint``).  The continuation of B's interface curve is clamped
  (``wrap``) and a descent that arrives at the clamp stops there however far B is.  On
  the unilateral 135 deg uniform stride (frame 47.2564) contact point 79 ran there from an iterate
  (t = 1.5 T, 4.78 mm, weight 0; its closest point on B: 1.51 mm, weight 1), the residual had
  two values (0.244 N against 3e-8 N) and Newton stalled.  A point ending on the clamp descends
  again from its place at the checkpoint (the last converged state, fixed within a level).

A second start on an element this rank does not hold asks for it (``ask_for``; the neighbours
and the checkpoint's elements are among those it reads).
"""
from __future__ import annotations

import numpy as np

from .descent import ROUNDING, Found
from .fade import curve_limits

#: a partner place within this much of a B element boundary (in ξ) is sought across it too
NEIGHBOUR_BAND = 0.1


class SecondStarts:
    """The second starts of ``Projector`` (its base: they use its ``descend``, ``wrap_bounds``,
    ``saved_places``, ``ask_for``, ``available``, ``points``, ``t_end`` and ``tolerance``)."""

    def across(self, itf: np.ndarray, e: np.ndarray, xi: np.ndarray) -> np.ndarray:
        """The B element across the boundary within NEIGHBOUR_BAND of the places (e, ξ), −1
        where there is none."""
        first, last, _ = self.wrap_bounds(itf)
        other = e + np.where(xi > 0.0, 1, -1)
        return np.where((other >= first) & (other <= last) & (np.abs(xi) > 1.0 - NEIGHBOUR_BAND), other, -1)

    def closest(self, itf, T, xA, x_of, eB, xiB, tB) -> Found:
        """The closest points from the places (e_B, ξ_B, t_B), started again across a near
        element boundary."""
        f = self.descend(itf, T, xA, x_of, eB, xiB, tB)
        other = np.where(f.valid, self.across(itf, f.eB, f.xiB), -1)
        absent = (other >= 0) & ~self.available[np.maximum(other, 0)]
        self.ask_for(other[absent])
        two = np.flatnonzero((other >= 0) & ~absent)
        if len(two):
            g = self.descend(itf[two], T[two], xA[two], x_of, other[two], -f.xiB[two], f.tB[two].copy())
            keep_nearer(f, two, g, T[two], g.valid)
        return f

    def at_clamp(self, itf: np.ndarray, tB: np.ndarray) -> np.ndarray:
        """Whether the curve parameters t_B sit at the clamp of the curve's continuation
        (``wrap``: fade.curve_limits)."""
        T = self.wrap_bounds(itf)[2]
        lo, hi = curve_limits(T)
        tol = self.tolerance * T
        return (tB <= lo + tol) | (tB >= hi - tol)

    def from_checkpoint(self, idx: np.ndarray, xA: np.ndarray, x_of, f: Found) -> None:
        """Points ``idx`` whose result in ``f`` is on the clamp descend again (``closest``) from
        their checkpoint places (unless those are on the clamp too, or are the result itself)."""
        itf = self.points.itf[idx]
        e0, xi0, t0 = self.saved_places(idx)
        moved = (e0 != f.eB) | (xi0 != f.xiB) | (t0 != f.tB)
        redo = self.at_clamp(itf, f.tB) & ~self.at_clamp(itf, t0) & moved
        absent = redo & ~self.available[e0]
        self.ask_for(e0[absent])
        rows = np.flatnonzero(redo & ~absent)
        if len(rows):
            T = self.t_end[idx][rows]
            g = self.closest(itf[rows], T, xA[rows], x_of, e0[rows], xi0[rows], t0[rows])
            keep_nearer(f, rows, g, T)


def keep_nearer(f: Found, rows: np.ndarray, g: Found, T: np.ndarray, eligible: np.ndarray | bool = True) -> None:
    """Take ``g``'s results into ``f``'s ``rows`` where they are done, ``eligible`` (all: True)
    and nearer by more than the rounding of φ (the first result on a tie)."""
    slack = ROUNDING * T * (np.sqrt(2.0 * f.phi[rows]) + ROUNDING * T)
    better = g.done & eligible & (g.phi < f.phi[rows] - slack)
    f.take(rows[better], g, better)
