"""The interfascicular matrix as an elastic shear-lag layer: a tangential law (issue 27).

The layer joins each contact point to its reference partner on B (partners.py) and resists their
tangential relative displacement with a stiffness k_t = G/h per area [Pa/m] (G the matrix's shear
modulus, h its thickness).  Tangential means in B's tangent plane at the partner, which turns
with B's material: n = m/|m|, m = T_t × T_ξ of B's surface at ζ₀ (flipped where B runs its
curve backwards), a function of the partner element's nodal vectors alone.  The energy

    Π = Σ_p ½ k_t ω_p (|d_p|² − (n_p·d_p)²) = Σ_p ½ k_t ω_p |s_p|²,   s = (I − n nᵀ) d,

gives the forces and a symmetric Jacobian (MUMPS LDLᵀ, the stability check) over A's element and
the partner's, with c = n·d and ∇c = ∇dᵀ n + ∇nᵀ d:

    ∇Π_p = k_t ω (∇dᵀ d − c ∇c),   ∇²Π_p = k_t ω (∇dᵀ∇d − ∇c ∇cᵀ − c (∇dᵀ∇n + ∇nᵀ∇d + d·∇²n)).

The normal is left to the normal law (the sliding law holds it; under the unilateral law the
layer neither holds an opening interface shut nor pushes it open).  k_t → 0 is frictionless
sliding, k_t → ∞ the bonded interface.  The interface stress reported is σ = k_t s."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .partners import PartnerTerm, drop_held, node_dofs, segment_outer, tangential

LEVI_CIVITA = np.zeros((3, 3, 3))
LEVI_CIVITA[0, 1, 2] = LEVI_CIVITA[1, 2, 0] = LEVI_CIVITA[2, 0, 1] = 1.0
LEVI_CIVITA[0, 2, 1] = LEVI_CIVITA[2, 1, 0] = LEVI_CIVITA[1, 0, 2] = -1.0


@dataclass
class MatrixEvaluation:
    """The layer at the local points: d (P, 3), σ = k_t s (P, 3), ω (P,), the partner's
    normal n (P, 3), |m| (P,), ∂m/∂q_B (P, 3, 18, 3), the partner's shape derivatives N_ζ
    (P, 18, 2) with the normal's sign (P,), and stick (all True: bonded)."""
    d: np.ndarray
    sigma: np.ndarray
    omega: np.ndarray
    n: np.ndarray
    rho: np.ndarray
    M: np.ndarray
    Nz: np.ndarray
    sign: np.ndarray
    stick: np.ndarray


class ElasticMatrix(PartnerTerm):
    """σ = k_t s: an elastic interlayer of shear modulus G and thickness h, k_t = G / h [Pa/m]."""
    law = "elastic"
    symmetric = True
    couples_beams = True

    def __init__(self, stiffness: float, model, points, projector):
        super().__init__(model, points, projector)
        self.stiffness = float(stiffness)

    @classmethod
    def from_spec(cls, spec, model, points, projector, reference: float,
                  scaling: float = 1.0) -> "ElasticMatrix":
        """From ``contact.tangential`` (``stiffness`` k_t [Pa/m])."""
        return cls(spec.stiffness, model, points, projector)

    def evaluate(self, c, st, x_of) -> MatrixEvaluation:
        """The layer at the local points of the ``Contact`` c in its evaluation ``st``."""
        idx = c.local
        d = self.relative(c, st, x_of)
        qB = x_of(self.eB0[idx])                                              # (P, 18, 3)
        Nz = self.NB0z[idx]                                                   # (P, 18, 2)
        T = np.einsum("pai,pak->pik", qB, Nz)                                 # T_ξ, T_t
        sign = np.where(self.flip[idx], -1.0, 1.0)
        m = sign[:, None] * np.cross(T[:, :, 1], T[:, :, 0])
        rho = np.linalg.norm(m, axis=1)
        n = m / rho[:, None]
        # ∂m_i/∂q_aj = ε_ijk V_ak with V_a = N_a,t T_ξ − N_a,ξ T_t (times the sign)
        V = sign[:, None, None] * (Nz[:, :, 1, None] * T[:, None, :, 0] - Nz[:, :, 0, None] * T[:, None, :, 1])
        M = np.einsum("ijk,pak->piaj", LEVI_CIVITA, V)
        s = tangential(d, n)
        return MatrixEvaluation(d=d, sigma=self.stiffness * s, omega=self.points.w[idx] * st.weight,
                                n=n, rho=rho, M=M, Nz=Nz, sign=sign, stick=np.ones(len(idx), dtype=bool))

    def _normal_terms(self, ev: MatrixEvaluation, sel) -> tuple:
        """∂n/∂q_B (P, 3, 18, 3) and ∇c over (A, partner) (P, 36, 3) of the points ``sel``."""
        n, rho, M, d = ev.n[sel], ev.rho[sel], ev.M[sel], ev.d[sel]
        Pn = np.eye(3)[None] - n[:, :, None] * n[:, None, :]
        Dn = np.einsum("pil,plaj->piaj", Pn, M) / rho[:, None, None, None]
        return Dn, n, d

    def add_forces(self, c, st, floc: np.ndarray) -> None:
        """k_t ω (∇dᵀ d − c ∇c) over A's element and the partner's."""
        ev = st.terms[self.name]
        NAB = self.grad_d(c)                                                  # (P, 36)
        Dn, n, d = self._normal_terms(ev, slice(None))
        cn = np.einsum("pi,pi->p", n, d)
        grad_c, SLOTS = NAB[:, :, None] * n[:, None, :], self.slots
        grad_c[:, SLOTS:] += np.einsum("piaj,pi->paj", Dn, d)
        force = (self.stiffness * ev.omega)[:, None, None] * (NAB[:, :, None] * d[:, None, :]
                                                              - cn[:, None, None] * grad_c)
        self.add_point_forces(c, st, floc, force)

    def jacobian_blocks(self, c, st, fixed_mask: np.ndarray) -> list:
        """One symmetric block per local segment over A's element and the partner's (108)."""
        if len(c.local) == 0:
            return []
        ev = st.terms[self.name]
        srow = np.searchsorted(c.segments, c.points.seg[c.local])
        K = self._segment_hessians(ev, self.grad_d(c), srow, len(c.segments))
        EL = 3 * self.slots
        return [(drop_held(node_dofs(self.segment_nodes(c), self.node_size), fixed_mask), K.reshape(-1, 2 * EL, 2 * EL))]

    def _segment_hessians(self, ev: MatrixEvaluation, NAB: np.ndarray, srow: np.ndarray, n_s: int) -> np.ndarray:
        """Σ_p ∇²Π_p per segment (n_s, 36, 3, 36, 3) over (A's element, the partner's): every
        term a sum of outer products, formed as batched products over the segments' points
        (``segment_outer``), never as a 108 × 108 matrix per point."""
        Dn, n, d = self._normal_terms(ev, slice(None))
        SLOTS = self.slots
        p = len(NAB)
        w = self.stiffness * ev.omega                                          # k_t ω
        cn = np.einsum("pi,pi->p", n, d)
        wc = w * cn
        grad_c = NAB[:, :, None] * n[:, None, :]                              # (P, 36, 3)
        grad_c[:, SLOTS:] += np.einsum("piaj,pi->paj", Dn, d)
        K = np.zeros((n_s, 2 * SLOTS, 3, 2 * SLOTS, 3))
        # ∇dᵀ∇d = (N ⊗ N) ⊗ I
        NN = segment_outer(srow, n_s, w[:, None] * NAB, NAB)
        K += NN[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
        # − ∇c ∇cᵀ
        K -= segment_outer(srow, n_s, w[:, None] * grad_c.reshape(p, -1),
                           grad_c.reshape(p, -1)).reshape(K.shape)
        # − c (∇dᵀ∇n + ∇nᵀ∇d): [(a, j), (b, l)] = N_a ∂n_j/∂q_bl, b over the partner's slots
        cross = segment_outer(srow, n_s, wc[:, None] * NAB, Dn.reshape(p, -1)).reshape(n_s, 2 * SLOTS, 3, SLOTS, 3)
        K[:, :, :, SLOTS:, :] -= cross
        K[:, SLOTS:, :, :, :] -= cross.transpose(0, 3, 4, 1, 2)
        K[:, SLOTS:, :, SLOTS:, :] -= self._segment_d_hessian_n(ev, wc, d, n, Dn, srow, n_s)
        return K

    def _segment_d_hessian_n(self, ev, wc, d, n, Dn, srow, n_s) -> np.ndarray:
        """Σ_p w_p c_p Σ_i d_i ∂²n_i/∂q_aj∂q_bl per segment over the partner's slots
        (n_s, 18, 3, 18, 3), from ∂²n = [P ∂²m − ∂_b n (n·∂_a m) − ∂_a n (n·∂_b m) −
        n (∂_b n·∂_a m)] / |m| and ∂²m_i/∂q_aj∂q_bl = ε_ijl (N_a,t N_b,ξ − N_b,t N_a,ξ)."""
        Nz, sign, rho, M = ev.Nz, ev.sign, ev.rho, ev.M
        SLOTS = self.slots
        p = len(d)
        f = wc / rho
        Pd = d - np.einsum("pi,pi->p", n, d)[:, None] * n
        A = sign[:, None, None] * (Nz[:, :, None, 1] * Nz[:, None, :, 0] - Nz[:, None, :, 1] * Nz[:, :, None, 0])
        E = np.einsum("ijl,pi->pjl", LEVI_CIVITA, Pd)
        out = segment_outer(srow, n_s, f[:, None] * A.reshape(p, -1), E.reshape(p, -1))
        out = out.reshape(n_s, SLOTS, SLOTS, 3, 3).transpose(0, 1, 3, 2, 4)
        g = np.einsum("piaj,pi->paj", Dn, d).reshape(p, -1)                    # d·∂n/∂q_aj
        h = np.einsum("pi,piaj->paj", n, M).reshape(p, -1)                     # n·∂m/∂q_aj
        hg = segment_outer(srow, n_s, f[:, None] * h, g)
        out -= (hg + hg.transpose(0, 2, 1)).reshape(out.shape)
        # Σ_i (n·d) ∂n_i/∂q_bl ∂m_i/∂q_aj: the component i as extra rows of each point
        rows = np.repeat(srow, 3)
        fM = (f * np.einsum("pi,pi->p", n, d))[:, None, None] * M.reshape(p, 3, -1)
        out -= segment_outer(rows, n_s, fM.reshape(3 * p, -1), Dn.reshape(3 * p, -1)).reshape(out.shape)
        return out

    def describe(self) -> str:
        return f"elastic interface matrix (shear-lag), k_t = {self.stiffness:.4g} Pa/m"
