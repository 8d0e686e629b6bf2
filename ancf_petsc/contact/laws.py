"""Contact laws: which multipliers hold their weighted gap at zero in a given state.

Both laws act on the weighted gaps ḡ_k and the scaled multipliers z_k of multipliers.py; the
residual rows of the multipliers are

    active:   −k_s ḡ_k      (the constraint ḡ_k = 0; z_k acts on the bodies)
    inactive: −k_s z_k      (z_k = 0: no pressure)

``SlidingLaw`` — the paper's (§5): the bodies stay together and slide without friction; every
multiplier is active and may have either sign (a pull holds the interface closed).

``UnilateralLaw`` — touching, free to separate: ḡ ≥ 0, z ≥ 0, z ḡ = 0, by an active-set strategy
inside Newton's iteration: an active constraint is released when its multiplier pulls
(z < −tol), an inactive one is activated when it penetrates (ḡ < −tol); otherwise a constraint
keeps its status.  The start counts as open: the loaded body moves freely in the first Newton
step and the constraints it penetrates come in.  Inactive multipliers drop out of the forces, so
the Jacobian stays symmetric.  The status is state of the law: the caller checkpoints it with
the converged load levels.  Measured on the Achilles ψ = 45° column (docs/contact.md): the
primal–dual rule "active where ḡ ≤ z" cycles on the many constraints that stay nearly closed
with nearly no pressure next to the supports (2 700 Newton iterations, 150 cut-backs), and
PETSc's SNESVI (reduced-space, bounds z ≥ 0) stagnates in the first increment, and this rule
started closed needs 200+ iterations (ψ = 15°: fails); started open it takes 36/95/111 Newton
iterations for the ψ = 0/15/45° columns with tol = 1e-9 of the section size.
"""
from __future__ import annotations

import numpy as np


class SlidingLaw:
    name = "sliding"

    @staticmethod
    def active(gbar: np.ndarray, z: np.ndarray, previous: np.ndarray, tol: float) -> np.ndarray:
        return np.ones(len(gbar), dtype=bool)

    @staticmethod
    def describe() -> str:
        return "sliding (normal gap held at zero, frictionless)"


class UnilateralLaw:
    name = "unilateral"

    @staticmethod
    def active(gbar: np.ndarray, z: np.ndarray, previous: np.ndarray, tol: float) -> np.ndarray:
        """The new status from the previous one: release on a pull, activate on penetration."""
        out = previous.copy()
        out[previous & (z < -tol)] = False
        out[~previous & (gbar < -tol)] = True
        return out

    @staticmethod
    def describe() -> str:
        return "unilateral (gap >= 0, pressure >= 0, frictionless; active set in Newton)"


LAWS = {"sliding": SlidingLaw, "unilateral": UnilateralLaw}


def make_law(mode: str):
    return LAWS[mode]()
