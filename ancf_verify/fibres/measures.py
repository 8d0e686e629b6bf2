"""Measures of a deformed bar: rim inclination, polar angle, section rotation, volumetric share."""
from __future__ import annotations

import math

import numpy as np

from ancf_verify.fibres.cases import LENGTH, SECTION, TWIST
from ancf_verify.paths import CONFIGS


def rim_inclination_deg() -> float:
    """Fibre inclination atan(ρ ψ / L) at the end of the section's major semi-axis."""
    return math.degrees(math.atan(max(SECTION["semi_axes"]) * math.radians(TWIST) / LENGTH))


# --------------------------------------------------------------------------------------------
# ANCF
# --------------------------------------------------------------------------------------------
def polar_angle_deg(M: np.ndarray) -> float:
    """Rotation angle of the polar decomposition of a 2x2 M, positive about +x."""
    return math.degrees(math.atan2(M[1, 0] - M[0, 1], M[0, 0] + M[1, 1]))


def section_rotation_deg(q: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """Rotation about x of the sections at nodes (n, 6, 3): polar angle of A A0⁻¹, A = in-plane
    part of [r_y r_z]."""
    A, A0 = q[:, 1:3, 1:3].transpose(0, 2, 1), q0[:, 1:3, 1:3].transpose(0, 2, 1)
    return np.array([polar_angle_deg(M) for M in np.matmul(A, np.linalg.inv(A0))])


def ancf_volumetric_share(raw: dict, q: np.ndarray) -> float:
    """Share of the volumetric energy K/2 (J − 1)² (``locking: mixed``: K/2 (θ − 1)², θ the
    projected dilatation) in the strain energy at nodal vectors q, over the beam's own Gauss points."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from ancf_petsc.physics.kernels import deformation_gradient
    model = build_model(parse_config(raw, base_dir=CONFIGS))
    b = model.beams[0]
    local = np.arange(b.n_elements)
    G, w, material = model.element_data(b, local)[0]
    F = deformation_gradient(q[b.connectivity][:, :, list(b.vectors)].reshape(len(local), -1, 3), G)
    J = material.dilatation(F) if hasattr(material, "dilatation") else np.linalg.det(F)
    return float(np.sum(w * 0.5 * raw["beams"][0]["material"]["bulk_modulus"] * (J - 1.0) ** 2)
                 / np.sum(w * material.energy(F)))


def fitted_rotation_deg(X: np.ndarray, x: np.ndarray, w: np.ndarray) -> float:
    """Rotation of the weighted least-squares linear fit x ≈ x̄ + M (X − X̄) of in-plane points."""
    s = X - w @ X / w.sum()
    d = x - w @ x / w.sum()
    return polar_angle_deg((w[:, None] * d).T @ s @ np.linalg.inv((w[:, None] * s).T @ s))
