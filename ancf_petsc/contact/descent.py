"""The closest-point iteration's step and its safeguard (paper eqs. 26–27, made global).

The closest point of x_A on B's surface Y(ζ), ζ = (ξ_B, t_B), minimises φ(ζ) = ½|x_A − Y(ζ)|².
Newton's step solves H dζ = −φ_ζ with φ_ζ = −Y_ζᵀ d and H = Y_ζᵀ Y_ζ − Y_ζζ·d (d = x_A − Y).
H is positive definite near the surface; it is not where the point lies farther from B than B's
radius of curvature on its concave side (a subtendon pulled away from its neighbour, a point past
the neighbour's end).  There the step is damped by a Levenberg shift of max|H| on both diagonal
entries.  That shift mixes units: |Y_t|² ≈ 1 against |Y_ξ|² ≈ 1e-4 m², so it all but freezes ξ,
and a point in a converged state crept 4e-7 in ξ per iteration until the iteration limit
(measured on soft GOH columns: "projection not converged" at an equilibrium).  With ``metric``
the step is Gauss–Newton's there, G dζ = −φ_ζ with the surface metric G = Y_ζᵀ Y_ζ: a descent
direction that does not depend on how ξ and t are scaled, which converges.  The frozen ξ is
kept for the iterates of a Newton solve: wild iterates put points centimetres from B, and
following their true closest points there cost the refined unilateral columns 24 Newton
iterations instead of 17 and made a fixed 100 N increment fail (tests/contact/test_unilateral.py);
``Projector.metric_steps`` asks for Gauss–Newton once a converged solve left a projection
unconverged (``Contact.refresh_weights``), and the state is solved again.

``Backtracking`` keeps φ from rising: a step after which φ lies above the Armijo line of its
start (beyond rounding) is halved and retried from that start, so that no point cycles between
elements or curve pieces (a period-4 cycle with ξ jumps of 1.5–3.9 was measured on the same
columns).  A full Newton step that lowers φ is taken as it is, so converged projections and their
iterates do not change where the step was already good.  A step is cut to one element in ξ; where
cutting ξ alone leaves no descent direction (a Gauss–Newton step 7.9 elements long for a point
7 mm from B, measured on the solver_default_2025 column at 89.5 N: halving it never lowered φ),
the whole step is shortened instead, in the Gauss–Newton steps of ``Projector.metric_steps``
(``keep_direction``; the iterates of a solve keep the cut: shortening there stopped the
optimized_SEE unilateral column at 336.35 N instead of 400 N).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: sufficient decrease of φ (Armijo's constant)
ARMIJO = 1e-4
#: φ may rise by this share of |d|·T (T: B's curve length) from rounding alone
ROUNDING = 1e-12


def newton_step(Yz: np.ndarray, Yzz: np.ndarray, d: np.ndarray, pinned: np.ndarray,
                metric: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Step dζ (P, 2) of the closest-point iteration and φ_ζ (P, 2): Newton's where H is positive
    definite, elsewhere Gauss–Newton's (``metric``) or Levenberg-damped by max|H|; pinned points
    (on a C0 element boundary) move in t only."""
    r = -np.einsum("pik,pi->pk", Yz, d)                                     # φ_ζ
    G = np.einsum("pik,pil->pkl", Yz, Yz)
    H = G - np.einsum("pikl,pi->pkl", Yzz, d)
    det = H[:, 0, 0] * H[:, 1, 1] - H[:, 0, 1] * H[:, 1, 0]
    bad = (det <= 0.0) | (H[:, 0, 0] <= 0.0) | (H[:, 1, 1] <= 0.0)
    if np.any(bad):
        if metric:
            H[bad] = G[bad]
        else:
            shift = np.abs(H[bad]).max(axis=(1, 2))
            H[bad, 0, 0] += shift
            H[bad, 1, 1] += shift
        det = H[:, 0, 0] * H[:, 1, 1] - H[:, 0, 1] * H[:, 1, 0]
    dz = np.empty((len(d), 2))
    with np.errstate(divide="ignore", invalid="ignore"):
        dz[:, 0] = -(H[:, 1, 1] * r[:, 0] - H[:, 0, 1] * r[:, 1]) / det
        dz[:, 1] = -(-H[:, 1, 0] * r[:, 0] + H[:, 0, 0] * r[:, 1]) / det
        dz[pinned, 0] = 0.0
        dz[pinned, 1] = -r[pinned, 1] / H[pinned, 1, 1]
    return dz, r


class Backtracking:
    """Start (e_B, ξ_B, t_B) of every point's current step, φ there, the step and its length α."""

    def __init__(self, eB: np.ndarray, xiB: np.ndarray, tB: np.ndarray, length: np.ndarray,
                 keep_direction: bool = False):
        P = len(eB)
        self.keep_direction = keep_direction    # shorten a cut step that no longer descends
        self.e, self.xi, self.t = eB.copy(), xiB.copy(), tB.copy()
        self.e_back = np.full(P, -1)            # the element of the start before (bounce test)
        self.phi = np.full(P, np.inf)
        self.phi_now = np.full(P, np.inf)         # φ at the points' current places
        self.slack = np.zeros(P)
        self.descent = np.zeros(P)              # φ_ζ·dζ of the step (≤ 0)
        self.dz = np.zeros((P, 2))
        self.alpha = np.ones(P)
        self.length = length

    def worse(self, d: np.ndarray, valid: np.ndarray) -> np.ndarray:
        """Points whose last step raised φ above the Armijo line of its start (beyond rounding)."""
        phi = 0.5 * np.einsum("pi,pi->p", d, d)
        self.phi_now = phi
        return valid & (phi > self.phi + ARMIJO * self.alpha * self.descent + self.slack)

    def accept(self, ok: np.ndarray, eB, xiB, tB, d: np.ndarray, dz: np.ndarray, r: np.ndarray) -> None:
        """Points ``ok`` start a new full step ``dz`` (ξ part limited to one element) from where
        they are; the others halve theirs."""
        self.e_back[ok] = self.e[ok]
        self.e[ok], self.xi[ok], self.t[ok] = eB[ok], xiB[ok], tB[ok]
        self.phi[ok] = self.phi_now[ok]
        self.slack[ok] = ROUNDING * self.length[ok] * (np.linalg.norm(d[ok], axis=1) + ROUNDING * self.length[ok])
        step = np.column_stack([np.clip(dz[ok, 0], -1.0, 1.0), dz[ok, 1]])
        # clipping ξ alone turns the step: where that left no descent direction, the whole step
        # is shortened instead (halving an ascent direction never lowers φ)
        ascent = (np.einsum("pk,pk->p", r[ok], step) >= 0.0) & self.keep_direction
        if np.any(ascent):
            step[ascent] = dz[ok][ascent] / np.maximum(np.abs(dz[ok][ascent, :1]), 1.0)
        self.dz[ok] = step
        self.descent[ok] = np.minimum(np.einsum("pk,pk->p", r[ok], step), 0.0)
        self.alpha[ok] = 1.0
        self.alpha[~ok] *= 0.5

    def trial(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Start + α dζ of every point (before wrapping onto B's elements)."""
        return self.e.copy(), self.xi + self.alpha * self.dz[:, 0], self.t + self.alpha * self.dz[:, 1]

    def restart(self, sel: np.ndarray) -> None:
        """The points ``sel`` were moved off their step (pinned): where they are is a new start."""
        self.phi[sel] = np.inf

    @property
    def full(self) -> np.ndarray:
        """Points taking a whole step (only those may be pinned as bouncing)."""
        return self.alpha == 1.0


@dataclass
class Found:
    """What ``Projector.descend`` found for its points (arrays over them)."""
    eB: np.ndarray
    xiB: np.ndarray
    tB: np.ndarray
    weight: np.ndarray
    valid: np.ndarray
    done: np.ndarray       # converged (or off B: weight 0)
    phi: np.ndarray        # ½|d|² at the last surface evaluation
    Y: np.ndarray
    Yz: np.ndarray
    Yzz: np.ndarray
    NB: np.ndarray
    NBz: np.ndarray

    def take(self, rows: np.ndarray, other: "Found", sel: np.ndarray) -> None:
        """Replace the points ``rows`` by the points ``sel`` of ``other``."""
        for name in self.__dataclass_fields__:
            getattr(self, name)[rows] = getattr(other, name)[sel]
