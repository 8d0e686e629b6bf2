"""Pretwist map and reference nodal coordinates (paper §6, Figure 3).

A section point with tendon-frame coordinates P = (Y, Z) at x = 0 sits at
``X(x, P) = (x, a + R(θ(x)) (P − a))`` with θ = ψ x / L and ``a`` the twist axis.  Each beam's
axis y = z = 0 runs through its section centroid c, so a beam's local section coordinates are
s = P − c and its reference nodal vectors at a node x_i are

    r = X(x_i, c),  r_y = (0, R(θ_i) e_y),  r_z = (0, R(θ_i) e_z),  r_yy = r_zz = r_yz = 0.

Because X is affine in P at fixed x, the element's interpolation of neighbouring beams agrees on
their shared interface for any element count (their nodes sit at the same x).
"""
from __future__ import annotations

import numpy as np


def rotation(theta: np.ndarray) -> np.ndarray:
    """In-plane rotation matrices R(θ), (n, 2, 2)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def twist_angle(x: np.ndarray, length: float, twist_deg: float) -> np.ndarray:
    """θ(x) = ψ x / L in radians (linear pretwist from 0 at x = 0 to ψ at x = L)."""
    return np.deg2rad(twist_deg) * np.asarray(x, dtype=float) / length


def place(x: np.ndarray, P: np.ndarray, length: float, twist_deg: float, axis) -> np.ndarray:
    """Reference position X(x, P) of tendon-frame section points P (n, 2) at stations x (n,)."""
    a = np.asarray(axis, dtype=float)
    R = rotation(twist_angle(x, length, twist_deg))
    yz = a + np.einsum("nij,nj->ni", R, np.asarray(P, dtype=float) - a)
    return np.column_stack([x, yz])


def reference_nodal_vectors(x_nodes: np.ndarray, centroid, length: float, twist_deg: float,
                            axis, vectors: int = 6) -> np.ndarray:
    """Reference nodal vectors (n_nodes, vectors, 3) of one beam in its node block's order (eq. (3)
    for 3363): r, r_y, r_z, then the higher section derivatives, all 0."""
    x_nodes = np.asarray(x_nodes, dtype=float)
    n = len(x_nodes)
    R = rotation(twist_angle(x_nodes, length, twist_deg))
    q0 = np.zeros((n, vectors, 3))
    q0[:, 0] = place(x_nodes, np.tile(centroid, (n, 1)), length, twist_deg, axis)
    q0[:, 1, 1:] = R[:, :, 0]
    q0[:, 2, 1:] = R[:, :, 1]
    return q0
