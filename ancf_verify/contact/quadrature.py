"""P2 triangle shape functions and the slave faces' Gauss rules (sub-triangles)."""
from __future__ import annotations

import numpy as np


# ============================================================================================
# P2 triangle (faces of the P2 tetrahedra)
# ============================================================================================
# node order: vertices v0 v1 v2, then mid-edge nodes opposite v0, v1, v2: (v1v2), (v0v2), (v0v1)
# parameters (z1, z2), l0 = 1 - z1 - z2
P2_NODES = np.array([[0, 0], [1, 0], [0, 1], [.5, .5], [0, .5], [.5, 0]], dtype=float)

_D2N = np.zeros((6, 2, 2))

_D2N[0] = 4.0

_D2N[1, 0, 0] = 4.0

_D2N[2, 1, 1] = 4.0

_D2N[3, 0, 1] = _D2N[3, 1, 0] = 4.0

_D2N[4, 0, 1] = _D2N[4, 1, 0] = -4.0

_D2N[4, 1, 1] = -8.0

_D2N[5, 0, 1] = _D2N[5, 1, 0] = -4.0

_D2N[5, 0, 0] = -8.0

D2N = _D2N


def p2_shape(z: np.ndarray):
    """Shape functions (..., 6) and derivatives (..., 6, 2) of the P2 triangle at z (..., 2)."""
    z1, z2 = z[..., 0], z[..., 1]
    l0 = 1.0 - z1 - z2
    N = np.stack([l0 * (2 * l0 - 1), z1 * (2 * z1 - 1), z2 * (2 * z2 - 1),
                  4 * z1 * z2, 4 * l0 * z2, 4 * l0 * z1], axis=-1)
    d1 = np.stack([1 - 4 * l0, 4 * z1 - 1, 0 * z1, 4 * z2, -4 * z2, 4 * (l0 - z1)], axis=-1)
    d2 = np.stack([1 - 4 * l0, 0 * z1, 4 * z2 - 1, 4 * z1, 4 * (l0 - z2), -4 * z1], axis=-1)
    return N, np.stack([d1, d2], axis=-1)


# four sub-triangles of the P2 face (corner nodes in P2 order): the multiplier hats live on them
SUBTRI = np.array([[0, 5, 4], [5, 1, 3], [4, 3, 2], [3, 4, 5]])


def tri_rule(n: int):
    """Barycentric points (m, 3) and weights (sum 1) of a triangle rule with n = 3, 6 or 7 points."""
    if n == 3:
        a, b = 2.0 / 3.0, 1.0 / 6.0
        return np.array([[a, b, b], [b, a, b], [b, b, a]]), np.full(3, 1.0 / 3.0)
    if n == 6:
        a1, w1 = 0.816847572980459, 0.109951743655322
        a2, w2 = 0.108103018168070, 0.223381589678011
        b1, b2 = (1 - a1) / 2, (1 - a2) / 2
        pts = [[a1, b1, b1], [b1, a1, b1], [b1, b1, a1], [a2, b2, b2], [b2, a2, b2], [b2, b2, a2]]
        return np.array(pts), np.array([w1] * 3 + [w2] * 3)
    if n == 7:
        a1, w1 = 0.797426985353087, 0.125939180544827
        a2, w2 = 0.059715871789770, 0.132394152788506
        b1, b2 = (1 - a1) / 2, (1 - a2) / 2
        pts = [[1 / 3] * 3, [a1, b1, b1], [b1, a1, b1], [b1, b1, a1], [a2, b2, b2], [b2, a2, b2],
               [b2, b2, a2]]
        return np.array(pts), np.array([0.225] + [w1] * 3 + [w2] * 3)
    raise ValueError(n)


def slave_rule(n: int):
    """Points of the slave-face rule: z (Q, 2), weights in z (Q,) (sum 1/2), hat corners (Q, 3)
    (P2 node indices) and hat values (Q, 3) of the sub-triangle each point lies in."""
    bary, w = tri_rule(n)
    zs, ws, corners, hats = [], [], [], []
    for tri in SUBTRI:
        P = P2_NODES[tri]                       # (3, 2)
        zs.append(bary @ P)
        ws.append(w * 0.125)                    # sub-triangle area in z: 1/8
        corners.append(np.tile(tri, (len(w), 1)))
        hats.append(bary)
    return np.vstack(zs), np.concatenate(ws), np.vstack(corners), np.vstack(hats)
