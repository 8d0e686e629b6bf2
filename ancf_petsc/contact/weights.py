"""The weights of contact points in the weighted gaps when their partners slide past B's ends.

A point's partner place (ξ_B, t_B) has the weight ``projection.end_weight``: 1 on B's surface and
up to CURVE_OVERHANG beyond the ends of its interface curve, falling smoothly (C¹) to 0 at
CURVE_FADE_END, and likewise past B's beam ends.  During a Newton solve a point whose weight was
1 at the last update follows its partner (a wild iterate that slides it far acts through no far
extrapolation of B's surface), and a point partly off keeps the weight it had: a constant, so
that the tangent stays exact.  Between solves the weights are brought up to date and the state
solved again until none changes by more than ``WEIGHT_TOL`` (``refresh``).  Before, a point was
switched off at once 25 % past the curve's end, and Newton cycled between two states when one
sat there (the bulk-modulus sweep of the paper's sliding columns, docs/contact.md).
"""
from __future__ import annotations

import numpy as np

#: a change of a point's weight beyond this asks for another Newton solve (a weight off by 1e-6
#: moves a weighted gap by 1e-6 of the point's local gap, ~1e-11 m)
WEIGHT_TOL = 1e-6


class PointWeights:
    """The last updated weight of every contact point, with its checkpoint."""

    def __init__(self, n_points: int):
        self.values = np.ones(n_points)
        self._saved = self.values.copy()

    def effective(self, idx: np.ndarray, current: np.ndarray) -> np.ndarray:
        """The weights of the points ``idx`` in an evaluation whose partner places have the
        weights ``current``: those that were whole follow them, the others keep theirs (0 once
        their partner has left every fade band)."""
        kept = self.values[idx]
        return np.where(kept < 1.0, kept * (current > 0.0), current)

    def refresh(self, idx: np.ndarray, current: np.ndarray) -> float:
        """Update the points ``idx`` to ``current``; the largest change."""
        change = float(np.max(np.abs(current - self.values[idx]), initial=0.0))
        self.values[idx] = current
        return change

    def set(self, values: np.ndarray) -> None:
        """Weights of a restored state (a restart), also as the checkpoint."""
        self.values = np.asarray(values, dtype=float).copy()
        self._saved = self.values.copy()

    def checkpoint(self) -> None:
        self._saved = self.values.copy()

    def restore(self) -> None:
        self.values = self._saved.copy()
