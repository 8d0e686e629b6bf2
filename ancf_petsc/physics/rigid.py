"""Rigid-body modes in ANCF nodal coordinates (eq. 3): a translation moves r only; an
infinitesimal rotation ω× acts on all six nodal vectors (r and its five gradients)."""
from __future__ import annotations

import numpy as np


def rigid_modes(x: np.ndarray) -> list[np.ndarray]:
    """The three translations and three rotations (about the origin) of nodal vectors x (n, V, 3),
    each an array like x."""
    modes = []
    for k in range(3):
        v = np.zeros_like(x)
        v[:, 0, k] = 1.0
        modes.append(v)
    return modes + [np.cross(np.eye(3)[k], x) for k in range(3)]
