"""The weights of contact points in the weighted gaps when their partners slide past B's ends.

A point's partner place (ξ_B, t_B) has the weight ``projection.end_weight``: 1 on B's surface and
up to CURVE_OVERHANG beyond the ends of its interface curve, falling smoothly (C¹) to 0 at
CURVE_FADE_END, and likewise past B's beam ends.  Two ways to solve with them
(``contact.fade``):

* ``settle`` (default): during a Newton solve a point whose weight was 1 at the last update
  follows its partner (a wild iterate that slides it far acts through no far extrapolation of
  B's surface), and a point partly off keeps the weight it had: a constant, so that the tangent
  stays exact (and symmetric).  Between solves the weights are brought up to date and the state
  solved again until none changes by more than ``WEIGHT_TOL`` (``refresh``): a fixed point.
* ``newton``: every evaluation takes the weights w_p = w(ζ_p(q)) of its own partner places, and
  the Jacobian their derivative ∇w_p = (∂w/∂ζ) ∂ζ/∂q (``weight_gradient``; ∂ζ/∂q from the
  linearised projection, gap.py): Newton on the state and the weights together, with an
  unsymmetric Jacobian (contact/blocks.py).

Before the fade, a point was switched off at once 25 % past the curve's end, and Newton cycled
between two states when one sat there (the bulk-modulus sweep of the paper's sliding columns,
docs/contact.md).
"""
from __future__ import annotations

import numpy as np

from .gap import closest_point_gradient
from .projection import end_weight_slope, subset

#: a change of a point's weight beyond this asks for another Newton solve (a weight off by 1e-6
#: moves a weighted gap by 1e-6 of the point's local gap, ~1e-11 m)
WEIGHT_TOL = 1e-6


def weight_gradient(projector, pr) -> np.ndarray:
    """∇w_p (P, 108, over A's then B's element slots as gap.gap_gradient) of the points of the
    projection ``pr``: (∂w/∂ζ) ∂ζ/∂q, nonzero only in the fade bands."""
    itf = projector.points.itf[pr.idx]
    first = np.array([i.b.element_offset for i in projector.interfaces], dtype=np.int64)[itf]
    last = first + np.array([i.b.n_elements - 1 for i in projector.interfaces], dtype=np.int64)[itf]
    slope = end_weight_slope(pr.xiB, pr.tB, projector.t_end[pr.idx], pr.eB == first, pr.eB == last)
    out = np.zeros((len(pr.idx), 108))
    band = np.flatnonzero(np.any(slope != 0.0, axis=1))
    if len(band):
        dz = closest_point_gradient(subset(pr, band))                   # (B, 2, 108)
        out[band] = np.einsum("pa,paj->pj", slope[band], dz)
    return out


class PointWeights:
    """The last updated weight of every contact point, with its checkpoint; ``differentiated``
    (``contact.fade: newton``): every evaluation takes its partner places' own weights."""

    def __init__(self, n_points: int, differentiated: bool = False):
        self.values = np.ones(n_points)
        self._saved = self.values.copy()
        self.differentiated = differentiated

    def effective(self, idx: np.ndarray, current: np.ndarray) -> np.ndarray:
        """The weights of the points ``idx`` in an evaluation whose partner places have the
        weights ``current``: settle: those that were whole follow them, the others keep theirs
        (0 once their partner has left every fade band); newton: ``current``."""
        if self.differentiated:
            return current
        kept = self.values[idx]
        return np.where(kept < 1.0, kept * (current > 0.0), current)

    def refresh(self, idx: np.ndarray, current: np.ndarray) -> float:
        """Update the points ``idx`` to ``current`` (what the output reports); the largest change
        (newton: 0, every evaluation had its own weights)."""
        change = float(np.max(np.abs(current - self.values[idx]), initial=0.0))
        self.values[idx] = current
        return 0.0 if self.differentiated else change

    def set(self, values: np.ndarray) -> None:
        """Weights of a restored state (a restart), also as the checkpoint."""
        self.values = np.asarray(values, dtype=float).copy()
        self._saved = self.values.copy()

    def checkpoint(self) -> None:
        self._saved = self.values.copy()

    def restore(self) -> None:
        self.values = self._saved.copy()
