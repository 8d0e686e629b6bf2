"""The normal constraints' part of the residual and the Jacobian (eqs. 26-29): the contact forces
τ_p n_p and the constraint rows k_s R_k, and per segment of contact points the gap Hessian term
−Σ τ ∇²g over A's and B's nodes and the constraint rows −k_s Φ ∇g of its multipliers, as dense
blocks with their DOF indices for the assembly layer to insert.

With the fade weights differentiated (``contact.fade: newton``, weights.py) w_p = w(ζ_p(q)): the
constraint rows and the multipliers' columns take ∇ḡ = Φ (w ∇g + g ∇w), the forces
−Σ_p p_p ∇(w_p g_p) (p_p = k_s (Φᵀ z·load)_p) and the stiffness
−Σ_p p_p (w ∇²g + ∇g ∇wᵀ + ∇w ∇gᵀ + g ∇²w): the exact, symmetric Jacobian.  With a tangential
law (``weights.variational`` False) the forces stay settle's −Σ_p τ_p ∇g_p (τ_p = p_p w_p), so a
friction model solves the same equations with either rule: their stiffness −Σ_p p_p (w ∇²g +
∇g ∇wᵀ), the multipliers' columns −k_s Φ w ∇g (unsymmetric, as friction is)."""
from __future__ import annotations

import numpy as np

from .. import native
from . import segment_layout

from .gap import gap_gradient, gap_hessian_core, gap_hessian_factors
from .projection import subset
from .state import ContactState
from .weights import FadeDerivatives


def state_nodes(c, st: ContactState):
    """``x_of(elements)``: the nodal vectors (E, 18, 3) of elements at the evaluated state."""
    return lambda els: st.xl[st.lpos(c.conn[els])].reshape(len(els), c.model.block.slots, 3)


def fade_derivatives(c, st: ContactState) -> FadeDerivatives:
    """The fade weights' derivatives at the evaluation ``st``, computed once for its residual
    and Jacobian (``weights.FadeDerivatives``)."""
    if st.fade is None:
        st.fade = FadeDerivatives(c.projector, st.pr, loaded=st.pressure != 0.0)
    return st.fade


def add_normal_forces(c, st: ContactState, floc: np.ndarray) -> None:
    """Add −τ_p N_A n_p on A, τ_p N_B n_p on B and the constraint rows k_s R_k to the local
    residual ``floc`` of the ``Contact`` c at its evaluation st."""
    pr = st.pr
    DOFS_PER_NODE, EL = c.model.dofs_per_node, c.model.block.dofs_per_element
    traction = st.tau[:, None] * pr.n                                  # τ_p n_p
    module = native.load("contact.blocks_native")
    for e, N, sign in ((c.points.eA[pr.idx], pr.NA, -1.0), (pr.eB, pr.NB, 1.0)):
        pos = st.lpos(c.conn[e])                                          # (P, 3)
        if module is not None and floc.dtype == float and floc.flags.c_contiguous:
            # bitwise the numpy below (contact/blocks_native.pyx)
            module.add_point_forces(floc.reshape(-1), np.ascontiguousarray(pos, dtype=np.int64),
                                    np.ascontiguousarray(N, dtype=float), traction, sign, DOFS_PER_NODE)
            continue
        f = sign * N[:, :, None] * traction[:, None, :]                   # (P, 18, 3)
        dofs = (DOFS_PER_NODE * pos[:, :, None] + np.arange(DOFS_PER_NODE)).ravel()
        floc += np.bincount(dofs, f.reshape(-1), minlength=floc.size)
    if c.weights.differentiated and c.weights.variational:
        # −Σ_p p_p g_p ∇w_p: the weights' part of the contact forces (forces = −Σ_k λ_k ∇ḡ_k)
        fd = fade_derivatives(c, st)
        gw, band = fd.grad, fd.band
        if len(band):
            f = -(st.pressure[band] * pr.g[band])[:, None] * gw[band]
            for half, e in enumerate((c.points.eA[pr.idx[band]], pr.eB[band])):
                pos = st.lpos(c.conn[e])
                dofs = (DOFS_PER_NODE * pos[:, :, None] + np.arange(DOFS_PER_NODE)).ravel()
                floc += np.bincount(dofs, f[:, EL * half:EL * (half + 1)].ravel(), minlength=floc.size)
    # the constraint rows; a function shared with another rank: each adds its own points
    rows = DOFS_PER_NODE * st.lpos(c.mult_block[c.mults]) + c.space.slot[c.mults]
    share = c.Phi @ np.ones(len(pr.g)) if c.sum_over_ranks is not None else 1.0
    floc[rows] += c.stiffness * st.rows.R * share


def jacobian_blocks(c, st: ContactState, fixed_mask: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Dense blocks (rows (n, D) PETSc DOF ids, −1 dropped; values (n, D, D)) of the contact
    part of the Jacobian: one per local segment over its A nodes, the nodes of the B elements
    its points project onto and its multiplier node; segments are batched by the number of
    B elements they span (contact/segment_layout.py).  ``c`` is the ``Contact``, ``st`` its
    evaluation at the state."""
    if len(c.local) == 0:
        return []
    return [_segment_blocks(c, st, lay) for lay in segment_layout.layouts(c, st.pr.eB, fixed_mask)]


def add_point_blocks(K: np.ndarray, seg: np.ndarray, j: np.ndarray, values: np.ndarray,
                     el: int, stride: int) -> None:
    """K[seg_p] += values_p (2 el × 2 el) over each point's unknowns in its segment's block: A's
    element (the block's first ``el``) and its B element j_p (``el`` from el + stride j_p on),
    in the points' order, i.e. exactly what ``np.add.at`` on those indices adds, entry by entry
    in the same order, without its per-entry cost (1 ms for the two fade-band points of the
    Achilles column's Jacobian).  Pass r adds the r-th point of every segment: no segment twice
    in a pass.  (The fade band's terms come compiled, ``_band_blocks``: bitwise this.)"""
    order = np.argsort(seg, kind="stable")
    grouped = seg[order]
    start = np.flatnonzero(np.r_[True, grouped[1:] != grouped[:-1]])
    rank = np.empty(len(seg), dtype=np.int64)
    rank[order] = np.arange(len(seg)) - np.repeat(start, np.diff(np.r_[start, len(seg)]))
    for r in range(int(rank.max(initial=-1)) + 1):
        for jj in np.unique(j[rank == r]):
            p = np.flatnonzero((rank == r) & (j == jj))
            s, v, b = seg[p], values[p], el + stride * int(jj)
            K[s, :el, :el] += v[:, :el, :el]
            K[s, :el, b:b + el] += v[:, :el, el:]
            K[s, b:b + el, :el] += v[:, el:, :el]
            K[s, b:b + el, b:b + el] += v[:, el:, el:]


def add_gap_hessian(K: np.ndarray, sub, tau: np.ndarray, spread, s_loc: np.ndarray, p_loc: np.ndarray,
                    col_b: np.ndarray, P_s: int, Dq: int) -> None:
    """K[s, :Dq, :Dq] += Σ_p τ_p W_p C_p W_pᵀ = −Σ_p τ_p ∇²g_p over each segment's unknowns
    (gap.gap_hessian_factors): point p of ``sub`` is the ``p_loc``-th of segment ``s_loc``, its B
    element's unknowns start at ``col_b``; ``spread`` puts per-point rows in that layout.
    Compiled (contact/blocks_native.pyx: bitwise this numpy code) or numpy."""
    module = native.load("contact.blocks_native")
    if module is not None:
        f = lambda a: np.ascontiguousarray(a, dtype=float)        # noqa: E731
        i = lambda a: np.ascontiguousarray(a, dtype=np.int64)     # noqa: E731
        pushed = np.flatnonzero(tau)              # a point with τ_p = 0 adds nothing: left out
        if len(pushed) < len(tau):
            sub, tau, s_loc, p_loc, col_b = (subset(sub, pushed), tau[pushed], s_loc[pushed],
                                             p_loc[pushed], col_b[pushed])
        Ct = gap_hessian_core(sub) * tau[:, None, None]
        module.add_gap_hessian(K, f(sub.NA), f(sub.NB), f(sub.NBz), f(sub.Yz), f(sub.n), Ct,
                               i(s_loc), i(p_loc), i(col_b), P_s, Dq)
        return
    n_s = len(K)
    W, C = gap_hessian_factors(sub)
    We = spread(W)
    WCe = spread(np.matmul(W, C * tau[:, None, None]))
    K[:, :Dq, :Dq] += np.matmul(WCe.transpose(0, 2, 1, 3).reshape(n_s, Dq, 4 * P_s),
                                We.transpose(0, 1, 3, 2).reshape(n_s, 4 * P_s, Dq))


def _band_blocks(K: np.ndarray, lay: segment_layout.SegmentLayout, band: np.ndarray, pgrad: np.ndarray,
                 gw: np.ndarray, coef: np.ndarray, hess: np.ndarray | None, variational: bool,
                 el: int, stride: int) -> None:
    """The fade band's stiffness per band point (∇w is zero elsewhere) over its 108 unknowns:
    −p_p ∇g ∇wᵀ (forces τ_p ∇g_p), or −p_p (∇g ∇wᵀ + ∇w ∇gᵀ + g_p ∇²w_p) (variational);
    ``pgrad`` = p_p ∇g_p, ``coef`` = p_p g_p.  Compiled (blocks_native.pyx, no temporaries:
    bitwise these values through ``add_point_blocks``) or numpy."""
    module = native.load("contact.blocks_native")
    seg, j = lay.s_loc[band], lay.j[band]
    if module is not None and K.flags.c_contiguous:
        f = lambda a: np.ascontiguousarray(a, dtype=float)        # noqa: E731
        module.add_band_blocks(K, np.ascontiguousarray(seg, dtype=np.int64), np.ascontiguousarray(j, dtype=np.int64),
                               f(pgrad), f(gw), f(coef), f(hess) if variational else np.zeros((0, 0, 0)),
                               el, stride, variational)
        return
    values = -pgrad[:, :, None] * gw[:, None, :]
    if variational:
        values = values + values.transpose(0, 2, 1) - coef[:, None, None] * hess
    add_point_blocks(K, seg, j, values, el, stride)


def _segment_blocks(c, st: ContactState, lay: segment_layout.SegmentLayout):
    """The block rows and values (n_s, D, D) of the segments of the layout ``lay``."""
    pr, sel, spread, Dq = st.pr, lay.sel, lay.spread, lay.Dq
    DOFS_PER_NODE, EL = c.model.dofs_per_node, c.model.block.dofs_per_element
    k = c.model.block.axial_nodes - 1                   # an element's last node
    sub = subset(pr, sel)
    grad = gap_gradient(sub)
    V = spread(grad * st.weight[sel][:, None])           # ∇(w_p g_p) at fixed w: w_p ∇g_p
    K = np.zeros((lay.n_s, lay.D, lay.D))
    Vg = V
    if c.weights.differentiated:
        nodes = state_nodes(c, st) if c.weights.variational else None     # ∇²w: variational only
        gw, band, hess = fade_derivatives(c, st).of(sel, nodes)
        if len(band):
            Vg = V + spread(sub.g[:, None] * gw)            # ∇(w_p g_p) with w = w(ζ(q))
            p_b = st.pressure[sel][band]
            on = np.flatnonzero(p_b)                         # the others' stiffness is zero
            hess = None if hess is None else hess[on]
            band, p_b = band[on], p_b[on]
            _band_blocks(K, lay, band, grad[band] * p_b[:, None], gw[band], p_b * sub.g[band], hess,
                         c.weights.variational, EL, k * DOFS_PER_NODE)
    tau = st.tau[sel]
    if np.any(tau != 0.0):
        # −Σ_p τ_p ∇²g_p = Σ_p τ_p W_p C_p W_pᵀ, one product per segment
        add_gap_hessian(K, sub, tau, spread, lay.s_loc, lay.p_loc, lay.cols[:, EL], lay.P_s, Dq)
    # constraint rows k_s ∂R/∂ḡ Φ_s ∇g, the multipliers' columns −k_s ω Φ_s ∇g of the forces and
    # the diagonal k_s ∂R/∂z × (the segment's share of the function)
    real, loc, ss, kk, mrow = lay.real, lay.loc, lay.ss, lay.kk, lay.mrow
    dRg, dRz, om = (np.zeros(real.shape) for _ in range(3))
    dRg[real], dRz[real], om[real] = st.rows.dR_dg[loc], st.rows.dR_dz[loc], st.rows.omega[loc]
    Gr = -c.stiffness * np.matmul(lay.Phi_s, Vg)     # (n_s, K, Dq): ∇ḡ = Φ ∇(w g)
    # the multipliers' columns: the forces' −k_s Φ ∇(w g), or Φ w ∇g when they are τ_p ∇g_p
    Gc = Gr if c.weights.variational or Vg is V else -c.stiffness * np.matmul(lay.Phi_s, V)
    K[ss, mrow, :Dq] = -dRg[ss, kk, None] * Gr[ss, kk]
    K[ss, :Dq, mrow] = om[ss, kk, None] * Gc[ss, kk]
    K[ss, mrow, mrow] = c.stiffness * dRz[ss, kk] * lay.share[ss, kk]
    return lay.rows, K
