"""Closest-point projection of A's contact points onto B's surface (paper eqs. 26–27).

Each point x_A is projected onto B's swept interface surface Y(e_B, ξ_B, t_B) by a safeguarded
Newton iteration on ζ = (ξ_B, t_B) (descent.py), for all points at once, following the point
across B's element boundaries as the bodies slide.  The result is a ``Projection``: the closest
points, the distance vector d = x_A − Y, B's unit outward normal n, the signed gap g = d·n and
the shape-function data the gap derivatives (gap.py) need.  The projection state (e_B, ξ_B, t_B)
of the last evaluation is the starting point of the next; ``checkpoint``/``restore`` keep it
across a cut-back load step.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .control import DescentControl
from .descent import Backtracking, Found
from .fade import END_FADE, curve_limits, end_weight
from .starts import SecondStarts
from .surface import InterfaceCurves, SurfaceKernels, closest_parameter, section_shift, shape_third_on_curve

PROJECTION_TOL = 1e-11                    # closest-point update (in ξ, and in t / curve length)
MAX_ITERATIONS = 40
#: passes in a row a point off B (weight 0) makes before it stops there, or a step leaves it in
#: place (``Projector.descend``; its own count, so the batch does not decide).  Off-B points used
#: to run for as long as the batch's slowest point; waiting for them to stand still made the
#: projection 5x slower (the unilateral 90 deg stride: 0.9 -> 4.9 s of 8.5); with 1 pass the
#: bundle's fixed increments lose a point from its search window (tests/contact/test_unilateral.py)
OFF_B_PASSES = 3
#: a start this close (in ξ) to the boundary it stepped across is on it
EDGE = 1e-9


@dataclass
class Projection:
    """Closest points of the points ``idx`` (arrays over those points)."""
    idx: np.ndarray        # (P,) contact point ids
    eB: np.ndarray         # (P,) B element of the closest point
    xiB: np.ndarray
    tB: np.ndarray
    d: np.ndarray          # (P, 3) x_A − Y
    n: np.ndarray          # (P, 3) B's unit outward normal
    g: np.ndarray          # (P,) signed gap d·n (> 0: apart)
    valid: np.ndarray      # (P,) the point counts (weight > 0)
    weight: np.ndarray     # (P,) the weight of its partner's place: 1 on B's surface, falling to
                           #      0 past its ends (CURVE_OVERHANG ... CURVE_FADE_END, END_FADE)
    NA: np.ndarray         # (P, 18) A's shape functions
    NB: np.ndarray         # (P, 18) B's shape functions at the closest point
    NBz: np.ndarray        # (P, 18, 2) their ζ derivatives
    Yz: np.ndarray         # (P, 3, 2) surface tangents Y_ξ, Y_t
    Yzz: np.ndarray        # (P, 3, 2, 2) second derivatives
    in_window: bool        # every point stayed within its candidate B elements (search_margin)
    converged: bool        # every local Newton iteration converged


class Projector(SecondStarts):
    """Projection state of every contact point and the Newton iteration that updates it."""

    tolerance = PROJECTION_TOL

    def __init__(self, model, interfaces, points, search_margin: float):
        self.model, self.interfaces, self.points = model, interfaces, points
        self.block = model.block                  # the node layout (physics/elements)
        self.search_margin = search_margin
        itf = points.itf
        self.t_end = np.array([interfaces[k].curve_b.t_end for k in itf])
        self.flip = np.array([interfaces[k].flip_b for k in itf], dtype=bool)
        self._shift = [section_shift(i.b) for i in interfaces]
        self._curves = InterfaceCurves([i.curve_b for i in interfaces], self._shift)
        # per interface (indexed by a point's interface): B's first and last element, its curve's length
        self._b_first = np.array([i.b.element_offset for i in interfaces], dtype=np.int64)
        self._b_last = self._b_first + np.array([i.b.n_elements - 1 for i in interfaces], dtype=np.int64)
        self._curve_end = np.array([i.curve_b.t_end for i in interfaces], dtype=float)
        self._kernels = SurfaceKernels(self.block)      # compiled or numpy
        self._control = DescentControl(self, self._kernels.compiled)
        # state (B element, ξ_B, t_B), started at the matching reference point
        self.eB = points.eB0.copy()
        self.xiB = points.xi.copy()
        self.tB = points.t.copy()
        for k, i in enumerate(interfaces):
            if i.curve_b is not i.curve:         # start from the closest point of B's curve
                sel = itf == k
                self.tB[sel] = closest_parameter(i.curve_b, i.curve(points.t[sel]))
        self.lo, self.hi = self.window_range(points.eA, itf)
        self.conn = model.connectivity()          # node ids of every element (set_numbering)
        self.available = np.ones(model.n_elements, dtype=bool)
        self.wanted = np.zeros(0, dtype=np.int64)
        self.missing = False
        #: Gauss–Newton steps where H is indefinite (descent.py), until the next checkpoint
        self.metric_steps = False
        self._saved = None
        self.checkpoint()

    # ------------------------------------------------------------------ search window
    def window_width(self, itf) -> int:
        """Number of B elements a point of one A element may project onto (fixed per interface)."""
        reach = max(1, int(np.ceil(self.search_margin * itf.b.n_elements)))
        return min(2 * reach + 1, itf.b.n_elements)

    def window_range(self, eA: np.ndarray, itf_idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Candidate B elements [lo, hi] for points of A element eA: within the sliding margin."""
        lo, hi = np.empty(len(eA), dtype=np.int64), np.empty(len(eA), dtype=np.int64)
        for k, itf in enumerate(self.interfaces):
            sel = itf_idx == k
            a, b = itf.a, itf.b
            width = self.window_width(itf)
            le = eA[sel] - a.element_offset
            first = np.clip(le - (width - 1) // 2, 0, b.n_elements - width)
            lo[sel] = b.element_offset + first
            hi[sel] = lo[sel] + width - 1
        return lo, hi

    def window_around(self, eB: np.ndarray, itf_idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Candidate B elements [lo, hi] centred on the B elements ``eB``."""
        lo, hi = np.empty(len(eB), dtype=np.int64), np.empty(len(eB), dtype=np.int64)
        for k, itf in enumerate(self.interfaces):
            sel = itf_idx == k
            b = itf.b
            width = self.window_width(itf)
            first = np.clip(eB[sel] - b.element_offset - (width - 1) // 2, 0, b.n_elements - width)
            lo[sel] = b.element_offset + first
            hi[sel] = lo[sel] + width - 1
        return lo, hi

    # ------------------------------------------------------------------ state
    def set_available(self, available: np.ndarray) -> None:
        """Elements whose node blocks are in the rank's local array."""
        self.available = available
        self.wanted = np.zeros(0, dtype=np.int64)
        self.missing = False

    def checkpoint(self) -> None:
        """Remember the projections of a converged state (restored when a step is cut back);
        every point's search window is centred on its partner element there, so that it may
        slide ``search_margin`` of the beam per load step, however far it has slid before."""
        self._saved = (self.eB.copy(), self.xiB.copy(), self.tB.copy())
        self.lo, self.hi = self.window_around(self.eB, self.points.itf)
        self.metric_steps = False

    def restore(self) -> None:
        self.eB, self.xiB, self.tB = (a.copy() for a in self._saved)
        self.metric_steps = False

    def state(self) -> np.ndarray:
        """(P, 3) [e_B, ξ_B, t_B] of every point (for restart files)."""
        return np.column_stack([self.eB, self.xiB, self.tB])

    def weights_of_state(self) -> np.ndarray:
        """The weight of every point's partner place in the projection state."""
        return self.wrap(self.points.itf, self.eB.copy(), self.xiB.copy(), self.tB.copy())[3]

    def set_state(self, state: np.ndarray) -> None:
        self.resume(state)
        self.checkpoint()

    def resume(self, state: np.ndarray) -> None:
        """Back to the places ``state`` (``state()``), keeping ``wanted``: a repeated evaluation."""
        self.eB, self.xiB, self.tB = state[:, 0].astype(np.int64), state[:, 1].copy(), state[:, 2].copy()

    # ------------------------------------------------------------------ surface
    def surface(self, x_of, itf, eB, xiB, tB):
        """B's surface at (e_B, ξ_B, t_B): Y, Y_ζ (P,3,2), Y_ζζ (P,3,2,2), N_B, N_B,ζ, N_B,ζζ.
        ``x_of(elements)`` returns their nodal vectors (E, 18, 3)."""
        S, S1, S2 = self._curves(itf, tB)                       # every interface's curve at once
        NB, NBz, NBzz = self._kernels.shapes(xiB, S, S1, S2)
        Y, Yz, Yzz = self._kernels.surface(x_of(eB), NB, NBz, NBzz)
        return Y, Yz, Yzz, NB, NBz

    def wrap(self, itf, eB, xiB, tB):
        """Move points across B's element boundaries; past B's beam and curve ends the end
        piece continues (up to the fade limits, clamped there): the weight says how far."""
        b_first, b_last, T = self._b_first[itf], self._b_last[itf], self._curve_end[itf]
        shift = np.floor((xiB + 1.0) / 2.0).astype(int)
        shift = np.where(xiB == 1.0, 0, shift)
        e_new = np.minimum(np.maximum(eB + shift, b_first), b_last)
        x = xiB - 2.0 * (e_new - eB)
        x = np.minimum(np.maximum(x, -1.0 - 2.0 * END_FADE), 1.0 + 2.0 * END_FADE)
        t = np.clip(tB, *curve_limits(T))
        eB[:], xiB[:], tB[:] = e_new, x, t
        weight = end_weight(x, t, T, e_new == b_first, e_new == b_last)
        return eB, xiB, tB, weight

    def wrap_bounds(self, itf: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """B's first and last element and its curve's length for points of the interfaces ``itf``
        (what ``wrap`` clamps to)."""
        return self._b_first[itf], self._b_last[itf], self._curve_end[itf]

    def on_surface(self, idx: np.ndarray, eB: np.ndarray, xiB: np.ndarray, tB: np.ndarray) -> np.ndarray:
        """Whether the partner places (e_B, ξ_B, t_B) of the points ``idx`` lie on B's interface
        surface: within its curve and its beam, not on the continued end pieces (``wrap``) where
        a gap is measured to an extrapolated surface."""
        itf, T = self.points.itf[idx], self.t_end[idx]
        past_beam = ((eB == self._b_first[itf]) & (xiB < -1.0)) | ((eB == self._b_last[itf]) & (xiB > 1.0))
        return (tB >= 0.0) & (tB <= T) & ~past_beam

    # ------------------------------------------------------------------ Newton on ζ
    def neighbours(self, idx: np.ndarray) -> np.ndarray:
        """B element across the element boundary within NEIGHBOUR_BAND of each point's partner
        place (the second start of ``project``), −1 where there is none."""
        return self.across(self.points.itf[idx], self.eB[idx], self.xiB[idx])

    def saved_places(self, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(e_B, ξ_B, t_B) of the points ``idx`` at the checkpoint (copies; ``from_checkpoint``)."""
        return tuple(a[idx] for a in self._saved)

    def ask_for(self, elements: np.ndarray) -> None:
        """Record B elements this rank does not hold (the caller exchanges them, projects again)."""
        if len(elements):
            self.missing = True
            self.wanted = np.union1d(self.wanted, elements)

    def project(self, idx: np.ndarray, xA: np.ndarray, x_of) -> Projection:
        """Project the points ``idx`` (positions ``xA``) onto B; updates the state of those points.

        Each point descends from its last partner place, and again across a near element
        boundary (``closest``); a point whose descent ends on the clamp of the curve's
        continuation descends again from its place at the checkpoint (``from_checkpoint``)."""
        itf, T = self.points.itf[idx], self.t_end[idx]
        f = self.closest(itf, T, xA, x_of, self.eB[idx].copy(), self.xiB[idx].copy(), self.tB[idx].copy())
        self.from_checkpoint(idx, xA, x_of, f)
        self.eB[idx], self.xiB[idx], self.tB[idx] = f.eB, f.xiB, f.tB
        in_window = not np.any(outside_window(f.eB, f.xiB, self.lo[idx], self.hi[idx]))
        d = xA - f.Y
        n = np.cross(f.Yz[:, :, 1], f.Yz[:, :, 0])               # outward normal of B
        n /= np.linalg.norm(n, axis=1)[:, None]
        n[self.flip[idx]] *= -1.0
        g = np.einsum("pi,pi->p", d, n)
        return Projection(idx=idx, eB=f.eB, xiB=f.xiB, tB=f.tB, d=d, n=n, g=g, valid=f.valid,
                          weight=f.weight, NA=self.points.NA[idx], NB=f.NB, NBz=f.NBz, Yz=f.Yz,
                          Yzz=f.Yzz, in_window=in_window, converged=bool(np.all(f.done)))

    def descend(self, itf, t_end, xA, x_of, eB, xiB, tB) -> Found:
        """Closest points from the partner places (e_B, ξ_B, t_B): each step Newton's or
        Gauss–Newton's, halved while it raises the distance (descent.py).  A point whose closest
        point sits on a boundary between two B elements makes Newton jump back and forth: it is
        pinned to the boundary and only t is solved for.  A point sliding onto a B element this
        rank does not hold stays at the boundary and the element is recorded in ``wanted`` (the
        caller exchanges it and projects again).  Each point stops when done (after the first pass;
        off B: ``OFF_B_PASSES``), so its place does not depend on the batch (a rank's)."""
        P = len(eB)
        valid, weight = np.ones(P, dtype=bool), np.ones(P)
        ok, stuck_ever = np.zeros(P, dtype=bool), np.zeros(P, dtype=bool)
        tol_t = PROJECTION_TOL * t_end
        pinned, stopped, idle, off = (np.zeros(P, dtype=t) for t in (bool, bool, bool, np.int64))
        search = Backtracking(eB, xiB, tB, t_end, keep_direction=self.metric_steps)
        for it in range(MAX_ITERATIONS):
            Y, Yz, Yzz, NB, NBz = self.surface(x_of, itf, eB, xiB, tB)
            d = xA - Y
            dz, r = self._kernels.step(Yz, Yzz, d, pinned, self.metric_steps)
            # worse: never on the first pass (φ of the start: ∞); a degenerate local problem (wild
            # iterates far from the surface) keeps the point (``stuck_ever``), never accepted
            worse, ok = self._control.assess(search, d, valid, dz, r, PROJECTION_TOL, tol_t, stuck_ever)
            off = np.where(ok & ~valid, off + 1, 0)
            stopped |= ok & (valid | idle | (off > OFF_B_PASSES)) & (it > 0)
            if np.all(stopped):
                break
            place = (eB.copy(), xiB.copy(), tB.copy(), weight.copy())   # advance may overwrite them
            eB, xiB, tB, weight, crossed = self._control.advance(search, itf, eB, xiB, tB, d, dz, r, worse)
            if np.any(crossed):
                pinned |= self._stop_at_boundary(itf, crossed, search, eB, xiB, tB, weight)
            eB[stopped], xiB[stopped], tB[stopped], weight[stopped] = (a[stopped] for a in place)
            valid = weight > 0.0
            miss = ~self.available[eB]
            if np.any(miss):
                self.ask_for(eB[miss])
                xiB[miss] = np.where(eB[miss] > search.e[miss], 1.0, -1.0)
                eB[miss] = search.e[miss]
            bounce = search.full & (eB == search.e_back) & (eB != search.e) & ~pinned & ~stopped
            if np.any(bounce):
                # stay on the element with the lower index, at its ξ = +1 end
                low = np.minimum(eB[bounce], search.e[bounce])
                eB[bounce], xiB[bounce] = low, 1.0
                pinned |= bounce
                search.restart(bounce)
            idle = (eB == place[0]) & (xiB == place[1]) & (tB == place[2])
        return Found(eB=eB, xiB=xiB, tB=tB, weight=weight, valid=valid, done=(ok | stopped) & ~stuck_ever,
                     phi=0.5 * np.einsum("pi,pi->p", d, d), Y=Y, Yz=Yz, Yzz=Yzz, NB=NB, NBz=NBz)

    def _stop_at_boundary(self, itf, crossed, search, eB, xiB, tB, weight) -> np.ndarray:
        """Points ``crossed`` stepped across a B element boundary and found B farther there (a
        ridge of the C0 surface): the next trial stops on that boundary; one that started on it
        already is pinned there (returned), on the lower element at ξ = +1 as a bouncing point
        is.  Halving alone never brings such a start back into its element: measured, 38 of 40
        iterations spent halving from ξ = 1 (solver_default_2025, unilateral, 37 N)."""
        side = np.where(search.dz[:, 0] > 0.0, 1.0, -1.0)
        pin = crossed & (np.abs(search.xi - side) < EDGE)
        cap = crossed & ~pin
        eB[cap], xiB[cap] = search.e[cap], side[cap]
        low = np.minimum(search.e[pin], search.e[pin] + side[pin].astype(np.int64))
        eB[pin], xiB[pin], tB[pin] = low, 1.0, search.t[pin]
        sel = cap | pin
        eB[sel], xiB[sel], tB[sel], weight[sel] = self.wrap(itf[sel], eB[sel], xiB[sel], tB[sel])
        search.restart(pin)
        return pin


def outside_window(eB: np.ndarray, xiB: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Whether each partner place (e_B, ξ_B) lies outside the B elements [lo, hi].  A point on a
    window's end boundary is inside: a point pinned on a boundary is kept on the element with the
    lower index at ξ = +1 (``descend``), which at the window's first boundary is element lo − 1,
    the same place as lo at ξ = −1 (counted as lost, one point pinned there failed the first
    evaluation of the 12-element unilateral stride's first frame at the predicted state)."""
    below = (eB < lo) & ~((eB == lo - 1) & (xiB >= 1.0))
    above = (eB > hi) & ~((eB == hi + 1) & (xiB <= -1.0))
    return below | above


def surface_third(projector: Projector, x_of, itf, eB, xiB, tB) -> tuple[np.ndarray, np.ndarray]:
    """N_B,ζζ (P, 18, 2, 2) and Y_ζζζ (P, 3, 2, 2, 2) of B's surface at (e_B, ξ_B, t_B) (the
    closest point's second-order sensitivity, gap.closest_point_hessian)."""
    P = len(eB)
    S, S1, S2, S3 = (np.zeros((P, 2)) for _ in range(4))
    for k, inter in enumerate(projector.interfaces):
        sel = itf == k
        if not np.any(sel):
            continue
        t, c = tB[sel], inter.curve_b
        S[sel], S1[sel] = c(t) + projector._shift[k], c(t, 1)
        if c.degree >= 2:
            S2[sel] = c(t, 2)
        if c.degree >= 3:
            S3[sel] = c(t, 3)
    NBzz, NBzzz = shape_third_on_curve(xiB, S, S1, S2, S3, projector.block)
    return NBzz, np.einsum("psi,psabc->piabc", x_of(eB), NBzzz)


def subset(pr: Projection, sel: np.ndarray) -> Projection:
    """The points ``sel`` (positions) of a projection."""
    return Projection(idx=pr.idx[sel], eB=pr.eB[sel], xiB=pr.xiB[sel], tB=pr.tB[sel], d=pr.d[sel],
                      n=pr.n[sel], g=pr.g[sel], valid=pr.valid[sel], weight=pr.weight[sel],
                      NA=pr.NA[sel], NB=pr.NB[sel], NBz=pr.NBz[sel],
                      Yz=pr.Yz[sel], Yzz=pr.Yzz[sel], in_window=pr.in_window,
                      converged=pr.converged)
