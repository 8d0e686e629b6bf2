"""``locking: mixed``: the volumetric term on a dilatation projected over the section (issue 26).

The quadratic section field of element 3363 has in-plane strains linear in (y, z), while the axial
stretch of a pretwisted section's material lines grows with ρ² (an untwist lengthens the outer
helices more).  K/2 (J − 1)² at every Gauss point then asks the section to stay isochoric pointwise,
which it cannot: it locks (docs/fibres.md, "3D-solid check").  The remedy is the three-field
Hu–Washizu functional of Simo, Taylor & Pister (1985), condensed per element:

    Π = ∫ [Ψ_iso(F) + Ψ_fibres(F) + U(θ) + p (J − θ)] dV,   U(θ) = K/2 (θ − 1)²,

with θ and p discontinuous between elements and, at each axial Gauss point ("station") of an
element, in span{1, y, z} over the section.  Stationarity in p gives θ = Π_h J (the L2 projection
in the reference volume, per station); in θ, p = Π_h U'(θ) = K (θ − 1).  What remains is an energy
of the displacements alone,

    Π = ∫ [Ψ_iso(F) + Ψ_fibres(F) + K/2 (θ − 1)²] dV,   θ = Φ c,  c = M⁻¹ Σ_p w φ_p J_p,
    M = Σ_p w φ_p φ_pᵀ (block-diagonal over the stations),

so the tangent is symmetric and exact:

    f_a  = Σ_p w P(F, θ) G_a,       P's volumetric part p J F⁻ᵀ, p = K (θ − 1),
    K_ab = Σ_p w G_a · 𝔸(F, θ) · G_b + K b_aᵀ M⁻¹ b_b,   b_ka = Σ_p w φ_k J (F⁻ᵀ G_a),

𝔸(F, θ) the law's tangent with p in place of U'(J) and without the pointwise U''J² F⁻ᵀ ⊗ F⁻ᵀ (the
last term replaces it; ``materials.NeoHookean._volumetric``).  A homogeneous state has J constant,
Π_h J = J, and the law's own stress (the exactness of uniaxial tests).  The ANCF literature uses
the same idea in cruder forms: selective reduced integration and an F-bar with J at one point
(Orzechowski & Frączek 2015, 2017); with {1} instead of {1, y, z} this module is the F-bar of
the mean dilatation per station (``degree`` 0).
"""
from __future__ import annotations

import numpy as np

from .materials import determinant

#: the pressure space's degree in (y, z) per station: {1, y, z} (docs/fibres.md: why not 0 or 2)
PRESSURE_DEGREE = 1


def pressure_basis(yz: np.ndarray, wq: np.ndarray, stations: int, degree: int = PRESSURE_DEGREE) -> np.ndarray:
    """Φ (P, m) or (E, P, m): the monomials of ``degree`` in (y, z) at every Gauss point, one block
    of columns per station (points are axial-major, P = stations × section points), with y, z
    taken from the station's centroid and scaled by √area (M well conditioned).  ``yz`` (P, 2) or
    (E, P, 2), ``wq`` (P,) or (E, P) the section rule's points and weights."""
    *lead, P, _ = yz.shape
    n = P // stations
    pts = yz.reshape(*lead, stations, n, 2)
    w = wq.reshape(*lead, stations, n)
    area = w.sum(axis=-1, keepdims=True)
    s = (pts - (np.sum(w[..., None] * pts, axis=-2, keepdims=True) / area[..., None])) / np.sqrt(area)[..., None]
    y, z = s[..., 0], s[..., 1]
    cols = [np.ones_like(y)] + ([y, z] if degree >= 1 else []) + ([y * y, y * z, z * z] if degree >= 2 else [])
    phi = np.stack(cols, axis=-1)                                  # (..., stations, n, k)
    k = phi.shape[-1]
    out = np.zeros((*lead, stations, n, stations, k))
    for st in range(stations):
        out[..., st, :, st, :] = phi[..., st, :, :]
    return out.reshape(*lead, P, stations * k)


def grouped_basis(yz: np.ndarray, wq: np.ndarray, stations: int, columns) -> np.ndarray:
    """Φ (P, m) of the space spanned per station by sums of the complete quadratic basis's
    columns (1, y, z, y², yz, z²): ``columns`` [[0], [1], [2], [3, 5]] is {1, y, z, y² + z²}."""
    B = pressure_basis(yz, wq, stations, degree=2)
    return np.stack([sum(B[..., 6 * s + k] for k in col) for s in range(stations) for col in columns], -1)


class ProjectedDilatation:
    """A law (neo-Hookean or GOH: a decoupled K/2 (J − 1)²) with its volumetric term on θ = Π_h J.

    ``basis`` Φ (P, m) or (E, P, m) (``pressure_basis``); ``on(w)`` binds the elements' reference
    weights w (E, P) = det J0 × cubature weights, which the projection needs.  The stress functions
    take F (E, P, 3, 3) of the same elements (whole elements: θ couples their points)."""

    def __init__(self, law, basis: np.ndarray, weights: np.ndarray | None = None,
                 Minv: np.ndarray | None = None):
        self.law, self.basis, self.w, self.Minv = law, basis, weights, Minv
        self.K = law.K

    def take(self, rows) -> "ProjectedDilatation":
        """The law for a chunk of elements (its per-element data sliced)."""
        return ProjectedDilatation(self.law.take(rows), self.basis[rows] if self.basis.ndim == 3 else self.basis,
                                   *(None if a is None else a[rows] for a in (self.w, self.Minv)))

    def on(self, w: np.ndarray) -> "ProjectedDilatation":
        """The same law bound to the reference weights w (E, P) of its elements, with the inverse
        of M = Σ_p w φ φᵀ (reference quantities: formed once)."""
        M = np.matmul(np.swapaxes(w[..., None] * self.basis, -1, -2), self.basis)
        return ProjectedDilatation(self.law, self.basis, w, np.linalg.inv(M))

    def describe(self) -> str:
        return self.law.describe() + "; volumetric term on the dilatation projected per station (mixed)"

    @property
    def fibre_exponent(self):
        """The law's k2 Ē² per point (petsc/step_limits.py holds Newton steps to its growth; it was
        off under ``mixed``); an AttributeError for a law without fibres, as the law's own."""
        return self.law.fibre_exponent

    def _projection(self, F: np.ndarray):
        """θ (E, P), J (E, P), Wφ = w Φ (E, P, m) and M⁻¹ (E, m, m)."""
        if self.w is None or self.w.shape != F.shape[:2]:
            raise ValueError("ProjectedDilatation needs the weights of F's elements (ProjectedDilatation.on)")
        J = determinant(F)
        Wphi = self.w[..., None] * self.basis
        c = np.matmul(self.Minv, np.matmul(np.swapaxes(Wphi, -1, -2), J[..., None]))
        return np.matmul(self.basis, c)[..., 0], J, Wphi, self.Minv

    def dilatation(self, F: np.ndarray) -> np.ndarray:
        """θ = Π_h J at the points (E, P)."""
        return self._projection(F)[0]

    def energy(self, F: np.ndarray) -> np.ndarray:
        return self.law.energy(F, self.dilatation(F))

    def stress(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.law.stress(F, self.dilatation(F))

    def stress_and_tangent(self, F: np.ndarray):
        """P, J and the law's pointwise terms at θ, plus K bᵀ M⁻¹ b as a ``projected`` term on the
        law's basis tensor F⁻ᵀ (index 0 of the neo-Hookean matrix's basis)."""
        theta, J, Wphi, Minv = self._projection(F)
        P, J, terms = self.law.stress_and_tangent(F, theta)
        terms.projected.append((self.K * Minv, Wphi * J[..., None], [(None, 0)]))
        return P, J, terms
