"""The mixed-integration-point tangent (``solver.tangent: mixed``): the initial-stress part of the
element tangent formed with the stress of the strain linearised along the last Newton step.

The element tangent K_ab = Σ_p w G_a · 𝔸 · G_b (kernels.py) holds the initial-stress term
δ_ik G_a · S · G_b with S = S(C(q)), the stress of the iterate.  A Newton step that turns a
slender beam's sections (the untwist of a pretwisted subtendon, a bend) leaves a second-order
stretch ½ ΔFᵀΔF in C, and in a stiff direction (the fibres, the bulk modulus) a large spurious
stress that enters the next tangent and sends the next step off: the residual then rises every
other iteration.  Treating the stress at each integration point as an independent field (the
Hu–Washizu form, condensed at the point: the MIP Newton of Magisano, Leonetti and Garcea,
CMAME 2017) replaces that S by the stress of the linearised strain

    Ĉ = C(q_prev) + 2 sym(F_prevᵀ ΔF) = FᵀF − ΔFᵀΔF,   ΔF = F − F_prev,

while the residual (eq. 9) stays the displacement model's: the converged states are the same, only
the iterates differ.  S(Ĉ) is evaluated exactly (any F̂ with F̂ᵀF̂ = Ĉ: the Cholesky factor), so the
material's own nonlinearity (GOH's exponential fibres, their tension-only switch) is kept.
"""
from __future__ import annotations

import numpy as np

from .materials import det_and_inverse_transpose
from .mixed import ProjectedDilatation

#: Ĉ's smallest eigenvalue below this (a principal stretch under 0.32): the step is too long for
#: the linearised strain; such a point keeps the iterate's own stress
MIN_EIGENVALUE = 0.1


def second_piola(material, F: np.ndarray) -> np.ndarray:
    """S = F⁻¹P (..., 3, 3) of a law whose stress depends on F only."""
    P, _ = material.stress(F)
    _, F_inv_t = det_and_inverse_transpose(F)
    return np.matmul(np.swapaxes(F_inv_t, -1, -2), P)


def linearised_stretch(F: np.ndarray, F_prev: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """F̂ (..., 3, 3) with F̂ᵀF̂ = Ĉ = FᵀF − ΔFᵀΔF, and where Ĉ is usable (MIN_EIGENVALUE,
    finite); elsewhere F̂ = I."""
    dF = F - F_prev
    C_hat = np.matmul(np.swapaxes(F, -1, -2), F) - np.matmul(np.swapaxes(dF, -1, -2), dF)
    finite = np.all(np.isfinite(C_hat), axis=(-2, -1))
    C_hat[~finite] = np.eye(3)
    ok = finite & (np.linalg.eigvalsh(C_hat)[..., 0] > MIN_EIGENVALUE)
    C_hat[~ok] = np.eye(3)
    return np.ascontiguousarray(np.swapaxes(np.linalg.cholesky(C_hat), -1, -2)), ok


def initial_stress_correction(F: np.ndarray, F_prev: np.ndarray, G: np.ndarray, w: np.ndarray,
                              material) -> np.ndarray:
    """δK (E, 3S, 3S) to add to the element tangents at F (E, P, 3, 3): δ_ik Σ_p w G_a · ΔS · G_b
    with ΔS = S(Ĉ) − S(C) (zero where Ĉ is not usable: with ``locking: mixed``, whose projected
    dilatation couples an element's points, in the whole element); G (E, P, S, 3), w (E, P)."""
    F_hat, ok = linearised_stretch(F, F_prev)
    if isinstance(material, ProjectedDilatation):    # θ couples an element's points: all or none
        ok = np.broadcast_to(ok.all(axis=1, keepdims=True), ok.shape)
        F_hat = np.where(ok[..., None, None], F_hat, F)
    with np.errstate(over="ignore", invalid="ignore"):
        dS = second_piola(material, F_hat) - second_piola(material, F)
    dS = np.where((ok & np.all(np.isfinite(dS), axis=(-2, -1)))[..., None, None], dS, 0.0)
    dS = 0.5 * (dS + np.swapaxes(dS, -1, -2))
    E, Np, S = G.shape[:3]
    right = np.matmul(G, dS) * w[..., None, None]                       # w (ΔS G_b) (E, P, S, 3)
    Ks = np.matmul(_by_function(G), np.swapaxes(_by_function(right), 1, 2))     # (E, S, S)
    K = np.zeros((E, S, 3, S, 3))
    idx = np.arange(3)
    K[:, :, idx, :, idx] = Ks[None]
    return K.reshape(E, 3 * S, 3 * S)


def _by_function(A: np.ndarray) -> np.ndarray:
    """(E, P, S, 3) → (E, S, 3P): shape functions × (points, components)."""
    E, P, S = A.shape[:3]
    return A.transpose(0, 2, 1, 3).reshape(E, S, 3 * P)
