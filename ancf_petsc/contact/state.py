"""What one evaluation of the contact at a state found (local points and multipliers)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .laws import Rows
from .projection import Projection


@dataclass
class ContactState:
    """Everything one evaluation at a state found (local points and multipliers)."""
    pr: Projection
    xA: np.ndarray         # (P_loc, 3) positions of the points
    gbar: np.ndarray       # (M_loc,) weighted gaps ḡ [m]
    z: np.ndarray          # (M_loc,) scaled multipliers [m]
    active: np.ndarray     # (M_loc,) bool
    tau: np.ndarray        # (P_loc,) w_p × pressure [N], times the point's weight
    pressure: np.ndarray   # (P_loc,) k_s (Φᵀ z·load)_p: τ_p without the point's weight [N]
    weight: np.ndarray     # (P_loc,) the points' weights in this evaluation (Contact.weights)
    lpos: object           # PETSc node id → position in the local array
    rows: Rows             # the law's constraint rows (laws.Rows)
    xl: np.ndarray         # the local state (n, 6, 3) it was evaluated at
    support: np.ndarray | None = None   # (M_loc,) bool: the function has a weighted point
    terms: dict = field(default_factory=dict)   # each contact term's evaluation (Contact.terms)
    fade: object = None    # the fade weights' derivatives here (weights.FadeDerivatives), once asked
