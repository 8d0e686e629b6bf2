"""Fibre directions in the reference configuration (GOH law, ``goh.py``), following the pretwist.

A section point with tendon-frame coordinates P at x = 0 sits at X(x, P) = (x, a + R(θ) (P − a)),
θ = ψ x / L (``geometry.place``).  Its material line x ↦ X(x, P) has the tangent

    ∂X/∂x = (1, θ' J R(θ) (P − a)),   θ' = ψ / L,   J = rotation by 90°,

inclined to the tendon axis by atan(ρ ψ / L) at radius ρ = |P − a| from the twist axis: the
default fibre direction (``follow: twist``).  ``follow: axis`` drops the pretwist term (fibres
parallel to x).  An extra fibre twist inside a subtendon (its own rate θ_e' = ψ_e / L about the
beam's axis, which runs through its section centroid c) adds θ_e' J R(θ) (P − c); and a fixed
angle α turns the unit fibre t about the section's local z axis (R(θ) e_z, made normal to t)
towards its y axis: t' = cos α t + sin α (b × t) (α = 90° with no twist: along the section's y).
Each angle is one fibre family.
"""
from __future__ import annotations

import numpy as np

from .geometry import rotation, twist_angle


def fibre_directions(x: np.ndarray, P: np.ndarray, length: float, twist_deg: float, axis,
                     centroid, follow: str = "twist", extra_twist_deg: float = 0.0,
                     angles_deg=(0.0,)) -> np.ndarray:
    """Unit fibre directions (families, n, 3) at stations x (n,) of section points P (n, 2)
    (tendon frame, at x = 0)."""
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    R = rotation(twist_angle(x, length, twist_deg))                        # (n, 2, 2)
    lever = np.zeros_like(P)
    if follow == "twist":
        lever += np.deg2rad(twist_deg) / length * (P - np.asarray(axis, dtype=float))
    elif follow != "axis":
        raise ValueError(f"follow must be 'twist' or 'axis'; got {follow!r}")
    if extra_twist_deg:
        lever += np.deg2rad(extra_twist_deg) / length * (P - np.asarray(centroid, dtype=float))
    Rl = np.einsum("nij,nj->ni", R, lever)
    t = np.column_stack([np.ones_like(x), -Rl[:, 1], Rl[:, 0]])           # (1, J R lever)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    ez = np.column_stack([np.zeros_like(x), R[:, :, 1]])                   # (0, R e_z)
    b = ez - np.einsum("ni,ni->n", ez, t)[:, None] * t
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    bt = np.cross(b, t)
    out = [np.cos(a) * t + np.sin(a) * bt for a in np.deg2rad(np.asarray(angles_deg, dtype=float))]
    return np.stack(out)


def gauss_point_stations(x_nodes: np.ndarray, xi: np.ndarray, axial_nodes: int = 3) -> np.ndarray:
    """x of every element's points (E, P): x = x_start + (ξ + 1) h / 2 (nodes equally spaced
    within an element, so the element's x(ξ) is exactly this linear map)."""
    k = axial_nodes - 1                       # an element's end nodes are k apart
    x0 = x_nodes[0:-1:k]
    h = x_nodes[k:None:k] - x0
    return x0[:, None] + 0.5 * (np.asarray(xi)[None, :] + 1.0) * h[:, None]
