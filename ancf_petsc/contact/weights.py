"""The weights of contact points in the weighted gaps when their partners slide past B's ends.

A point's partner place (ξ_B, t_B) has the weight ``projection.end_weight``: 1 on B's surface and
up to CURVE_OVERHANG beyond the ends of its interface curve, falling smoothly (C², a quintic) to 0
at CURVE_FADE_END, and likewise past B's beam ends.  Two ways to solve with them (``contact.fade``):

* ``newton`` (the default without a tangential law): every evaluation takes the weights
  w_p = w(ζ_p(q)) of its own partner places, inside the weighted gaps ḡ_k = Σ_p Φ_kp w_p g_p
  and the forces, which are their exact variation −Σ_k λ_k ∇ḡ_k (a point in a fade band adds
  −p_p g_p ∇w_p, of the size of its pointwise gap).  The Jacobian is their exact derivative:
  ∇(w g) = w ∇g + g ∇w, and in the stiffness p (∇g ∇wᵀ + ∇w ∇gᵀ + g ∇²w) with
  ∇²w = ζ′ᵀ (∂²w/∂ζ²) ζ′ + ∇²(∂w/∂ζ · ζ) from the closest point's second-order sensitivity
  (gap.closest_point_hessian): Newton on the state and the weights together, symmetric (the
  Hessian of the Lagrangian), so that LDLᵀ and its inertia still apply.
* ``settle`` (the default with contact.tangential, whose laws keep their weights constant in a
  solve): during a Newton solve a point whose weight was 1 at the last update follows its
  partner, and a point partly off keeps the weight it had; between solves the weights are
  brought up to date and the state solved again until none changes by more than ``WEIGHT_TOL``
  (``refresh``): a fixed point, converging linearly.

The forces of a point in a fade band (``contact.fade_forces``, with ``newton``): ``variational``
(the default without a tangential law) as above; ``pointwise``, −Σ_p τ_p ∇g_p (τ_p = p_p w_p,
friction's form): the weights' slope puts no force along B's surface, the constraint rows keep
∇(w g), and the Jacobian (−Σ p ∇g ∇wᵀ in the force rows) is unsymmetric: LU, no inertia, so no
stability check or branch switch.  At large twist a point sliding along a fade band makes a nearly
free direction along which the variational residual changes only through p g ∇w: there Newton
took steps of microns that did not settle (the second subject, 150°, soleus-biased, unilateral,
80.9 N; docs/gait.md), where ``pointwise`` converges (docs/contact.md, "The weights' forces").

Measured on the gait envelope (the paper's outlines, twist 90° and 180°, three loading biases to
1.2 kN; scripts/bench_envelope.py): at large twist the sections of neighbouring subtendons turn
against each other and points near the ends of the interface curves slide up to half the
curve's length past them.  The settled weights then cost 5-10 extra solves per level and did not
settle at all on unilateral columns; the earlier narrow C¹ band (25-30 % of the curve's length)
made Newton cycle (ψ = 180°, soleus-biased: a 2-cycle at 1030 N).  With the band 25-50 % and the
weights differentiated exactly, the sliding columns take 48-66 Newton iterations to 1.2 kN with
no cut-back (72-459 and a failure before).

Before the fade, a point was switched off at once 25 % past the curve's end, and Newton cycled
between two states when one sat there (the bulk-modulus sweep of the paper's sliding columns,
docs/contact.md).
"""
from __future__ import annotations

import numpy as np

from .gap import closest_point_gradient, closest_point_hessian, projection_conditioning
from .fade import end_weight_curvature, end_weight_slope, fade
from .projection import subset, surface_third

#: a change of a point's weight beyond this asks for another Newton solve (a weight off by 1e-6
#: moves a weighted gap by 1e-6 of the point's local gap, ~1e-11 m)
WEIGHT_TOL = 1e-6


#: det H / det a (``gap.projection_conditioning``) from which a point's weight is differentiated
#: whole (``FadeDerivatives``), and below which not at all; in between its ∇w and ∇²w enter with
#: the share ``conditioned``.  Only a partner place near a focal point of B's surface (det H → 0:
#: an early iterate far off the surface) has meaningless derivatives; with the fade at 0.25–0.5
#: (2026-11-29) points at converged states sat in it and the weighted gaps' gradients lacked
#: (1 − s) g ∇w: Newton converged linearly (0.946 per iteration, |F| 1e-6 → 2.5e-7 in 15) and the
#: 165° soleus-biased unilateral column stopped at 2881.9 N (docs/gait.md)
WELL_POSED = 0.1
ILL_POSED = 0.05


def conditioned(kappa: np.ndarray) -> np.ndarray:
    """The share of the weight's derivatives that enters the forces and the Jacobian of a
    point whose projection has the conditioning ``kappa``: 1 from WELL_POSED up, 0 from ILL_POSED
    down, the C² quintic fade in between.  A cut at one threshold made the residual jump: on the
    soleus-biased unilateral stride at twist 90° (frame 46.8) a point 0.52 mm off the end piece of
    its partner's interface curve sat at det H / det a = 0.5, and its −p g ∇w switched a 0.87 N
    force pair on and off between states 5e-13 apart, so that Newton cycled at every increment.
    The share is a constant in the Jacobian (its own derivative, through H's, is left out), and
    the weight itself keeps following its partner place: where the share is below 1, the
    weighted gaps' gradients lack (1 − s) g ∇w and Newton converges only linearly (a weight
    blended as w_kept + s (w − w_kept), with the share's own derivative (w − w_kept) s′ ∇κ added,
    was tried: Newton then cycled at 1600 N in that column).  The Jacobian is exact where the
    share is 1, which the fade at 0.05–0.1 leaves to points near a focal point of B."""
    return fade((WELL_POSED - kappa) / (WELL_POSED - ILL_POSED))


class FadeDerivatives:
    """The fade weights' derivatives at one evaluation of the points of ``pr``: ∇w_p (P, 108 for
    3363: A's then B's element slots × 3, as gap.gap_gradient) of every point and the positions
    of the points in a fade band (``band``), at once; their ∇²w_p (B, 108, 108) =
    ζ′ᵀ (∂²w/∂ζ²) ζ′ + ∇²(∂w/∂ζ · ζ) (gap.closest_point_hessian, exact) on first use
    (``hessians``: the Jacobian's; a residual alone never needs them).  One evaluation serves the
    residual's forces and every segment group of the Jacobian (``of``), instead of one each."""

    def __init__(self, projector, pr, loaded: np.ndarray | None = None):
        itf = projector.points.itf[pr.idx]
        first, last, _ = projector.wrap_bounds(itf)
        self._projector, self._pr, self._itf = projector, pr, itf
        #: the points under pressure (all without ``loaded``): only their ∇²w enter the Jacobian
        #: (−p_p g_p ∇²w_p), so the others' are left zero
        self._loaded = np.ones(len(pr.idx), dtype=bool) if loaded is None else loaded
        self._args = (pr.xiB, pr.tB, projector.t_end[pr.idx], pr.eB == first, pr.eB == last)
        self._slope = end_weight_slope(*self._args)
        # a partner place far off B's surface (an early iterate) is ill-determined (det H → 0): its
        # weight's derivatives there would be large and meaningless, so it counts as kept; between
        # ILL_POSED and WELL_POSED its derivatives enter with the share ``conditioned`` (the
        # conditioning of the sloped points alone: each point's is its own)
        sloped = np.flatnonzero(np.any(self._slope != 0.0, axis=1))
        kappa = projection_conditioning(subset(pr, sloped)) if len(sloped) else np.zeros(0)
        posed = kappa > ILL_POSED
        self.band, self.share = sloped[posed], conditioned(kappa[posed])
        self.grad = np.zeros((len(pr.idx), 6 * pr.NA.shape[1]))     # A's and B's slots × 3
        self._sub = self._dz = self._hess = None
        if len(self.band):
            self._sub = subset(pr, self.band)
            self._dz = closest_point_gradient(self._sub)
            self.grad[self.band] = np.einsum("pa,paj->pj", self._slope[self.band], self._dz)
            if np.any(self.share < 1.0):
                self.grad[self.band] *= self.share[:, None]

    def hessians(self, x_of) -> np.ndarray:
        """∇²w_p (B, 108, 108) of the band's points, zero for those not ``loaded`` (their
        p_p g_p ∇²w_p is zero: 6 of the 14 band points of the unilateral stride's Jacobians);
        ``x_of(elements)``: B's nodal vectors."""
        if self._hess is None:
            self._hess = np.zeros((len(self.band),) + 2 * self.grad.shape[1:])
            on = np.flatnonzero(self._loaded[self.band])
            if len(on):
                band, pr = self.band[on], self._pr
                curv = end_weight_curvature(*(a[band] for a in self._args))
                NBzz, Yzzz = surface_third(self._projector, x_of, self._itf[band], pr.eB[band],
                                           pr.xiB[band], pr.tB[band])
                self._hess[on] = closest_point_hessian(subset(self._sub, on), self._slope[band], NBzz,
                                                       Yzzz, curv) * self.share[on, None, None]
        return self._hess

    def of(self, sel: np.ndarray, x_of=None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """∇w of the points ``sel`` (positions in ``pr``), the positions among them of those in a
        band and, with ``x_of``, their ∇²w."""
        inside = np.zeros(len(self.grad), dtype=bool)
        inside[self.band] = True
        band = np.flatnonzero(inside[sel])
        hess = None if x_of is None else self.hessians(x_of)[np.searchsorted(self.band, sel[band])]
        return self.grad[sel], band, hess


class PointWeights:
    """The last updated weight of every contact point, with its checkpoint.  ``rule`` settle or
    newton (``contact.fade``); ``differentiated``: the evaluations take their partner places' own
    weights, differentiated (newton, from the second solve of an increment on: ``refresh``)."""

    def __init__(self, n_points: int, rule: str = "settle", variational: bool = True):
        self.values = np.ones(n_points)
        self._saved = self.values.copy()
        self.rule = rule
        self.differentiated = False
        #: the normal forces are −Σ_k λ_k ∇ḡ_k, with the weights' part −p g ∇w (``contact.fade_forces:
        #: variational``, the default without a tangential law), or τ_p ∇g_p as settle's
        #: (``pointwise``, the only choice with one; blocks.py)
        self.variational = variational

    @property
    def symmetric(self) -> bool:
        """Whether the weights keep the Jacobian symmetric: their forces are the weighted gaps'
        exact variation, or they are never differentiated (settle)."""
        return self.variational or self.rule == "settle"

    def effective(self, idx: np.ndarray, current: np.ndarray) -> np.ndarray:
        """The weights of the points ``idx`` in an evaluation whose partner places have the
        weights ``current``: differentiated: ``current``; newton's solve from rest: the kept
        ones (constants: the tangent is exact for them, and Newton converges quadratically to the
        kept weights' state, from which the next solve differentiates them); settle: those that
        were whole follow them, the others keep theirs (0 once their partner has left every
        fade band)."""
        if self.differentiated:
            return current
        kept = self.values[idx]
        if self.rule == "newton":
            return kept.copy()
        return np.where(kept < 1.0, kept * (current > 0.0), current)

    def refresh(self, idx: np.ndarray, current: np.ndarray) -> float:
        """Update the points ``idx`` to ``current`` (what the output reports); the largest change
        (0 when the evaluations were differentiated).  With newton, a change beyond
        ``WEIGHT_TOL`` after a solve that kept them (the first from rest, ``begin_increment``)
        makes the next solves differentiate them."""
        change = float(np.max(np.abs(current - self.values[idx]), initial=0.0))
        self.values[idx] = current
        if self.differentiated:
            return 0.0
        if self.rule == "newton" and change > WEIGHT_TOL:
            self.differentiated = True
        return change

    @property
    def kept(self) -> bool:
        """newton's solve from rest: the evaluations keep the weights (``begin_increment``) until
        ``refresh`` finds one changed."""
        return self.rule == "newton" and not self.differentiated

    def set(self, values: np.ndarray) -> None:
        """Weights of a restored state (a restart), also as the checkpoint."""
        self.values = np.asarray(values, dtype=float).copy()
        self._saved = self.values.copy()

    def begin_increment(self, from_rest: bool) -> None:
        """newton: differentiate the weights in the increment's solves, but for the first solve
        from rest, which keeps them (the reference state: its first iterates are far from the
        answer, and points sliding through far extrapolations of B's surface then wreck them:
        from rest on the paper's unilateral tendon at 8 elements, ψ = 45°, the differentiated
        iterates met an inverted element and cost a cut-back and 44 more Newton iterations; kept,
        the level takes 11)."""
        self.differentiated = self.rule == "newton" and not from_rest

    def checkpoint(self) -> None:
        self._saved = self.values.copy()

    def restore(self) -> None:
        self.values = self._saved.copy()
