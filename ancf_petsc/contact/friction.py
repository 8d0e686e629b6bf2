"""Coulomb friction between subtendons: a tangential law (issue 27).

Stick while |σ| < μ p⁺, slip against the slip increment otherwise; p⁺ = max(p, 0) with p the
contact pressure at the point (p = k_s Σ_k z_k Φ_kp / w_p, multipliers.py): a pulled interface,
under the sliding law, carries no friction, and an open one, under the unilateral law, has no
pressure.  The incremental return mapping (Wriggers, Computational Contact Mechanics, 2006, §5.2;
Laursen 2002, §5) from the stress σ₀ and the relative displacement d₀ (partners.py) of the last
accepted increment:

    σ = proj_{|σ| ≤ μ p⁺} (P (σ₀ + k (d − d₀))),   P = I − n nᵀ,

n B's unit normal at the point's current closest point.  Stick is regularised by the stiffness k
per area (a sticking point moves by σ/k).  The virtual work adds ω N_Aᵀ σ on A and −ω N_B(ζ₀)ᵀ σ on
the partner; the Jacobian ω ∇dᵀ (∂σ/∂d ∇d + ∂σ/∂n ∇n + ∂σ/∂p ∂p/∂z) is consistent (the rotation
of the normal with ∇n from gap.normal_gradient) and not symmetric (MUMPS LU).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..physics.element3363 import DOFS_PER_ELEMENT, DOFS_PER_NODE, SLOTS
from .gap import normal_gradient
from .partners import PartnerTerm, drop_held, node_dofs, segment_outer

EL = DOFS_PER_ELEMENT
#: default stick stiffness k: this many times E/h of the softest beam (partners.reference_scale)
STICK_FACTOR = 100.0


@dataclass
class FrictionEvaluation:
    """Friction at the local points: d (P, 3), σ (P, 3) [Pa], ∂σ/∂d, ∂σ/∂n (P, 3, 3), ∂σ/∂p
    (P, 3), stick (P,), the weights ω (P,) [m²] and pressures p (P,) [Pa]."""
    d: np.ndarray
    sigma: np.ndarray
    dsigma_dd: np.ndarray
    dsigma_dn: np.ndarray
    dsigma_dp: np.ndarray
    stick: np.ndarray
    omega: np.ndarray
    pressure: np.ndarray


class CoulombFriction(PartnerTerm):
    """Coulomb friction |σ| ≤ μ p⁺, stick regularised by a stiffness k [Pa/m]."""
    law = "coulomb"
    symmetric = False
    #: per point: the stress σ₀ [Pa] and relative displacement d₀ [m] of the last increment
    history = ("traction", "anchor")
    #: full Newton steps cycle between slip directions from a state with no slip yet (the
    #: paper's tendon at 10 N, mu = 0.1 and 0.3, at every cut-back: the problem is scale-free
    #: there); the backtracking line search on |F| converges, in up to ~25 iterations from rest
    options = {"snes_linesearch_type": "bt", "snes_max_it": "50"}

    def __init__(self, coefficient: float, stick_stiffness: float, model, points, projector):
        super().__init__(model, points, projector)
        self.mu = float(coefficient)
        self.stick_stiffness = float(stick_stiffness)

    @classmethod
    def from_spec(cls, spec, model, points, projector, reference: float) -> "CoulombFriction":
        """From ``contact.tangential`` (``friction`` μ, ``stick_stiffness`` k [Pa/m], by default
        ``STICK_FACTOR`` × ``reference`` = E/h of the softest beam)."""
        k = spec.stick_stiffness if spec.stick_stiffness is not None else STICK_FACTOR * reference
        return cls(spec.friction, k, model, points, projector)

    def evaluate(self, c, st, x_of) -> FrictionEvaluation:
        """The return mapping at the local points of the ``Contact`` c in its evaluation ``st``."""
        idx, k, n = c.local, self.stick_stiffness, st.pr.n
        d = self.relative(c, st, x_of)
        pressure = c.stiffness * (c.Phi.T @ (st.z * st.rows.load)) / self.points.w[idx]
        a = self.state["traction"][idx] + k * (d - self.state["anchor"][idx])
        na = np.einsum("pi,pi->p", n, a)
        trial = a - na[:, None] * n
        size = np.linalg.norm(trial, axis=1)
        bound = self.mu * np.maximum(pressure, 0.0)
        stick = (size <= bound) & (bound > 0.0)
        slide = ~stick & (size > 0.0) & (bound > 0.0)
        direction = np.zeros_like(trial)
        direction[slide] = trial[slide] / size[slide, None]
        sigma = np.where(stick[:, None], trial, bound[:, None] * direction)
        # S = ∂σ/∂σ*: I (stick), μp⁺/|σ*| (I − t̂ t̂ᵀ) (slip), 0 (no pressure)
        ratio = np.where(slide, bound / np.where(slide, size, 1.0), 0.0)
        eye = np.eye(3)[None]
        S = (stick[:, None, None] * eye
             + ratio[:, None, None] * (eye - direction[:, :, None] * direction[:, None, :]))
        P = eye - n[:, :, None] * n[:, None, :]
        dtrial_dn = -(na[:, None, None] * eye + n[:, :, None] * a[:, None, :])  # ∂(P a)/∂n
        return FrictionEvaluation(d=d, sigma=sigma, dsigma_dd=k * S @ P, dsigma_dn=S @ dtrial_dn,
                                  dsigma_dp=self.mu * direction * (pressure > 0.0)[:, None], stick=stick,
                                  omega=self.points.w[idx] * st.weight, pressure=pressure)

    def kept(self, ev: FrictionEvaluation) -> dict:
        """The next increment starts from this state's stresses and relative displacements."""
        return {"traction": ev.sigma, "anchor": ev.d}

    def add_forces(self, c, st, floc: np.ndarray) -> None:
        """ω N_Aᵀ σ on A's DOFs and −ω N_B(ζ₀)ᵀ σ on the partners'."""
        ev = st.terms[self.name]
        force = ev.omega[:, None] * ev.sigma
        self.add_point_forces(c, st, floc, self.grad_d(c)[:, :, None] * force[:, None, :])

    def jacobian_blocks(self, c, st, fixed_mask: np.ndarray) -> list:
        """Dense blocks, rows over A's element and the partner's (108): per local segment
        ∂/∂(A, partner) (square); per segment and B element of the closest points ∂/∂(A, that
        element) through the normal; per segment ∂/∂z through the pressure.  Square blocks are
        (rows, values), the others (rows, columns, values)."""
        if len(c.local) == 0:
            return []
        ev, pts, segs = st.terms[self.name], c.points, c.segments
        srow = np.searchsorted(segs, pts.seg[c.local])
        NAB = self.grad_d(c)                                                  # (P, 36)
        rows = node_dofs(self.segment_nodes(c))                               # (n_s, 108)
        wN = ev.omega[:, None] * NAB
        # Σ_p ω N_a (∂σ/∂d)_ij N_b per segment: one (36·3·3 × P)(P × 36) product
        left = (wN[:, :, None, None] * ev.dsigma_dd[:, None]).reshape(len(NAB), -1)
        Kdd = segment_outer(srow, len(segs), left, NAB)                        # (n_s, [a i j], b)
        Kdd = Kdd.reshape(-1, 2 * SLOTS, 3, 3, 2 * SLOTS).transpose(0, 1, 2, 4, 3).reshape(-1, 2 * EL, 2 * EL)
        out = [(drop_held(rows, fixed_mask), Kdd)]
        # ω (N ⊗ I)ᵀ (∂σ/∂n) ∇n per (segment, B element of the closest point)
        pair, inv = np.unique(np.stack([srow, st.pr.eB], 1), axis=0, return_inverse=True)
        inv = inv.ravel()
        grad = ev.dsigma_dn @ normal_gradient(st.pr)                          # (P, 3, 108)
        blocks = (wN[:, :, None, None] * grad[:, None]).reshape(len(NAB), 2 * EL, 2 * EL)
        order = np.argsort(inv, kind="stable")
        Kdn = np.add.reduceat(blocks[order], np.searchsorted(inv[order], np.arange(len(pair))), axis=0)
        cols = node_dofs(np.concatenate([c.conn[pts.seg_eA[segs[pair[:, 0]]]], c.conn[pair[:, 1]]], axis=1))
        out.append((drop_held(rows[pair[:, 0]], fixed_mask), drop_held(cols, fixed_mask), Kdn))
        out.append(self._pressure_block(c, st, ev, srow, wN, rows, fixed_mask))
        return out

    def _pressure_block(self, c, st, ev, srow, wN, rows, fixed_mask):
        """ω (N ⊗ I)ᵀ (∂σ/∂p) ∂p/∂z_k per segment, ∂p/∂z_k = k_s Φ_kp load_k / w_p, over the
        segment's multiplier nodes (the functions living on it)."""
        pts, sp, idx, segs = c.points, c.space, c.local, c.segments
        m_ids = sp.seg_mults[segs]                                            # (n_s, K)
        real = m_ids >= 0
        load = np.zeros(m_ids.shape)
        load[real] = st.rows.load[np.searchsorted(c.mults, m_ids[real])]
        p_loc = idx - pts.seg_start[pts.seg[idx]]
        col = (c.stiffness / pts.w[idx])[:, None] * sp.dense[pts.seg[idx], :, p_loc] * load[srow]
        G = (wN[:, :, None] * ev.dsigma_dp[:, None, :]).reshape(len(idx), 2 * EL)
        Kz = segment_outer(srow, len(segs), G, col)                            # (n_s, 108, K)
        K = np.zeros((len(segs), 2 * EL, 2 * DOFS_PER_NODE))
        ss, kk = np.nonzero(real)
        second = sp.node[m_ids[ss, kk]] != c.seg_mnodes[segs[ss], 0]
        K[ss, :, DOFS_PER_NODE * second + sp.slot[m_ids[ss, kk]]] = Kz[ss, :, kk]
        return drop_held(rows, fixed_mask), drop_held(node_dofs(c.seg_blocks[segs]), fixed_mask), K

    def couplings(self, c) -> list[np.ndarray]:
        """A's nodes, the partner's, the B elements of the closest points and the multiplier
        nodes of each local segment, all with all."""
        nodes = self.segment_nodes(c)
        srow = np.searchsorted(c.segments, c.points.seg[c.local])
        pair = np.unique(np.stack([srow, c.projected_elements()], 1), axis=0)
        return [np.concatenate([nodes[pair[:, 0]], c.conn[pair[:, 1]], c.seg_blocks[c.segments[pair[:, 0]]]], axis=1)]

    def describe(self) -> str:
        return (f"Coulomb friction, mu = {self.mu:g} (stick regularised by k = "
                f"{self.stick_stiffness:.4g} Pa/m)")
