"""Contact laws: which multipliers hold their weighted gap at zero in a given state.

Both laws act on the weighted gaps ḡ_k and scaled multipliers z_k of multipliers.py; the
residual rows of the multipliers are

    active:   −k_s ḡ_k      (the constraint ḡ_k = 0, and z_k acts on the bodies)
    inactive: −k_s z_k      (z_k = 0, no pressure)

``SlidingLaw`` — the paper's (§5): the bodies stay together and slide without friction; every
multiplier is active, z may have either sign (tension holds the interface closed).

``UnilateralLaw`` — touching, free to separate: ḡ ≥ 0, z ≥ 0, z ḡ = 0.  The active set is that of
the semismooth Newton method for the complementarity function min(ḡ, z) (a primal–dual active
set strategy): active where ḡ_k ≤ z_k.  Inactive multipliers drop out of the forces, so the
Jacobian stays symmetric and its Newton step is the semismooth Newton step of min(ḡ, z) = 0.
A state with all z = 0 and ḡ = 0 (the start) counts as active: contact starts closed.
"""
from __future__ import annotations

import numpy as np


class SlidingLaw:
    name = "sliding"

    @staticmethod
    def active(gbar: np.ndarray, z: np.ndarray, tol: float = 0.0) -> np.ndarray:
        return np.ones(len(gbar), dtype=bool)

    @staticmethod
    def describe() -> str:
        return "sliding (normal gap held at zero, frictionless)"


class UnilateralLaw:
    name = "unilateral"

    @staticmethod
    def active(gbar: np.ndarray, z: np.ndarray, tol: float = 0.0) -> np.ndarray:
        """ḡ ≤ z, with ties within ``tol`` [m] (rounding of a closed reference gap) active."""
        return gbar <= z + tol

    @staticmethod
    def describe() -> str:
        return "unilateral (gap >= 0, pressure >= 0, frictionless; active set by min(gap, pressure))"


LAWS = {"sliding": SlidingLaw, "unilateral": UnilateralLaw}


def make_law(mode: str):
    return LAWS[mode]()
