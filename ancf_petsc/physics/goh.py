"""Fibre-reinforced hyperelastic law of Gasser, Ogden & Holzapfel (2006) with a neo-Hookean matrix.

    Ψ = μ/2 (Ī₁ − 3) + K/2 (J − 1)²  +  Σ_families k1/(2 k2) (exp(k2 Ē_i²) − 1)   (Ē_i > 0 only)
    Ē_i = κ (I₁ − 3) + (1 − 3κ)(I4_i − 1) = H_i : C − 1,   H_i = κ I + (1 − 3κ) a0_i ⊗ a0_i,

with C = FᵀF, I4_i = a0_i · C a0_i, a0_i the unit fibre direction of family i in the reference
configuration (one per Gauss point, ``with_directions``) and κ ∈ [0, 1/3] the dispersion (0:
aligned fibres, 1/3: isotropic).  The matrix is the decoupled neo-Hookean of ``materials.py``
(the paper's eqs. 18, 23, 24, μ = 2 c10, K = d).

**The fibre term is not split** into isochoric and volumetric parts: it uses I₁ and I4 of C, not
of C̄ = J^(−2/3) C.  With the split (Ī4), a fibre-reinforced body under hydrostatic stress deforms
as F = λI: Ī₁ = 3, Ī4 = 1, the fibres carry nothing and a sphere stays a sphere whatever k1, and a
load along the fibres changes the volume through the volumetric term alone (Sansour 2008; Vergori
et al. 2013; Annaidh et al. 2013 — the paper's ref. [19]; the remedy used here is Nolan et al.
2014's "modified anisotropic" form).  Unsplit, the fibres resist any stretch along them,
including the one of a dilatation (tests/physics/test_goh.py).

**Fibres carry no compression: the switch is Ē_i > 0**, not I4_i > 1.  With κ > 0, Ē_i can be
positive at I4_i < 1 (the dispersed fibres off-axis are stretched); at the switch Ē = 0 the fibre
stress ψ'(Ē) ∂Ē/∂F = k1 Ē e^(k2Ē²) 2FH vanishes, so stress is continuous (the tangent jumps by
at most 4k1 (FH)⊗(FH), as in any tension-only law).  At Ē = 0 (the reference state) the tangent
is the tension side's: the first Newton step of a pulled tendon then sees the fibres' stiffness
(with the compression side's, zero, it sees only the soft matrix and overshoots).  "Ē = 0" is
|Ē| <= ``E_ROUNDING``: F of the reference state is I only to rounding, and Ē there is ±1e-15, so
an exact test switched the fibres of 40-50 % of the Gauss points off in the first tangent
(docs/fibres.md: with the published soft matrix the first step moved 14-29x too far).  A switch
at I4 = 1 with κ > 0 would make the stress jump by 2k1 κ(I₁ − 3) 2FH, which Newton does not
like.  For κ = 0 both switches agree.

Stress and tangent in the dyadic form of ``materials.TangentTerms`` (δ_ik S_jl, outer products):

    P  = P_matrix + Σ 2ψ'_i F H_i,        ψ' = k1 Ē e^(k2 Ē²),  ψ'' = k1 e^(k2 Ē²)(1 + 2 k2 Ē²)
    𝔸 = 𝔸_matrix + Σ [δ_ik (2ψ'_i H_i)_jl + 4ψ''_i (F H_i) ⊗ (F H_i)]

F H_i = κ F + (1 − 3κ) Fa0_i ⊗ a0_i is never formed as a 3×3 field: the stress adds its two parts,
the tangent's last term is a ``square`` on F and the pair (Fa0, a0), whose product with the
gradients the kernel forms once for both sides.
"""
from __future__ import annotations

import numpy as np

from .materials import NeoHookean, TangentTerms, determinant

#: |Ē| below this is Ē = 0 for the switch's tangent (Ē of the reference state is ±1e-15: rounding)
E_ROUNDING = 1e-12


class GOH:
    """GOH law; ``with_directions`` binds the fibre field a0 (families, ..., 3) to the points.

    ``fibres`` is the recipe of the field (follow, extra_twist_deg, angles_deg; ``fibres.py``).
    The stress functions take F (..., 3, 3) whose leading axes match a0's (or broadcast)."""

    name = "goh"
    volumetric_term = True          # the matrix's K/2 (J − 1)² (``locking: mixed`` projects it)

    def __init__(self, mu: float, bulk_modulus: float, k1: float, k2: float, kappa: float = 0.0,
                 fibres: dict | None = None, directions: np.ndarray | None = None,
                 e_rounding: float = E_ROUNDING):
        self.mu, self.K = float(mu), float(bulk_modulus)
        self.k1, self.k2, self.kappa = float(k1), float(k2), float(kappa)
        self.fibres = dict(fibres or {"follow": "twist", "extra_twist_deg": 0.0, "angles_deg": (0.0,)})
        self.extra_twist_deg = float(self.fibres["extra_twist_deg"])   # numbers for restart checks
        self.follow_axis = float(self.fibres["follow"] == "axis")
        self.matrix = NeoHookean(mu, bulk_modulus)
        self.a0 = None if directions is None else np.asarray(directions, dtype=float)
        #: |Ē| below this is Ē = 0 for the switch's tangent (E_ROUNDING; 0: the exact switch, a
        #: diagnosis of scripts/goh_published_sets.py)
        self.e_rounding = float(e_rounding)

    @property
    def families(self) -> int:
        return len(self.fibres["angles_deg"])

    @property
    def young(self) -> float:
        """Small-strain Young's modulus of the matrix alone: a stretched fibre adds 4 k1 (times
        cos^4 of its angle to the stretch, with kappa = 0) on the tension side, not counted here."""
        return self.matrix.young

    def with_directions(self, a0: np.ndarray) -> "GOH":
        """The same law bound to unit fibre directions a0 (families, ..., 3)."""
        a0 = np.asarray(a0, dtype=float)
        if a0.shape[0] != self.families or a0.shape[-1] != 3:
            raise ValueError(f"fibre directions must be ({self.families}, ..., 3); got {a0.shape}")
        return GOH(self.mu, self.K, self.k1, self.k2, self.kappa, self.fibres, a0, self.e_rounding)

    def take(self, rows) -> "GOH":
        """The law bound to the directions of elements ``rows`` (kernels process elements in chunks)."""
        return self if self.a0 is None else self.with_directions(self.a0[:, rows])

    def poisson_free(self) -> "GOH":
        """Matrix at ν = 0 with the same fibres (``locking: ecm``): the fibre energy cancels in
        the axis correction Ψ − Ψ₀, so it is integrated over the full section."""
        m = self.matrix.poisson_free()
        return GOH(m.mu, m.K, self.k1, self.k2, self.kappa, self.fibres, self.a0, self.e_rounding)

    def describe(self) -> str:
        f = self.fibres
        extra = f", extra twist {f['extra_twist_deg']:g} deg" if f["extra_twist_deg"] else ""
        angles = ", ".join(f"{a:g}" for a in f["angles_deg"])
        return (f"GOH  mu={self.mu:.6g} Pa  K={self.K:.6g} Pa  k1={self.k1:.6g} Pa  k2={self.k2:.6g}  "
                f"kappa={self.kappa:.4g}; fibres follow {f['follow']}{extra}, at {angles} deg "
                f"(I4 not split, tension only)")

    # ------------------------------------------------------------------ fibre kinematics
    def _fibres(self, F: np.ndarray):
        """Per family: a0 (..., 3), Fa0 (..., 3), I4 (...), Ē (...) (0 where off) and the switch."""
        if self.a0 is None:
            raise ValueError("GOH needs fibre directions at the points (GOH.with_directions)")
        c = 1.0 - 3.0 * self.kappa
        I1 = np.einsum("...ij,...ij->...", F, F) if self.kappa else None
        out = []
        for a0 in self.a0:
            if a0.shape != F.shape[:-1]:
                a0 = np.broadcast_to(a0, F.shape[:-1])
            Fa = np.einsum("...ij,...j->...i", F, a0)
            I4 = np.einsum("...i,...i->...", Fa, Fa)
            E = I4 - 1.0 if c == 1.0 else self.kappa * (I1 - 3.0) + c * (I4 - 1.0)
            on = E >= -self.e_rounding     # tangent at Ē = 0: the tension side's (see below)
            out.append((a0, Fa, I4, np.maximum(E, 0.0), on))
        return out

    def _active(self, F: np.ndarray) -> list:
        """``_fibres`` of the laws whose fibres carry stress: none with k1 = 0 ("0 switches the
        fibres off", config/beams.py), where 0 · e^(k2 Ē²) was NaN once the exponential overflowed
        (k2 524.6 at a fibre stretch of 1.47) and the step limit throttled Newton (5x the matrix's
        iterations on the lone soleus)."""
        return self._fibres(F) if self.k1 else []

    def _exp(self, E):
        with np.errstate(over="ignore"):
            return np.exp(self.k2 * E * E)

    def _add_times_FH(self, P: np.ndarray, s: np.ndarray, F: np.ndarray, Fa: np.ndarray,
                      a0: np.ndarray) -> None:
        """P += s F H = s κ F + s (1 − 3κ) Fa0 ⊗ a0 (..., 3, 3), in place, without forming H
        (the dyad as a (3 × 1)(1 × 3) matmul: 2x faster than the broadcast product)."""
        sFa = (s * (1.0 - 3.0 * self.kappa))[..., None] * Fa
        P += np.matmul(sFa[..., :, None], a0[..., None, :])
        if self.kappa:
            P += (s * self.kappa)[..., None, None] * F

    def fibre_exponent(self, F: np.ndarray) -> np.ndarray:
        """k2 Ē² per point, the largest of the families (Ē clipped at 0): the fibres' stiffness
        ψ'' grows like e^(k2 Ē²), and the Newton steps are held to a bounded growth of it
        (petsc/step_limits.py); 0 with k1 = 0 (no fibre stiffness to grow)."""
        if not self.k1:
            return np.zeros(F.shape[:-2])
        return np.max([self.k2 * E * E for _, _, _, E, _ in self._fibres(F)], axis=0)

    def fibre_stretch(self, F: np.ndarray) -> np.ndarray:
        """√I4 of every family (families, ...)."""
        return np.stack([np.sqrt(I4) for _, _, I4, _, _ in self._fibres(F)])

    def energy(self, F: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """Ψ per point (``theta``: the matrix's volumetric term on a dilatation field, physics/mixed.py)."""
        W = self.matrix.energy(F, theta)
        for _, _, _, E, _ in self._active(F):      # expm1: exp(k2Ē²) − 1 cancels for a small k2
            with np.errstate(over="ignore"):
                W = W + self.k1 / (2.0 * self.k2) * np.expm1(self.k2 * E * E)
        return W

    def stress(self, F: np.ndarray, theta: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        P, J = self.matrix.stress(F, theta)
        for a0, Fa, _, E, _ in self._active(F):
            self._add_times_FH(P, 2.0 * self.k1 * E * self._exp(E), F, Fa, a0)
        return P, J

    def fibre_cauchy_stress(self, F: np.ndarray, theta: np.ndarray | None = None,
                            P: np.ndarray | None = None) -> np.ndarray:
        """Cauchy normal stress along each deformed fibre, n·σn with n = Fa0/|Fa0| and σ = PFᵀ/J
        (families, ...): the stress a fibre-aligned cut carries, matrix included (``theta``: the
        matrix's pressure on that dilatation, ``locking: mixed``; ``P``: the model's stress where
        it is not the law's at F: io/vtk.py ``AxialRecovery``)."""
        P = self.stress(F, theta)[0] if P is None else P
        J = determinant(F)
        out = []
        with np.errstate(over="ignore", invalid="ignore"):      # an overflowed fibre term: inf
            sigma = np.matmul(P, np.swapaxes(F, -1, -2)) / J[..., None, None]
            for _, Fa, I4, _, _ in self._fibres(F):
                out.append(np.einsum("...i,...ij,...j->...", Fa, sigma, Fa) / I4)
        return np.stack(out)

    def stress_and_tangent(self, F: np.ndarray, theta: np.ndarray | None = None
                           ) -> tuple[np.ndarray, np.ndarray, TangentTerms]:
        """P and 𝔸 with the matrix's terms plus, per family, with H = κI + (1 − 3κ) a0 ⊗ a0:
        δ_ik 2ψ'H_jl = 2ψ'κ δ_ik δ_jl (added to ``iso``) + 2ψ'(1 − 3κ) δ_ik a0_j a0_l
        (``rank_one``), and 4ψ'' FH ⊗ FH as a ``square`` (the kernel forms FH G_a once), FH =
        κF + (1 − 3κ) Fa0 ⊗ a0 written on the matrix's basis tensor F and the pair
        ((1 − 3κ) Fa0, a0), so neither side needs a 3×3 product."""
        P, J, terms = self.matrix.stress_and_tangent(F, theta)
        k_F = 1
        assert terms.basis[k_F] is F                          # NeoHookean's basis: [F⁻ᵀ, F]
        c = 1.0 - 3.0 * self.kappa
        for a0, Fa, _, E, on in self._active(F):
            ex = self._exp(E)
            d1 = self.k1 * E * ex                              # ψ'
            d2 = np.where(on, self.k1 * ex * (1.0 + 2.0 * self.k2 * E * E), 0.0)   # ψ''
            self._add_times_FH(P, 2.0 * d1, F, Fa, a0)
            if self.kappa:
                terms.iso = terms.iso + 2.0 * self.kappa * d1
            terms.rank_one.append((2.0 * c * d1, a0))
            k = len(terms.basis)
            terms.basis.append((Fa if c == 1.0 else c * Fa, a0))
            terms.squares.append((4.0 * d2, [(self.kappa, k_F), (None, k)] if self.kappa else [(None, k)]))
        return P, J, terms
