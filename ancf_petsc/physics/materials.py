"""Hyperelastic materials (paper §4, eqs. 16–25), batched over points.

Each material gives the strain energy Ψ(F), the first Piola–Kirchhoff stress P = ∂Ψ/∂F and the
tangent 𝔸 = ∂P/∂F.  The tangent is returned as a short sum of dyadic terms (``TangentTerms``)
so that the element kernel can contract it with the shape-function gradients as matrix products
instead of forming the 81-component tensor at every Gauss point:

    𝔸_ijkl = δ_ik S_jl            (``iso``; S a scalar multiple of I or a 3×3 field)
           + Σ δ_ik c a_j a_l     (``rank_one`` pairs (c, a): a scalar times a direction's dyad)
           + B_ik δ_jl            (``gram``)
           + Σ X_ij Y_kl          (``outer`` pairs (X, Y))
           + Σ c T_ij T_kl        (``squares`` (c, T): one tensor on both sides, multiplied with
                                   the gradients once; a fibre's 4ψ'' FH ⊗ FH)
           + Σ U_il V_kj          (``cross`` pairs (U, V))

and one term that couples the points of an element (``projected``, a projected dilatation,
physics/mixed.py): K_ab += Σ_kl b_ka C_kl b_lb with b_ka = Σ_p Q_pk (X G_a)_p.

All arrays are batched over a leading point axis (n, 3, 3).  A basis tensor may be given as a
pair (u, v) of vectors, meaning u ⊗ v (a fibre's F a0 ⊗ a0): the kernel then needs no product.  The paper works with S : δE
(eq. 14); P : δF is the same virtual work.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def det_and_inverse_transpose(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """det F and F⁻ᵀ for a batch of 3×3 matrices by cofactors (no LAPACK call per matrix)."""
    a = F
    cof = np.empty_like(a)
    cof[..., 0, 0] = a[..., 1, 1] * a[..., 2, 2] - a[..., 1, 2] * a[..., 2, 1]
    cof[..., 0, 1] = a[..., 1, 2] * a[..., 2, 0] - a[..., 1, 0] * a[..., 2, 2]
    cof[..., 0, 2] = a[..., 1, 0] * a[..., 2, 1] - a[..., 1, 1] * a[..., 2, 0]
    cof[..., 1, 0] = a[..., 0, 2] * a[..., 2, 1] - a[..., 0, 1] * a[..., 2, 2]
    cof[..., 1, 1] = a[..., 0, 0] * a[..., 2, 2] - a[..., 0, 2] * a[..., 2, 0]
    cof[..., 1, 2] = a[..., 0, 1] * a[..., 2, 0] - a[..., 0, 0] * a[..., 2, 1]
    cof[..., 2, 0] = a[..., 0, 1] * a[..., 1, 2] - a[..., 0, 2] * a[..., 1, 1]
    cof[..., 2, 1] = a[..., 0, 2] * a[..., 1, 0] - a[..., 0, 0] * a[..., 1, 2]
    cof[..., 2, 2] = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
    det = np.einsum("...j,...j->...", a[..., 0, :], cof[..., 0, :])
    with np.errstate(divide="ignore", invalid="ignore"):
        H = cof / det[..., None, None]
    return det, H


def determinant(F: np.ndarray) -> np.ndarray:
    """det F of a batch of 3×3 matrices by the first row's cofactors (no LAPACK call per matrix)."""
    a = F
    return (a[..., 0, 0] * (a[..., 1, 1] * a[..., 2, 2] - a[..., 1, 2] * a[..., 2, 1])
            + a[..., 0, 1] * (a[..., 1, 2] * a[..., 2, 0] - a[..., 1, 0] * a[..., 2, 2])
            + a[..., 0, 2] * (a[..., 1, 0] * a[..., 2, 1] - a[..., 1, 1] * a[..., 2, 0]))


Side = list  # [(coefficient (n,), a number or None, basis index)]: the tensor Σ c_k B_k


@dataclass
class TangentTerms:
    """𝔸 = δ_ik S_jl + B_ik δ_jl + Σ X_ij Y_kl + Σ c T_ij T_kl + Σ U_il V_kj (module docstring),
    and the element-level ``projected`` terms (C (E, m, m), Q (E, P, m), side X).

    X, Y, U, V are linear combinations of a few ``basis`` tensors (e.g. F⁻ᵀ and F), written as
    sides ``[(c, k), ...]`` meaning Σ c B_k (c None = 1), so that the element kernel multiplies
    each basis tensor with the shape-function gradients only once.
    """

    basis: list = field(default_factory=list)            # [(n, 3, 3) or (u (n, 3), v (n, 3))]
    iso: np.ndarray | None = None    # (n,) scalar multiple of I, or (n, 3, 3)
    gram: np.ndarray | None = None   # (n, 3, 3)
    outer: list[tuple[Side, Side]] = field(default_factory=list)
    cross: list[tuple[Side, Side]] = field(default_factory=list)
    squares: list[tuple[np.ndarray, Side]] = field(default_factory=list)             # [(c (n,), T)]
    rank_one: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)   # [(c (n,), a (n, 3))]
    projected: list[tuple[np.ndarray, np.ndarray, Side]] = field(default_factory=list)   # [(C, Q, X)]

    def base(self, k: int) -> np.ndarray:
        """Basis tensor k as a 3×3 field (a pair (u, v) is u ⊗ v)."""
        B = self.basis[k]
        return B[0][..., :, None] * B[1][..., None, :] if isinstance(B, tuple) else B

    def tensor(self, side: Side) -> np.ndarray:
        """The 3×3 field Σ c_k B_k of one side."""
        return sum(B if c is None else np.multiply(np.asarray(c)[..., None, None], B)
                   for c, B in ((c, self.base(k)) for c, k in side))

    def full(self) -> np.ndarray:
        """The 81-component tangent (n, 3, 3, 3, 3) of the pointwise terms; for tests and
        diagnostics only (a ``projected`` term couples points: it has no such form)."""
        if self.projected:
            raise ValueError("a projected term couples the points of an element: no pointwise tangent")
        n = self.base(0).shape[0]
        A = np.zeros((n, 3, 3, 3, 3))
        eye = np.eye(3)
        if self.iso is not None:
            S = self.iso[:, None, None] * eye if self.iso.ndim == 1 else self.iso
            A += np.einsum("ik,njl->nijkl", eye, S)
        for c, a in self.rank_one:
            A += np.einsum("ik,n,nj,nl->nijkl", eye, c, a, a)
        if self.gram is not None:
            A += np.einsum("nik,jl->nijkl", self.gram, eye)
        for X, Y in self.outer:
            A += np.einsum("nij,nkl->nijkl", self.tensor(X), self.tensor(Y))
        for c, T in self.squares:
            T = self.tensor(T)
            A += np.einsum("n,nij,nkl->nijkl", c, T, T)
        for U, V in self.cross:
            A += np.einsum("nil,nkj->nijkl", self.tensor(U), self.tensor(V))
        return A


class NeoHookean:
    """Decoupled compressible neo-Hookean, Ψ = μ/2 (Ī₁ − 3) + K/2 (J − 1)² (eqs. 18, 23, 24).

    The paper writes Ψ_iso = c10 (Ī₁ − 3) and S_vol = d (J − 1) J C⁻¹, i.e. μ = 2 c10 and K = d.
    """

    name = "neo-hookean"
    volumetric_term = True          # a decoupled K/2 (J − 1)² (``locking: mixed`` projects it)

    def __init__(self, mu: float, bulk_modulus: float):
        self.mu = float(mu)
        self.K = float(bulk_modulus)

    @property
    def young(self) -> float:
        """Small-strain Young's modulus E = 9Kμ / (3K + μ)."""
        return 9.0 * self.K * self.mu / (3.0 * self.K + self.mu)

    @property
    def poisson(self) -> float:
        """Small-strain Poisson ratio ν = (3K − 2μ) / (2 (3K + μ))."""
        return (3 * self.K - 2 * self.mu) / (2 * (3 * self.K + self.mu))

    def poisson_free(self) -> "NeoHookean":
        """The same small-strain E with ν = 0 (μ₀ = E/2, K₀ = E/3): used by ``locking: ecm``."""
        E = self.young
        return NeoHookean(0.5 * E, E / 3.0)

    def take(self, rows) -> "NeoHookean":
        """The law for a chunk of elements: an isotropic law has no per-point data."""
        return self

    def describe(self) -> str:
        return (f"neo-Hookean  mu={self.mu:.6g} Pa  K={self.K:.6g} Pa  "
                f"(K/mu={self.K / self.mu:.4g}, small-strain nu={self.poisson:.4f})")

    def _invariants(self, F):
        J, H = det_and_inverse_transpose(F)
        I1 = np.einsum("...ij,...ij->...", F, F)
        with np.errstate(invalid="ignore", divide="ignore"):
            Jm = np.where(J > 0.0, np.abs(J) ** (-2.0 / 3.0), np.nan)
        return J, H, I1, Jm

    def energy(self, F: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """Ψ per point; with ``theta`` the volumetric term is K/2 (θ − 1)² of that dilatation
        field instead of J's (``locking: mixed``, physics/mixed.py)."""
        J, _, I1, Jm = self._invariants(F)
        return 0.5 * self.mu * (Jm * I1 - 3.0) + 0.5 * self.K * ((J if theta is None else theta) - 1.0) ** 2

    def _volumetric(self, J: np.ndarray, theta: np.ndarray | None):
        """(pJ, coefficient of F⁻ᵀ ⊗ F⁻ᵀ, of F⁻ᵀ ⊠ F⁻ᵀ) of the volumetric term: p = U'(J) = K (J − 1)
        with U''J² + pJ on the outer product; with a dilatation field θ, p = K (θ − 1) and no U''
        term (its pointwise part is not there: physics/mixed.py couples the points)."""
        if theta is None:
            pJ = self.K * (J - 1.0) * J
            return pJ, self.K * (2.0 * J - 1.0) * J, -self.K * (J * J - J)
        pJ = self.K * (theta - 1.0) * J
        return pJ, pJ, -pJ

    def stress(self, F: np.ndarray, theta: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """P = μ J^(−2/3) (F − I₁/3 F⁻ᵀ) + p J F⁻ᵀ, p = K (J − 1) (or K (θ − 1)), and J."""
        J, H, I1, Jm = self._invariants(F)
        P = (self.mu * Jm)[..., None, None] * (F - (I1 / 3.0)[..., None, None] * H) \
            + self._volumetric(J, theta)[0][..., None, None] * H
        return P, J

    def stress_and_tangent(self, F: np.ndarray, theta: np.ndarray | None = None
                           ) -> tuple[np.ndarray, np.ndarray, TangentTerms]:
        """P, J and 𝔸 (``theta``: see ``_volumetric``)."""
        J, H, I1, Jm = self._invariants(F)
        muJm = self.mu * Jm
        pJ, c_vol, g_vol = self._volumetric(J, theta)
        P = muJm[..., None, None] * (F - (I1 / 3.0)[..., None, None] * H) + pJ[..., None, None] * H
        c1 = (2.0 / 9.0) * muJm * I1 + c_vol
        c2 = -(2.0 / 3.0) * muJm
        gamma = muJm * I1 / 3.0 + g_vol
        # basis 0 = F⁻ᵀ, 1 = F:  (c1 H + c2 F) ⊗ H + c2 H ⊗ F,  γ H ⊠ H
        terms = TangentTerms(basis=[H, F], iso=muJm,
                             outer=[([(c1, 0), (c2, 1)], [(None, 0)]), ([(c2, 0)], [(None, 1)])],
                             cross=[([(gamma, 0)], [(None, 0)])])
        return P, J, terms


class StVenantKirchhoff:
    """St. Venant–Kirchhoff, Ψ = λ/2 (tr E)² + μ E:E with E = ½(FᵀF − I) (eq. 15); for verification."""

    name = "svk"
    volumetric_term = False         # no decoupled K/2 (J − 1)²: ``locking: mixed`` does not apply

    def __init__(self, E: float, nu: float):
        self.E, self.nu = float(E), float(nu)
        self.lam = E * nu / ((1 + nu) * (1 - 2 * nu))
        self.mu = E / (2 * (1 + nu))

    @property
    def young(self) -> float:
        return self.E

    def poisson_free(self) -> "StVenantKirchhoff":
        """The same E with ν = 0: used by ``locking: ecm``."""
        return StVenantKirchhoff(self.E, 0.0)

    def take(self, rows) -> "StVenantKirchhoff":
        """The law for a chunk of elements: an isotropic law has no per-point data."""
        return self

    def describe(self) -> str:
        return f"St. Venant-Kirchhoff  E={self.E:.6g} Pa  nu={self.nu:.4g}"

    def _green(self, F):
        C = np.matmul(np.swapaxes(F, -1, -2), F)
        return 0.5 * (C - np.eye(3))

    def energy(self, F: np.ndarray) -> np.ndarray:
        E = self._green(F)
        tr = np.trace(E, axis1=-2, axis2=-1)
        return 0.5 * self.lam * tr ** 2 + self.mu * np.einsum("...ij,...ij->...", E, E)

    def _pk2(self, F):
        E = self._green(F)
        tr = np.trace(E, axis1=-2, axis2=-1)
        return self.lam * tr[..., None, None] * np.eye(3) + 2.0 * self.mu * E

    def stress(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        J, _ = det_and_inverse_transpose(F)
        return np.matmul(F, self._pk2(F)), J

    def stress_and_tangent(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, TangentTerms]:
        S = self._pk2(F)
        J, _ = det_and_inverse_transpose(F)
        lam = np.full(F.shape[:-2], self.lam)
        mu = np.full(F.shape[:-2], self.mu)
        terms = TangentTerms(basis=[F], iso=S,
                             gram=self.mu * np.matmul(F, np.swapaxes(F, -1, -2)),
                             outer=[([(lam, 0)], [(None, 0)])],
                             cross=[([(mu, 0)], [(None, 0)])])
        return np.matmul(F, S), J, terms
