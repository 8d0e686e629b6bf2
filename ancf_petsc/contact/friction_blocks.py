"""The Jacobian blocks of Coulomb friction with tangential multipliers (friction.py).

With R_k = y_k − proj(P̄_k a_k), a = y + c U, bound b_k = μ ẑ_k, the generalised derivatives
(T = −∂proj/∂(P̄ a): −I sticking, −b/|P̄a| (I − t̂t̂ᵀ) slipping, 0 without pressure; g = ∂R/∂b =
−t̂ slipping, 0 while the bounds are held):

    ∂R/∂y = I + T P̄,   ∂R/∂U = c T P̄,   ∂R/∂n̄ = −T ((n̄·a) I + n̄ aᵀ),   ∂n̄/∂m = P̄ / |m|,
    ∂R_k/∂z_j = μ g_k ∂ẑ_k/∂z_j,   ∂ẑ_k/∂z_j = A_k Σ_p Φ_kp ω'_p [p_p > 0] Φ_jp / w_p (per segment),
    ∂U_k/∂q = Σ_p Φ_kp ω'_p (P_p ∇d_p + D_p ∇n_p),   D = −(n·Δd) I − n Δdᵀ,   ∂m_k/∂q = Σ_p Φ_kp ω'_p ∇n_p,

and of the forces f_p = k_s ω'_p P_p Y_p (Y_p = Σ_k Φ_kp y_k) on (A, partner) through ∇dᵀ:
∂f/∂y_k = k_s ω'_p Φ_kp P_p and ∂f/∂n = k_s ω'_p (−(n·Y) I − n Yᵀ).  ∇n_p (gap.normal_gradient)
runs over A's element and the B element of the closest point.  The rows of y carry k_s.
"""
from __future__ import annotations

import numpy as np

from .blocks import fade_derivatives
from .gap import normal_gradient
from .partners import drop_held, node_dofs, pair_products, segment_outer, tangential

EYE = np.eye(3)


def _points(term, c, st):
    """Per local point: its segment row, the local index of each of its segment's functions
    (P, K), the tangential functions' Φ_kp ω'_p, the pressure's Φ_kp (P, K; 0 for a missing
    function); each segment's local indices."""
    pts, sp, idx = c.points, c.space, c.local
    srow = np.searchsorted(c.segments, pts.seg[idx])
    sm = sp.seg_mults[c.segments]
    real = sm >= 0
    kloc = np.searchsorted(c.mults, np.maximum(sm, 0))
    kloc = np.where(real, np.minimum(kloc, len(c.mults) - 1), 0)
    p_loc = idx - pts.seg_start[pts.seg[idx]]
    phi0 = sp.dense[pts.seg[idx], :, p_loc] * real[srow]
    phit = sp.tdense[pts.seg[idx], :, p_loc] * real[srow]
    return srow, sm, kloc[srow], phit * st.weight[:, None], phi0, kloc, phit


def _weight_columns(term, c, st, srow, sm, kp, phit, A, Bm, NAB) -> tuple[np.ndarray, np.ndarray]:
    """The fade weights' part (``contact.fade: newton``, weights.py) of the (segment, B element)
    blocks, per point the outer product of its two factors (P, 3K + 108) ⊗ (P, 108): rows of y
    then the forces, over A's element and the B element of the closest point.  ω'_p = w_p enters
    U_k, m_k and ẑ_k as Φ_kp w_p (·) and the forces as k_s w_p P_p Y_p, so ∂/∂q through w_p is
    k_s Φ_kp (∂R/∂U u_p + ∂R/∂m n_p + μ g_k A_k [p_p > 0] p_p / k_s) ⊗ ∇w_p on the rows of y and
    k_s N_ABᵀ P_p Y_p ⊗ ∇w_p on the forces (zero off the fade bands)."""
    ev, ks, n = st.terms[term.name], c.stiffness, st.pr.n
    gw = fade_derivatives(c, st).grad                                         # (P, 108)
    u = tangential(ev.du, n)
    bound = c.space.tarea[sm[srow]] * (ev.positive * ev.pressure)[:, None]    # (P, K) A_k p⁺ k_s
    rows = (np.einsum("pkij,pj->pki", A[kp], u) + np.einsum("pkij,pj->pki", Bm[kp], n)
            + term.mu * ev.g[kp] * (bound / ks)[:, :, None])                  # (P, K, 3)
    rows_y = ks * phit[:, :, None] * rows
    forces = ks * (NAB[:, :, None] * tangential(ev.Y, n)[:, None, :])          # (P, 36, 3)
    return np.concatenate([rows_y.reshape(len(n), -1), forces.reshape(len(n), -1)], axis=1), gw


def jacobian_blocks(term, c, st, fixed_mask: np.ndarray) -> list:
    """Blocks (rows, columns, values) of the friction's part of the Jacobian: per local segment
    ∂(rows of y)/∂(A, partner) and ∂(forces)/∂y; per (segment, B element of the closest points)
    the normals' rotation in both; per local multiplier ∂/∂(y, z) of its own rows."""
    if len(c.local) == 0:
        return []
    ev, ks = st.terms[term.name], c.stiffness
    srow, sm, kp, phi, phi0, kseg, phit = _points(term, c, st)
    n_s, K, P = len(c.segments), sm.shape[1], len(c.local)
    n = st.pr.n
    Pn = EYE - n[:, :, None] * n[:, None, :]
    Pbar = EYE - ev.nbar[:, :, None] * ev.nbar[:, None, :]
    A = term.augmentation * ev.T @ Pbar                                      # ∂R/∂U (M, 3, 3)
    Bm = ev.dRdn @ Pbar / np.where(ev.mnorm > 0.0, ev.mnorm, 1.0)[:, None, None]
    NAB = term.grad_d(c)                                                      # (P, 36)
    rows_y = np.where((sm >= 0)[:, :, None], term.tdof[np.maximum(sm, 0)], -1).reshape(n_s, 3 * K)
    qrows = drop_held(node_dofs(term.segment_nodes(c), term.node_size), fixed_mask)   # (n_s, 108)
    # rows of y through the slips d: Σ_p (k_s Φ ω' ∂R/∂U P_p) ⊗ N_AB
    M1 = ks * phi[:, :, None, None] * (A[kp] @ Pn[:, None])                   # (P, K, 3, 3)
    K1 = segment_outer(srow, n_s, M1.reshape(P, -1), NAB)
    out = [(rows_y, qrows, K1.reshape(n_s, K, 3, 3, -1).transpose(0, 1, 2, 4, 3).reshape(n_s, 3 * K, -1))]
    # the forces through y: Σ_p N_AB ⊗ (k_s Φ ω' P_p); not in a probe (friction held there)
    if not c.law.phase.probe:
        M4 = ks * phi[:, :, None, None] * Pn[:, None]
        K4 = segment_outer(srow, n_s, NAB, M4.reshape(P, -1))
        out.append((qrows, rows_y, K4.reshape(n_s, -1, K, 3, 3).transpose(0, 1, 3, 2, 4).reshape(n_s, -1, 3 * K)))
    # the normals' rotation: rows of y (slips, n̄) and the forces (P_p Y_p)
    gradn = normal_gradient(st.pr)                                            # (P, 3, 108)
    D = -(np.einsum("pi,pi->p", n, ev.du)[:, None, None] * EYE + n[:, :, None] * ev.du[:, None, :])
    M2 = ks * phi[:, :, None, None] * (A[kp] @ D[:, None] + Bm[kp])
    E = ks * st.weight[:, None, None] * -(np.einsum("pi,pi->p", n, ev.Y)[:, None, None] * EYE
                                          + n[:, :, None] * ev.Y[:, None, :])
    # per point L_p ∇n_p (+ the fade weights' outer product), summed per pair as one product
    left = np.concatenate([M2.reshape(P, 3 * K, 3), (NAB[:, :, None, None] * E[:, None]).reshape(P, -1, 3)], axis=1)
    right = gradn
    if c.weights.differentiated:
        lw, gw = _weight_columns(term, c, st, srow, sm, kp, phit, A, Bm, NAB)
        left = np.concatenate([left, lw[:, :, None]], axis=2)
        right = np.concatenate([right, gw[:, None]], axis=1)
    pair, Kn = pair_products(srow, st.pr.eB, left, right)
    cols = node_dofs(np.concatenate([c.conn[c.points.seg_eA[c.segments[pair[:, 0]]]], c.conn[pair[:, 1]]], axis=1),
                     term.node_size)
    rows = np.concatenate([rows_y[pair[:, 0]], qrows[pair[:, 0]]], axis=1)
    out.append((rows, drop_held(cols, fixed_mask), Kn))
    # the bounds μ ẑ_k = μ ∫ φ_k p⁺ dA / k_s of the sliding functions through the pressures z_j
    wp = term.points.w[c.local]
    left = c.space.tarea[sm[srow]] * phi * (ev.positive / wp)[:, None]
    Gz = segment_outer(srow, n_s, left, phi0 * st.rows.load[kp])                 # (n_s, K, K)
    Vz = ks * term.mu * ev.g[kseg][:, :, :, None] * Gz[:, :, None, :]   # (n_s, K, 3, K)
    zcols = np.where(sm >= 0, term.node_size * c.mult_block[np.maximum(sm, 0)] + c.space.slot[np.maximum(sm, 0)], -1)
    out.append((rows_y, zcols, Vz.reshape(n_s, 3 * K, K)))
    # each multiplier's own rows: ∂R/∂y (each rank its share)
    ydof = term.tdof[c.mults]
    out.append((ydof, ydof, ks * ev.share[:, None, None] * (EYE + ev.T @ Pbar)))
    return out
