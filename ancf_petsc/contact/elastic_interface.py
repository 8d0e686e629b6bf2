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

from ..physics.element3363 import DOFS_PER_ELEMENT, SLOTS
from .partners import PartnerTerm, drop_held, node_dofs, per_segment_sum

EL = DOFS_PER_ELEMENT
LEVI_CIVITA = np.zeros((3, 3, 3))
LEVI_CIVITA[0, 1, 2] = LEVI_CIVITA[1, 2, 0] = LEVI_CIVITA[2, 0, 1] = 1.0
LEVI_CIVITA[0, 2, 1] = LEVI_CIVITA[2, 1, 0] = LEVI_CIVITA[1, 0, 2] = -1.0
#: points per batch of the per-point 108 × 108 Hessians (bounds the temporaries' memory)
CHUNK_POINTS = 256


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

    def __init__(self, stiffness: float, model, points, projector):
        super().__init__(model, points, projector)
        self.stiffness = float(stiffness)

    @classmethod
    def from_spec(cls, spec, model, points, projector, reference: float) -> "ElasticMatrix":
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
        s = d - np.einsum("pi,pi->p", n, d)[:, None] * n
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
        grad_c = NAB[:, :, None] * n[:, None, :]
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
        NAB = self.grad_d(c)
        K = np.zeros((len(c.segments), 2 * EL, 2 * EL))
        for start in range(0, len(c.local), CHUNK_POINTS):
            sel = slice(start, start + CHUNK_POINTS)
            H = self._point_hessians(ev, NAB[sel], sel)
            K += per_segment_sum(srow[sel], len(c.segments), H)
        return [(drop_held(node_dofs(self.segment_nodes(c)), fixed_mask), K)]

    def _point_hessians(self, ev: MatrixEvaluation, NAB: np.ndarray, sel) -> np.ndarray:
        """∇²Π of the points ``sel`` (P, 108, 108) over (A's element, the partner's)."""
        Dn, n, d = self._normal_terms(ev, sel)
        p = len(NAB)
        cn = np.einsum("pi,pi->p", n, d)
        grad_c = NAB[:, :, None] * n[:, None, :]                              # (P, 36, 3)
        grad_c[:, SLOTS:] += np.einsum("piaj,pi->paj", Dn, d)
        grad_n = np.zeros((p, 3, 2 * SLOTS, 3))
        grad_n[:, :, SLOTS:] = Dn
        # ∇dᵀ∇d = (N ⊗ N) ⊗ I;  ∇dᵀ∇n: [(a, j), (b, l)] = N_a ∂n_j/∂q_bl
        H = (NAB[:, :, None, None, None] * NAB[:, None, None, :, None]
             * np.eye(3)[None, None, :, None, :])
        cross = NAB[:, :, None, None, None] * grad_n[:, None]                  # (P, a, j, b, l)
        second = cross + cross.transpose(0, 3, 4, 1, 2)
        second[:, SLOTS:, :, SLOTS:, :] += self._d_hessian_n(ev, d, n, Dn, sel)
        H -= grad_c[:, :, :, None, None] * grad_c[:, None, None, :, :] + cn[:, None, None, None, None] * second
        return (self.stiffness * ev.omega[sel])[:, None, None] * H.reshape(p, 2 * EL, 2 * EL)

    def _d_hessian_n(self, ev, d, n, Dn, sel) -> np.ndarray:
        """Σ_i d_i ∂²n_i/∂q_aj∂q_bl over the partner's slots (P, 18, 3, 18, 3), from
        ∂²n = [P ∂²m − ∂_b n (n·∂_a m) − ∂_a n (n·∂_b m) − n (∂_b n·∂_a m)] / |m| and
        ∂²m_i/∂q_aj∂q_bl = ε_ijl (N_a,t N_b,ξ − N_b,t N_a,ξ)."""
        Nz, sign, rho, M = ev.Nz[sel], ev.sign[sel], ev.rho[sel], ev.M[sel]
        Pd = d - np.einsum("pi,pi->p", n, d)[:, None] * n
        A = sign[:, None, None] * (Nz[:, :, None, 1] * Nz[:, None, :, 0] - Nz[:, None, :, 1] * Nz[:, :, None, 0])
        E = np.einsum("ijl,pi->pjl", LEVI_CIVITA, Pd)
        out = A[:, :, None, :, None] * E[:, None, :, None, :]
        g = np.einsum("piaj,pi->paj", Dn, d)                                   # d·∂n/∂q_aj
        h = np.einsum("pi,piaj->paj", n, M)                                    # n·∂m/∂q_aj
        out -= g[:, None, None, :, :] * h[:, :, :, None, None] + g[:, :, :, None, None] * h[:, None, None, :, :]
        out -= np.einsum("p,pibl,piaj->pajbl", np.einsum("pi,pi->p", n, d), Dn, M)
        return out / rho[:, None, None, None, None]

    def describe(self) -> str:
        return f"elastic interface matrix (shear-lag), k_t = {self.stiffness:.4g} Pa/m"
