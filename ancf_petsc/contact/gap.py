"""Derivatives of the signed normal gap g = (x_A − Y(ζ̄))·n (paper eq. 27) with respect to q.

Per contact point the unknowns are A's element (18 slots × 3 components) then B's element
(18 × 3): 108 numbers, slot-major.  With ζ̄ = (ξ_B, t_B) the closest point (Y_ζ·d = 0, d = g n):

    ∇g  = Dᵀ n,                     D = ∂d/∂q at fixed ζ = [N_A ⊗ I, −N_B ⊗ I]
    ∇²g = −W C Wᵀ,                  W = [u₁ u₂ v₁ v₂] (108 × 4)

with the tangents T_α = Y_,α, u_α = Dᵀ T_α, v_α = [0, N_B,α ⊗ n] (the normal component of the
tangents' variation), the metric a = TᵀT, the curvature b_αβ = n·Y_,αβ, H = a − g b and

    C = [[a⁻¹ b H⁻¹, H⁻¹], [H⁻¹, g H⁻¹]]   (symmetric).

It follows from δg = nᵀD δq, the rotation of the normal δn = −a^{αβ}(n·δT_α) T_β and the
linearised projection H Δζ = (U + g V) Δq.  No division by g: the formula holds on the surface.
The same two give the normal's gradient (``normal_gradient``, for a tangential law):

    ∇n = −T a⁻¹ (V + b H⁻¹ (U + g V)),   U = [u₁ u₂]ᵀ, V = [v₁ v₂]ᵀ (2 × 108),

and the partner place's (``closest_point_gradient``, for the fade weights, contact/weights.py):
∂ζ/∂q = H⁻¹ (U + g V).
"""
from __future__ import annotations

import numpy as np



def gap_gradient(pr) -> np.ndarray:
    """∇g of every point (P, 108)."""
    NAB = np.concatenate([pr.NA, -pr.NB], axis=1)                    # (P, 36)
    return (NAB[:, :, None] * pr.n[:, None, :]).reshape(len(pr.g), 3 * NAB.shape[1])


def _det2(M: np.ndarray) -> np.ndarray:
    """Determinants of (P, 2, 2) matrices in closed form (np.linalg.det's LAPACK call costs
    ~25 µs a batch of a few points, the formula ~3 µs)."""
    return M[:, 0, 0] * M[:, 1, 1] - M[:, 0, 1] * M[:, 1, 0]


def _inverse2(M: np.ndarray) -> np.ndarray:
    """Inverses of (P, 2, 2) matrices in closed form."""
    det = _det2(M)
    out = np.empty_like(M)
    out[:, 0, 0], out[:, 1, 1] = M[:, 1, 1] / det, M[:, 0, 0] / det
    out[:, 0, 1], out[:, 1, 0] = -M[:, 0, 1] / det, -M[:, 1, 0] / det
    return out


def gap_hessian_factors(pr) -> tuple[np.ndarray, np.ndarray]:
    """W (P, 108, 4) and C (P, 4, 4) with ∇²g_p = −W_p C_p W_pᵀ."""
    return _gap_hessian_w(pr), gap_hessian_core(pr)


def _gap_hessian_w(pr) -> np.ndarray:
    """W (P, 108, 4) of ``gap_hessian_factors``: [u₁ u₂ v₁ v₂]."""
    P, T = len(pr.g), pr.Yz
    NAB = np.concatenate([pr.NA, -pr.NB], axis=1)                    # (P, 36)
    SLOTS = pr.NA.shape[1]                                           # an element's slots (18 for 3363)
    W = np.zeros((P, 2 * SLOTS, 3, 4))
    W[..., :2] = NAB[:, :, None, None] * T[:, None, :, :]            # u_α
    W[:, SLOTS:, :, 2:] = pr.NBz[:, :, None, :] * pr.n[:, None, :, None]  # v_α
    return W.reshape(P, 6 * SLOTS, 4)


def gap_hessian_core(pr) -> np.ndarray:
    """C (P, 4, 4) of ``gap_hessian_factors``."""
    P = len(pr.g)
    T = pr.Yz                                                        # (P, 3, 2)
    a = np.matmul(T.transpose(0, 2, 1), T)
    b = np.einsum("piab,pi->pab", pr.Yzz, pr.n)
    Hi = _inverse2(a - pr.g[:, None, None] * b)
    C = np.empty((P, 4, 4))
    Cuu = _inverse2(a) @ b @ Hi
    C[:, :2, :2] = 0.5 * (Cuu + Cuu.transpose(0, 2, 1))           # symmetric in exact arithmetic
    C[:, :2, 2:] = Hi
    C[:, 2:, :2] = Hi
    C[:, 2:, 2:] = pr.g[:, None, None] * Hi
    return C



def projection_conditioning(pr) -> np.ndarray:
    """det H / det a of every point (1 on B's surface, g = 0): how well its closest point is
    determined; it falls towards 0 as the point lies a radius of curvature of B away from it
    (H = a − g b singular) and is negative past that."""
    T = pr.Yz
    a = np.matmul(T.transpose(0, 2, 1), T)
    b = np.einsum("piab,pi->pab", pr.Yzz, pr.n)
    H = a - pr.g[:, None, None] * b
    with np.errstate(invalid="ignore", divide="ignore"):
        out = _det2(H) / _det2(a)
    return np.nan_to_num(out, nan=-1.0)          # a degenerate surface: ill-posed


def _projection_parts(pr):
    """a, b, H⁻¹ and U, V (P, 2, 108) of the linearised projection H Δζ = (U + g V) Δq."""
    T = pr.Yz                                                        # (P, 3, 2)
    a = np.matmul(T.transpose(0, 2, 1), T)
    b = np.einsum("piab,pi->pab", pr.Yzz, pr.n)
    Hi = _inverse2(a - pr.g[:, None, None] * b)
    W = _gap_hessian_w(pr)
    U, V = W[:, :, :2].transpose(0, 2, 1), W[:, :, 2:].transpose(0, 2, 1)     # (P, 2, 108)
    return a, b, Hi, U, V


def normal_gradient(pr) -> np.ndarray:
    """∇n of every point (P, 3, 108): B's unit normal at the closest point, as the point and
    B's surface move (the closest point moving with them)."""
    a, b, Hi, U, V = _projection_parts(pr)
    M = V + b @ Hi @ (U + pr.g[:, None, None] * V)
    return -(pr.Yz @ _inverse2(a)) @ M


def _slot_vector(N: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(P, 36 × 3) vectors N_s v_i (slot-major) from slot values N (P, 36) and 3-vectors v (P, 3)."""
    return (N[:, :, None] * v[:, None, :]).reshape(len(N), -1)


def closest_point_hessian(pr, c: np.ndarray, NBzz: np.ndarray, Yzzz: np.ndarray,
                          curvature: np.ndarray | None = None) -> np.ndarray:
    """∇²(c·ζ) (P, 108, 108) of the partner place ζ = (ξ_B, t_B) of every point of ``pr``
    contracted with fixed weights c (P, 2), from the closest-point condition r = −Y_ζᵀ d = 0
    differentiated twice:

        ∇²(c·ζ) = −λ·(φ_ζζζ[ζ′, ζ′] + 2 sym(∂H/∂q ζ′) + r_qq),   λ = H⁻¹ c,

    with φ_αβγ = Y_αβ·Y_γ + Y_αγ·Y_β + Y_βγ·Y_α − Y_αβγ·d, ∂H_αβ/∂q from H = Y_ζᵀY_ζ − Y_ζζ·d
    and r_α,qq = −(a_α bᵀ + b a_αᵀ) ⊗ I (a_α = [0, N_B,α], b = [N_A, −N_B]): the surface is
    linear in B's nodal vectors and d in both bodies'.  ``NBzz``, ``Yzzz``: B's shape functions'
    second ζ-derivatives and the surface's third (``projection.surface_third``).  With
    ``curvature`` C (P, 2, 2), ζ′ᵀ C ζ′ is added (a weight's ∂²w/∂ζ², weights.py).

    Every term has rank ≤ 3 per point in q, so the sum is one batched product L R of
    (P, 108, 10) and (P, 10, 108): [ζ′ᵀ(C − ψ) − Λᵀ, −ζ′ᵀ, ā ⊗ I, b ⊗ I] [ζ′; Λ; b ⊗ I; ā ⊗ I]
    with ψ = λ·φ_ζζζ and Λ_β = Σ_α λ_α ∂H_αβ/∂q."""
    P = len(pr.g)
    T, Tab, d = pr.Yz, pr.Yzz, pr.d                                    # (P,3,2), (P,3,2,2), (P,3)
    a, b, Hi, U, V = _projection_parts(pr)
    dz = Hi @ (U + pr.g[:, None, None] * V)                           # ζ′ (P, 2, 108)
    lam = np.einsum("pab,pb->pa", Hi, c)                              # H symmetric
    phi = (np.einsum("piab,pic->pabc", Tab, T) + np.einsum("piac,pib->pabc", Tab, T)
           + np.einsum("pibc,pia->pabc", Tab, T) - np.einsum("piabc,pi->pabc", Yzzz, d))
    M = -np.einsum("pa,pabc->pbc", lam, phi)                          # −ψ, the φ_ζζζ[ζ′, ζ′] part
    if curvature is not None:
        M = M + curvature
    # Λ_β = Σ_α λ_α ∂H_αβ/∂q for β = ξ, t
    SLOTS = pr.NA.shape[1]                                           # an element's slots (18 for 3363)
    zA = np.zeros((P, SLOTS))
    NA, NB, NBz = pr.NA, pr.NB, pr.NBz
    lam_h = np.empty((P, 2, 6 * SLOTS))
    lt = np.einsum("pa,pia->pi", lam, T)                              # Σ_α λ_α Y_α
    nb_lam = np.einsum("psa,pa->ps", NBz, lam)                        # Σ_α λ_α N_B,α
    for beta in range(2):
        tb = np.einsum("pa,pia->pi", lam, Tab[:, :, :, beta])          # Σ_α λ_α Y_αβ
        part_a = _slot_vector(np.concatenate([-NA, NB], axis=1), tb)
        nbb_lam = np.einsum("psa,pa->ps", NBzz[:, :, :, beta], lam)     # Σ_α λ_α N_B,αβ
        part_b = (_slot_vector(np.concatenate([zA, nb_lam], axis=1), T[:, :, beta])
                  + _slot_vector(np.concatenate([zA, NBz[:, :, beta]], axis=1), lt)
                  - _slot_vector(np.concatenate([zA, nbb_lam], axis=1), d))
        lam_h[:, beta] = part_a + part_b
    # −Σ_α λ_α r_α,qq = (ā bᵀ + b āᵀ) ⊗ I, ā = [0, Σ_α λ_α N_B,α], b = [N_A, −N_B]
    abar = np.concatenate([zA, nb_lam], axis=1)                       # (P, 36)
    bb = np.concatenate([NA, -NB], axis=1)
    eye = np.eye(3)
    abar_I = (abar[:, :, None, None] * eye).reshape(P, 6 * SLOTS, 3)  # (P, 108, 3): ā ⊗ e_k
    bb_I = (bb[:, :, None, None] * eye).reshape(P, 6 * SLOTS, 3)
    left = np.concatenate([np.einsum("paj,pab->pjb", dz, M) - lam_h.transpose(0, 2, 1),
                           -dz.transpose(0, 2, 1), abar_I, bb_I], axis=2)
    right = np.concatenate([dz, lam_h, bb_I.transpose(0, 2, 1), abar_I.transpose(0, 2, 1)], axis=1)
    return left @ right


def closest_point_gradient(pr) -> np.ndarray:
    """∂ζ/∂q = H⁻¹ (U + g V) of every point (P, 2, 108): how its partner place (ξ_B, t_B) moves
    with A's and B's nodal vectors (the linearised projection)."""
    _, _, Hi, U, V = _projection_parts(pr)
    return Hi @ (U + pr.g[:, None, None] * V)
