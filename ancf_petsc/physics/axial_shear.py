"""The axial-shear part of ``locking: ecm``: the ν = 0 law's shear modulus in the planes that
hold the beam axis brought back to the law's own.

ecm integrates the same material at ν = 0 (``poisson_free``: the same small-strain E) over the
section, so the shear strains E_xy, E_xz see μ₀ = E/2 = μ (1 + ν) instead of μ.  The axis
correction Ψ − Ψ₀ puts μ back for a shear that is uniform over the section, but the shear of
torsion grows with the distance from the axis and vanishes on it: a circular neo-Hookean bar at
K/μ = 50 (ν = 0.49) was 49 % too stiff in torsion.  This law,

    Ψ_s = −(c/2) (I5/I4 − I4),   I4 = a·Ca,  I5 = a·C²a,  a = e_x,  c = μ₀ − μ,

(I5/I4 − I4 = |C a|²/I4 − I4, the squared shear of the axial direction: 4 (E_xy² + E_xz²) at
small strain) is added to Ψ₀ over the section and subtracted with it on the axis, so homogeneous
states keep Ψ exactly and the small-strain shear modulus in the axial planes is μ.  The law is
transversely isotropic about the reference axis (the answers do not depend on how the section is
turned in its plane).  Divided by I4, the axis' tilt keeps the modulus μ₀ − c = μ at any
stretch (I5 − I4² alone took c λ² off: Ψ₀ + Ψ_s lost convexity at 1.7x stretch).
"""
from __future__ import annotations

import numpy as np

from .materials import TangentTerms, determinant

__all__ = ["AxialShear", "axial_shear_for"]


def axial_shear_for(material, free) -> "AxialShear | None":
    """The correction for ``material`` beside its ν = 0 law ``free`` (None where they shear alike)."""
    c = float(free.mu - material.mu)
    return AxialShear(c) if c != 0.0 else None


class AxialShear:
    """Ψ_s = −(c/2)(I5/I4 − I4) about a = e_x (module docstring); energy, P and its tangent."""

    name = "axial-shear"

    def __init__(self, c: float):
        self.c = float(c)

    def take(self, rows) -> "AxialShear":
        """The law for a chunk of elements: no per-point data."""
        return self

    def describe(self) -> str:
        return f"axial shear correction c={self.c:.6g} Pa"

    @staticmethod
    def _vectors(F):
        """f = F a, g = C a = Fᵀ f, b = F g, I4 = |f|², I5 = |g|² and a broadcast to the points."""
        f = F[..., :, 0]
        g = np.einsum("...ki,...k->...i", F, f)
        a = np.zeros(f.shape)
        a[..., 0] = 1.0
        dot = lambda u, v: np.einsum("...i,...i->...", u, v)      # noqa: E731
        return f, g, np.einsum("...ij,...j->...i", F, g), dot(f, f), dot(g, g), a

    def energy(self, F: np.ndarray) -> np.ndarray:
        """Ψ_s per point."""
        _, _, _, I4, I5, _ = self._vectors(F)
        return -0.5 * self.c * (I5 / I4 - I4)

    def _stress(self, f, g, b, I4, I5, a):
        """P = −c [(f ⊗ g + b ⊗ a)/I4 − (I5/I4² + 1) f ⊗ a]."""
        dyad = lambda u, v: u[..., :, None] * v[..., None, :]      # noqa: E731
        return -self.c * ((dyad(f, g) + dyad(b, a)) / I4[..., None, None]
                          - (I5 / I4 ** 2 + 1.0)[..., None, None] * dyad(f, a))

    def stress(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """P and det F."""
        return self._stress(*self._vectors(F)), determinant(F)

    def stress_and_tangent(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, TangentTerms]:
        """P, det F and 𝔸 = −c [α (δ_ik (g⊗a + a⊗g)_jl + (f⊗f)_ik δ_jl + Y ⊠ F + F ⊠ Y
        + Σ_m (F_m⊗a) ⊗ (F_m⊗a)) − β δ_ik (a⊗a)_jl − 2/I4² (X ⊗ Y + Y ⊗ X) + 4 I5/I4³ Y ⊗ Y],
        α = 1/I4, β = I5/I4² + 1, X = f⊗g + b⊗a, Y = f⊗a, F_m the m-th column of F."""
        f, g, b, I4, I5, a = self._vectors(F)
        al, be = -self.c / I4, -self.c * (I5 / I4 ** 2 + 1.0)        # −c α, −c β
        dyad = lambda u, v: u[..., :, None] * v[..., None, :]      # noqa: E731
        ga = dyad(g, a)
        iso = al[..., None, None] * (ga + np.swapaxes(ga, -1, -2)) - be[..., None, None] * dyad(a, a)
        k = 2.0 * self.c / I4 ** 2
        # basis: 0 F, 1 Y = f⊗a, 2 f⊗g, 3 b⊗a, 4.. F_m⊗a
        basis = [F, (f, a), (f, g), (b, a)] + [(np.ascontiguousarray(F[..., :, m]), a) for m in range(3)]
        X = [(None, 2), (None, 3)]
        terms = TangentTerms(basis=basis, iso=iso, gram=al[..., None, None] * dyad(f, f),
                             cross=[([(al, 1)], [(None, 0)]), ([(al, 0)], [(None, 1)])],
                             outer=[([(k, 2), (k, 3)], [(None, 1)]), ([(k, 1)], X)],
                             squares=[(al, [(None, 4 + m)]) for m in range(3)]
                             + [(-4.0 * self.c * I5 / I4 ** 3, [(None, 1)])])
        return self._stress(f, g, b, I4, I5, a), determinant(F), terms
