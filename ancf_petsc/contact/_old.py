"""Surface-to-surface penalty contact between beams over shared interfaces (paper §5, eqs. 26–29).

An interface is a spline curve shared by two beams' section loops (e.g. ``mg_sol`` between the
soleus and the medial gastrocnemius).  Swept along the beams it is a surface on each body.
Quadrature points live on body A's surface: axial Gauss points of every A element × Gauss points
on every polynomial piece of the curve, weighted by the reference area element |X_ξ × X_t|.
Each point x_A is projected onto B's surface, Y(e_B, ξ_B, t_B): the closest point, found by
Newton on (ξ_B, t_B) and followed across B's element boundaries as the bodies slide.

With d = x_A − Y at the closest point, d is normal to B (d = g n), so the penalty energy of the
paper, Π_con = p_n/2 ∫ g² dA (eq. 28 gives its variation), is

    Π_con = Σ_points  p_n w / 2 · |d|².

Modes: ``sliding`` (the paper's: the normal gap held at zero, free tangential sliding, no
friction: every point active) and ``unilateral`` (g ≥ 0: a point is active only while it
penetrates, d · n_B < 0).  With ζ = (ξ_B, t_B) eliminated by the projection condition, the
gradient is p_n w Dᵀd (D = ∂d/∂q at fixed ζ) and the consistent Hessian is

    p_n w [DᵀD − φ_qζ φ_ζζ⁻¹ φ_ζq],   φ(q, ζ) = ½|x_A(q) − Y(q, ζ)|²,

which needs no derivative of the normal and makes Newton converge quadratically.
The interface must be conforming in the reference configuration (both beams with the same
element count along the shared length), so that every reference gap is zero.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from . import element3363 as el
from .config import ConfigError, ContactSpec
from .cubature import gauss_legendre
from .model import Beam, Model

DDL = np.array([1.0, -2.0, 1.0])          # second ξ-derivatives of the Lagrange polynomials
CURVE_OVERHANG = 0.25                     # fraction of an interface curve it is extended by
PROJECTION_TOL = 1e-11                    # closest-point update (in ξ, and in t / curve length)


@dataclass
class Interface:
    name: str
    a: Beam
    b: Beam
    curve: object          # the SplineCurve on A carrying the points (shared interfaces: also B's)
    flip_b: bool           # B traverses curve_b backwards in its CCW loop (normal sign)
    curve_b: object = None # the SplineCurve on B (defaults to the shared curve)
    n_points: int = 0

    def __post_init__(self):
        if self.curve_b is None:
            self.curve_b = self.curve


def _section_shift(beam: Beam) -> np.ndarray:
    """Add to a base-curve point (tendon frame, before offset) to get beam section coordinates."""
    sec = beam.section
    offset = np.asarray(sec.shape_params.get("offset", (0.0, 0.0)), dtype=float)
    return offset - sec.centroid


def curve_shape(beam: Beam, curve, xi: np.ndarray, t: np.ndarray, second: bool = False):
    """Shape functions of a beam on its interface surface (ξ, S(t)) and their ζ = (ξ, t) derivatives.

    Returns N (P, 18), Nz (P, 18, 2) and, with ``second``, Nzz (P, 18, 2, 2).
    """
    S = curve(t) + _section_shift(beam)
    S1 = curve(t, 1)
    S2 = (curve(t, 2) if curve.degree >= 2 else np.zeros_like(S1)) if second else None
    return shape_on_curve(xi, S, S1, S2)


def shape_on_curve(xi, S, S1, S2=None):
    """N, N_ζ (and N_ζζ if S2 given) at section points S(t) with derivatives S1, S2 w.r.t. t."""
    L, dL = el.lagrange(xi)
    m, my, mz = el.section_monomials(S[:, 0], S[:, 1])
    mt = my * S1[:, :1] + mz * S1[:, 1:]
    P = len(xi)
    N = (L[:, :, None] * m[:, None, :]).reshape(P, 18)
    Nz = np.stack([(dL[:, :, None] * m[:, None, :]).reshape(P, 18),
                   (L[:, :, None] * mt[:, None, :]).reshape(P, 18)], axis=-1)
    if S2 is None:
        return N, Nz
    mtt = my * S2[:, :1] + mz * S2[:, 1:]
    mtt[:, 3] += S1[:, 0] ** 2                 # (y²/2)'' = y'² + y y''
    mtt[:, 4] += S1[:, 1] ** 2
    mtt[:, 5] += 2.0 * S1[:, 0] * S1[:, 1]     # (yz)'' = 2 y'z' + y''z + y z''
    cross = (dL[:, :, None] * mt[:, None, :]).reshape(P, 18)
    Nzz = np.stack([np.stack([(DDL[None, :, None] * m[:, None, :]).reshape(P, 18), cross], -1),
                    np.stack([cross, (L[:, :, None] * mtt[:, None, :]).reshape(P, 18)], -1)], -2)
    return N, Nz, Nzz


def _closest_parameter(curve, points: np.ndarray, samples: int = 400) -> np.ndarray:
    """Parameter of the closest point of ``curve`` to each point (sampling, then Newton in t)."""
    ts = np.linspace(0.0, curve.t_end, samples)
    P = curve(ts)
    t = ts[np.argmin(np.linalg.norm(points[:, None, :] - P[None], axis=2), axis=1)]
    for _ in range(20):
        d = curve(t) - points
        d1, d2 = curve(t, 1), (curve(t, 2) if curve.degree >= 2 else np.zeros_like(points))
        g = np.einsum("pi,pi->p", d, d1)
        h = np.einsum("pi,pi->p", d1, d1) + np.einsum("pi,pi->p", d, d2)
        t = np.clip(t - g / h, 0.0, curve.t_end)
    return t


def find_interfaces(model: Model, spec: ContactSpec) -> list[Interface]:
    """Interfaces from the config (explicit pairs) or every curve shared by two outlines ('auto')."""
    def shared(a: Beam, b: Beam):
        la, lb = a.section.loop or [], b.section.loop or []
        out = []
        for ca, _ in la:
            for cb, fb in lb:
                if ca is cb:
                    out.append((ca, fb))
        return out

    pairs = []
    if spec.interfaces:
        for k, (ia, ib, cname, cname_b) in enumerate(spec.interfaces):
            a, b = model.beams[ia], model.beams[ib]
            if cname_b is not None:            # two curves: one on each body (non-matching)
                ca = [c for c, _ in (a.section.loop or []) if c.name == cname]
                cb = [(c, f) for c, f in (b.section.loop or []) if c.name == cname_b]
                if not ca or not cb:
                    raise ConfigError(f"contact.interfaces[{k}]", f"no curve {cname!r} in {a.name}'s "
                                      f"outline or {cname_b!r} in {b.name}'s")
                pairs.append((a, b, ca[0], cb[0][1], cb[0][0]))
                continue
            found = [(c, f) for c, f in shared(a, b) if cname is None or c.name == cname]
            if not found:
                raise ConfigError(f"contact.interfaces[{k}]", f"beams {a.name} and {b.name} share no "
                                  "outline curve" + (f" named {cname!r}" if cname else "")
                                  + "; interfaces are curves used by both section outlines")
            pairs += [(a, b, c, f, None) for c, f in found]
    else:
        # the quadrature points go on the body that does not slide out of the interface: a
        # loaded beam is the target (B); otherwise the later beam in the config carries them
        loaded = {ld.beam for ld in model.spec.loads}
        for i, first in enumerate(model.beams):
            for second in model.beams[i + 1:]:
                a, b = second, first
                if first.index not in loaded and second.index in loaded:
                    a, b = first, second
                pairs += [(a, b, c, f, None) for c, f in shared(a, b)]
        if not pairs:
            raise ConfigError("contact", "no two beam outlines share a curve; give the "
                                         "neighbours a common named curve or remove contact")
    out = []
    for a, b, c, fb, cb in pairs:
        if a.n_elements != b.n_elements:
            raise ConfigError("contact", f"interface {c.name}: beams {a.name} ({a.n_elements} "
                              f"elements) and {b.name} ({b.n_elements}) must have the same number "
                              "of elements so that the interface is conforming")
        out.append(Interface(f"{c.name} ({a.name}|{b.name})", a, b, c, fb, cb))
    return out


#: p_n = factor · E / h; the augmented Lagrangian only needs a penalty that keeps Newton's
#: convergence radius large, pure penalty needs one on the plateau (penalty study in the README)
PENALTY_FACTOR = {"augmented": 30.0, "penalty": 1000.0}
SMOOTHING_FACTOR = 1e-3


def default_penalty(interfaces: list[Interface], factor: float) -> float:
    """p_n = factor · E_min / h with E the small-strain Young's modulus of the softer beam and
    h = min(element length, √area) of the two beams [Pa/m]."""
    best = np.inf
    for itf in interfaces:
        for beam in (itf.a, itf.b):
            mat = beam.material
            E = getattr(mat, "E", None)
            if E is None:
                E = 9.0 * mat.K * mat.mu / (3.0 * mat.K + mat.mu)
            h = min(beam.x_nodes[2] - beam.x_nodes[0], np.sqrt(beam.section.area))
            best = min(best, factor * E / h)
    return float(best)


class Contact:
    """Contact points of all interfaces; projections, energy, forces and Hessians."""

    def __init__(self, model: Model, spec: ContactSpec, interfaces: list[Interface]):
        self.model, self.spec, self.interfaces = model, spec, interfaces
        self.mode = spec.mode
        self.augmented = spec.augmented and spec.mode == "sliding" and spec.projection is not None
        factor = PENALTY_FACTOR["augmented" if self.augmented else "penalty"]
        self.penalty = spec.penalty if spec.penalty is not None else default_penalty(interfaces, factor)
        self.penalty *= spec.penalty_scale
        #: unilateral penalty ramp width δ [m]; auto: 1e-3 of the smallest section size
        self.smoothing = (spec.smoothing if spec.smoothing is not None else
                          SMOOTHING_FACTOR * min(np.sqrt(b.section.area) for b in model.beams))
        xa, wa = gauss_legendre(spec.axial_points)
        xc, wc = gauss_legendre(spec.curve_points)
        cols = {k: [] for k in ("itf", "eA", "xi", "t", "w", "eB", "seg")}
        n_seg = 0
        for k, itf in enumerate(interfaces):
            curve, a = itf.curve, itf.a
            bp = curve.breakpoints
            t = (0.5 * (bp[:-1, None] + bp[1:, None]) + 0.5 * np.diff(bp)[:, None] * xc).ravel()
            wt = (0.5 * np.diff(bp)[:, None] * wc).ravel()
            T, XI = np.meshgrid(t, xa)                       # (na, nt)
            WT, WX = np.meshgrid(wt, wa)
            T, XI, W0 = T.ravel(), XI.ravel(), (WT * WX).ravel()
            # the same points (ξ, t) on every element of A: one shape-function evaluation
            _, Nz = curve_shape(a, curve, XI, T)
            q0e = model.q0[a.connectivity].reshape(a.n_elements, 18, 3)
            Xz = np.einsum("pak,eai->epik", Nz, q0e)        # (E, P, 3, 2): X_ξ, X_t
            dA = np.linalg.norm(np.cross(Xz[..., 0], Xz[..., 1]), axis=-1)
            E, P = a.n_elements, len(T)
            elems = np.repeat(np.arange(E), P)
            cols["itf"].append(np.full(E * P, k))
            cols["eA"].append(a.element_offset + elems)
            cols["xi"].append(np.tile(XI, E))
            cols["t"].append(np.tile(T, E))
            cols["w"].append((W0 * dA).ravel())
            cols["eB"].append(itf.b.element_offset + elems)
            cols["seg"].append(n_seg + elems)
            n_seg += E
            itf.n_points = E * P
        self.pts = {k: np.concatenate(v) for k, v in cols.items()}
        self.n_points = len(self.pts["w"])
        # projection state (B element, ξ_B, t_B), started at the matching reference point
        self.eB = self.pts["eB"].copy()
        self.xiB = self.pts["xi"].copy()
        self.tB = self.pts["t"].copy()
        for k, itf in enumerate(interfaces):
            if itf.curve_b is not itf.curve:      # start from the closest point of B's curve
                sel = self.pts["itf"] == k
                self.tB[sel] = _closest_parameter(itf.curve_b, itf.curve(self.pts["t"][sel]))
        self.t_end = np.array([interfaces[k].curve_b.t_end for k in self.pts["itf"]])    # B side
        self.t_end_a = np.array([interfaces[k].curve.t_end for k in self.pts["itf"]])  # A side
        self.NA = np.empty((self.n_points, 18))                  # A side: fixed material points
        for k, itf in enumerate(interfaces):
            sel = self.pts["itf"] == k
            self.NA[sel] = curve_shape(itf.a, itf.curve, self.pts["xi"][sel], self.pts["t"][sel])[0]
        self.n_segments = n_seg
        self.projection = spec.projection if spec.mode == "sliding" else None
        if self.projection is not None:
            self._build_projection()
        self.local = np.arange(self.n_points)
        self._check_reference_gaps()
        self.checkpoint()

    # ---------------------------------------------------------------- layout hooks
    def _window_range(self, eA: np.ndarray, itf_idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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

    def window_width(self, itf: Interface) -> int:
        """Number of B elements a point of one A element may project onto (fixed per interface)."""
        reach = max(1, int(np.ceil(self.spec.search_margin * itf.b.n_elements)))
        return min(2 * reach + 1, itf.b.n_elements)

    def _window(self, eA: np.ndarray, itf_idx: np.ndarray) -> list[np.ndarray]:
        lo, hi = self._window_range(eA, itf_idx)
        return [np.arange(a, b + 1) for a, b in zip(lo, hi)]

    def node_couplings(self, layout, points: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Node-block couplings (PETSc numbering) of the current contact pairs of ``points``
        (default: all): per segment (interface × A element) its A nodes and the nodes of every
        B element its points project onto, all with all (the projected gap couples the points
        of a segment).  Couplings that sliding creates later are added when they first occur
        (``Problem.grow_pattern``)."""
        conn = layout.perm[self.model.connectivity()]
        points = np.arange(self.n_points) if points is None else points
        if len(points) == 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        seg = self.pts["seg"][points]
        seg_b = np.unique(np.stack([seg, self.eB[points]], 1), axis=0)     # sorted by segment
        e_a = self.pts["eA"][np.searchsorted(self.pts["seg"], seg_b[:, 0])]
        # (A element, one B element) of each pair: its 6 nodes, all with all
        six = np.concatenate([conn[e_a], conn[seg_b[:, 1]]], axis=1)
        rows, cols = [np.repeat(six, 6, axis=1).ravel()], [np.tile(six, (1, 6)).ravel()]
        # a segment on several B elements also couples those elements with each other
        first = np.searchsorted(seg_b[:, 0], seg_b[:, 0])
        for i in np.flatnonzero(first != np.arange(len(seg_b))):
            others = conn[seg_b[first[i]:i, 1]].ravel()
            mine = conn[seg_b[i, 1]]
            rows += [np.repeat(mine, len(others)), np.tile(others, 3)]
            cols += [np.tile(others, 3), np.repeat(mine, len(others))]
        return np.concatenate(rows), np.concatenate(cols)

    def setup_layout(self, layout) -> None:
        """Select this rank's points (those on its A elements) and the PETSc node numbering."""
        own = layout.elem_owner[self.pts["eA"]] == layout.rank
        self.local = np.flatnonzero(own)
        self._allowed = self._window_range(self.pts["eA"], self.pts["itf"])
        self._conn = layout.perm[self.model.connectivity()]
        self._avail = np.ones(self.model.n_elements, dtype=bool)
        self._want = np.zeros(0, dtype=np.int64)

    def required_nodes(self) -> np.ndarray:
        """Node blocks (PETSc numbering) of the elements the local points live on (A) and
        currently project onto (B), plus any B element a projection tried to enter but could
        not (it was not exchanged yet).  This is all the contact ever reads from other ranks."""
        idx = self.local
        els = np.concatenate([self.pts["eA"][idx], self.eB[idx], self._want])
        return np.unique(self._conn[els].ravel())

    def set_available(self, needed: np.ndarray) -> None:
        """Record which elements have every node block in the rank's local array ``needed``."""
        self._avail = np.all(np.isin(self._conn, needed), axis=1)
        self._want = np.zeros(0, dtype=np.int64)
        self.missing = False

    missing = False        # a projection wanted an element whose nodes this rank does not hold

    # ---------------------------------------------------------------- kernels
    def _gather(self, xl, lpos, elems):
        return xl[lpos(self._conn[elems])].reshape(len(elems), 18, 3)

    timers = None          # dict of accumulated seconds (set by the Problem)

    _cache = None          # (xl, needed, result) of the last evaluation

    def _evaluate(self, xl: np.ndarray, needed: np.ndarray, hessian: bool):
        """Project the local points; returns everything the energy/force/Hessian need.

        SNES evaluates the Jacobian at the state of the residual before it: the projection of
        that state is reused (the projection state is its result, so nothing else changes)."""
        c = self._cache
        if c is not None and c[1] is needed and np.array_equal(c[0], xl):
            return c[2]
        t0 = time.perf_counter()
        try:
            r = self._evaluate_projection(xl, needed, hessian)
        finally:
            if self.timers is not None:
                self.timers["contact_projection"] += time.perf_counter() - t0
        self._cache = None if self.missing else (xl.copy(), needed, r)
        return r

    def _evaluate_projection(self, xl: np.ndarray, needed: np.ndarray, hessian: bool):
        idx = self.local
        def lpos(nodes):
            return np.searchsorted(needed, nodes)

        itf = self.pts["itf"][idx]
        eA, xiA, tA, w = self.pts["eA"][idx], self.pts["xi"][idx], self.pts["t"][idx], self.pts["w"][idx]
        NA = self.NA[idx]
        xA = np.einsum("pa,pai->pi", NA, self._gather(xl, lpos, eA))
        eB, xiB, tB = self.eB[idx].copy(), self.xiB[idx].copy(), self.tB[idx].copy()
        valid = np.ones(len(idx), dtype=bool)
        ok = True
        self.converged_projection = True
        # Newton on (ξ_B, t_B) for every point at once, element switching along B; the surface
        # quantities of the last evaluation are kept once the update is below rounding
        tol_t = PROJECTION_TOL * self.t_end[idx]
        # A point whose closest point sits on a boundary between two B elements (the surface is
        # only C0 in ξ there) makes Newton jump back and forth: it is pinned to the boundary
        # and only t is solved for.
        pinned = np.zeros(len(idx), dtype=bool)
        e_prev2 = np.full(len(idx), -1)
        e_prev = eB.copy()
        for it in range(40):
            Y, Yz, Yzz, NB, NBz, NBzz = self._surface(xl, lpos, itf, eB, xiB, tB, second=True)
            d = xA - Y
            g = -np.einsum("pik,pi->pk", Yz, d)                                   # φ_ζ
            H = np.einsum("pik,pil->pkl", Yz, Yz) - np.einsum("pikl,pi->pkl", Yzz, d)
            # Levenberg damping where φ_ζζ is not positive definite (far from the surface)
            det = H[:, 0, 0] * H[:, 1, 1] - H[:, 0, 1] * H[:, 1, 0]
            bad_h = (det <= 0.0) | (H[:, 0, 0] <= 0.0) | (H[:, 1, 1] <= 0.0)
            if np.any(bad_h):
                shift = np.abs(H[bad_h]).max(axis=(1, 2))
                H[bad_h, 0, 0] += shift
                H[bad_h, 1, 1] += shift
                det = H[:, 0, 0] * H[:, 1, 1] - H[:, 0, 1] * H[:, 1, 0]
            dz = np.empty((len(idx), 2))
            dz[:, 0] = -(H[:, 1, 1] * g[:, 0] - H[:, 0, 1] * g[:, 1]) / det
            dz[:, 1] = -(-H[:, 1, 0] * g[:, 0] + H[:, 0, 0] * g[:, 1]) / det
            dz[pinned, 0] = 0.0
            with np.errstate(divide="ignore", invalid="ignore"):
                dz[pinned, 1] = -g[pinned, 1] / H[pinned, 1, 1]
            stuck = ~np.all(np.isfinite(dz), axis=1)
            if np.any(stuck):
                # degenerate local problem (only in wild intermediate iterates, far from the
                # surface): keep the point where it is; the step is not accepted unless every
                # projection has converged at the end (``converged_projection``)
                dz[stuck] = 0.0
                self.converged_projection = False
            if it > 0 and np.all((np.abs(dz[:, 0]) < PROJECTION_TOL) & (np.abs(dz[:, 1]) < tol_t) | ~valid):
                break
            dz[:, 0] = np.minimum(np.maximum(dz[:, 0], -1.0), 1.0)
            xiB += dz[:, 0]
            tB += dz[:, 1]
            eB, xiB, tB, valid = self._wrap(itf, eB, xiB, tB)
            miss = ~self._avail[eB]
            if np.any(miss):
                # the point slid onto a B element this rank has not received: remember it, stay
                # at the boundary of the element it came from; the Problem exchanges the missing
                # node blocks and evaluates again (see Problem._exchange)
                self.missing = True
                self._want = np.union1d(self._want, eB[miss])
                xiB[miss] = np.where(eB[miss] > e_prev[miss], 1.0, -1.0)
                eB[miss] = e_prev[miss]
            bounce = (eB == e_prev2) & (eB != e_prev) & ~pinned
            if np.any(bounce):
                # stay on the element with the lower index, at its ξ = +1 end
                low = np.minimum(eB[bounce], e_prev[bounce])
                eB[bounce], xiB[bounce] = low, 1.0
                pinned |= bounce
            e_prev2, e_prev = e_prev, eB.copy()
        else:
            # not fatal in an intermediate Newton iterate: the best point found is used; a load
            # step is only accepted if every projection converged (see ``projections_converged``)
            self.converged_projection = False
        self.eB[idx], self.xiB[idx], self.tB[idx] = eB, xiB, tB
        lo, hi = self._allowed[0][idx], self._allowed[1][idx]
        if np.any((eB < lo) | (eB > hi)):
            ok = False              # slid beyond the candidate window (see search_margin)
        d = xA - Y
        n = np.cross(Yz[:, :, 1], Yz[:, :, 0])                   # outward normal of B
        n /= np.linalg.norm(n, axis=1)[:, None]
        flip = np.array([self.interfaces[k].flip_b for k in itf], dtype=bool)
        n[flip] *= -1.0
        g = np.einsum("pi,pi->p", d, n)
        active = valid.copy()
        if self.mode == "unilateral":
            active &= g < 0.0           # (φ, φ', φ'' vanish for g >= 0 in any case)
        return dict(eA=eA, eB=eB, w=w * active, d=d, n=n, g=g, valid=valid, NA=NA, NB=NB,
                    NBz=NBz, Yz=Yz, Yzz=Yzz, lpos=lpos, ok=ok)

    def _surface(self, xl, lpos, itf, eB, xiB, tB, second):
        """B's surface at (e_B, ξ_B, t_B): Y, Y_ζ (P,3,2), Y_ζζ (P,3,2,2) and the shape functions."""
        P = len(eB)
        S, S1 = np.empty((P, 2)), np.empty((P, 2))
        S2 = np.zeros((P, 2)) if second else None
        for k, inter in enumerate(self.interfaces):          # only the spline evaluations
            sel = itf == k
            if not np.any(sel):
                continue
            t = tB[sel]
            S[sel] = inter.curve_b(t) + _section_shift(inter.b)
            S1[sel] = inter.curve_b(t, 1)
            if second and inter.curve_b.degree >= 2:
                S2[sel] = inter.curve_b(t, 2)
        res = shape_on_curve(xiB, S, S1, S2)
        NB, NBz = res[0], res[1]
        NBzz = res[2] if second else None
        qB = self._gather(xl, lpos, eB)                         # (P, 18, 3)
        Y = np.matmul(NB[:, None, :], qB)[:, 0]
        Yz = np.matmul(qB.transpose(0, 2, 1), NBz)              # (P, 3, 2)
        Yzz = (np.matmul(qB.transpose(0, 2, 1), NBzz.reshape(P, 18, 4)).reshape(P, 3, 2, 2)
               if second else None)
        return Y, Yz, Yzz, NB, NBz, NBzz

    def _wrap(self, itf, eB, xiB, tB):
        """Move points across B's element boundaries; clamp at beam and curve ends (invalid there)."""
        valid = np.ones(len(eB), dtype=bool)
        for k, inter in enumerate(self.interfaces):
            sel = itf == k
            b = inter.b
            lo, hi = b.element_offset, b.element_offset + b.n_elements - 1
            e, x = eB[sel], xiB[sel]
            shift = np.floor((x + 1.0) / 2.0).astype(int)
            shift = np.where(x == 1.0, 0, shift)
            e_new = np.minimum(np.maximum(e + shift, lo), hi)
            x = x - 2.0 * (e_new - e)
            out = (x < -1.0 - 1e-12) | (x > 1.0 + 1e-12)
            x = np.minimum(np.maximum(x, -1.0), 1.0)
            # past an end of the interface curve the target surface continues smoothly (the
            # spline's end piece is extrapolated), so a point whose partner slid off the curve end
            # by a little stays in contact instead of switching off abruptly
            t = tB[sel]
            T = inter.curve_b.t_end
            out |= (t < -CURVE_OVERHANG * T) | (t > (1.0 + CURVE_OVERHANG) * T)
            t = np.minimum(np.maximum(t, -CURVE_OVERHANG * T), (1.0 + CURVE_OVERHANG) * T)
            eB[sel], xiB[sel], tB[sel], valid[sel] = e_new, x, t, ~out
        return eB, xiB, tB, valid

    # ---------------------------------------------------------------- state
    converged_projection = True

    def checkpoint(self) -> None:
        """Remember the projections of a converged state (restored when a step is cut back)."""
        self._saved = (self.eB.copy(), self.xiB.copy(), self.tB.copy(),
                       [m.copy() for m in getattr(self, "mu", [])])

    def restore(self) -> None:
        self._cache = None
        self.eB, self.xiB, self.tB = (a.copy() for a in self._saved[:3])
        if hasattr(self, "mu"):
            self.mu = [m.copy() for m in self._saved[3]]

    # ---------------------------------------------------------------- energy, force, Hessian
    def penalty_function(self, g: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """φ(g), φ'(g), φ''(g) of the pointwise penalty energy Π = p Σ w φ(g).

        Sliding: φ = g²/2.  Unilateral: φ = 0 for g ≥ 0 and g²/2 + δg/2 + δ²/6 for g ≤ −δ, joined
        by −g³/(6δ) on (−δ, 0): twice differentiable, so the stiffness grows smoothly from 0 at
        touch to p at δ of penetration (δ = ``contact.smoothing``; δ = 0: the plain max(0, −g)²/2,
        whose stiffness jumps at touch and makes Newton chatter between active sets)."""
        if self.mode != "unilateral":
            return 0.5 * g * g, g, np.ones_like(g)
        dlt = self.smoothing
        pen = np.minimum(g, 0.0)
        if dlt <= 0.0:
            return 0.5 * pen * pen, pen, (g < 0.0).astype(float)
        deep = g <= -dlt
        mid = (g < 0.0) & ~deep
        phi = np.where(deep, 0.5 * g * g + 0.5 * dlt * g + dlt * dlt / 6.0, np.where(mid, -g ** 3 / (6.0 * dlt), 0.0))
        d1 = np.where(deep, g + 0.5 * dlt, np.where(mid, -g * g / (2.0 * dlt), 0.0))
        d2 = np.where(deep, 1.0, np.where(mid, -g / dlt, 0.0))
        return phi, d1, d2

    def energy(self, xl: np.ndarray, needed: np.ndarray) -> float:
        if len(self.local) == 0:
            return 0.0
        r = self._evaluate(xl, needed, hessian=False)
        if not r["ok"]:
            return np.inf
        if self.projection is not None:
            return self._lambda(r)[2]
        if self.mode == "unilateral":
            return float(self.penalty * np.sum(r["w"] * self.penalty_function(r["g"])[0]))
        return float(0.5 * self.penalty * np.sum(r["w"] * np.einsum("pi,pi->p", r["d"], r["d"])))

    def add_residual(self, xl: np.ndarray, needed: np.ndarray, floc: np.ndarray) -> bool:
        if len(self.local) == 0:
            return True
        r = self._evaluate(xl, needed, hessian=False)
        if self.projection is not None:
            _, tau, _ = self._lambda(r)
            traction = tau[:, None] * r["n"]                                     # τ_p n_p
        elif self.mode == "unilateral":
            traction = (self.penalty * r["w"] * self.penalty_function(r["g"])[1])[:, None] * r["n"]
        else:
            traction = (self.penalty * r["w"])[:, None] * r["d"]                 # p w_p d_p
        fA = r["NA"][:, :, None] * traction[:, None, :]                          # (P, 18, 3)
        fB = -r["NB"][:, :, None] * traction[:, None, :]
        for e, f in ((r["eA"], fA), (r["eB"], fB)):
            pos = r["lpos"](self._conn[e])                                       # (P, 3)
            dofs = (18 * pos[:, :, None] + np.arange(18)).reshape(len(e), 54)
            floc += np.bincount(dofs.ravel(), f.reshape(len(e), 54).ravel(), minlength=floc.size)
        return bool(r["ok"])

    def pair_hessians(self, r: dict, pair_index: np.ndarray, n_pairs: int,
                      coef: np.ndarray | None = None, outer: np.ndarray | None = None) -> np.ndarray:
        """Σ_p c_p ∇²(½|d_p|²) + Σ_p o_p ∇g_p ∇g_pᵀ summed per group (A element, B element),
        (n_groups, 108, 108).

        Per point ∇²(½|d|²) = (n nᵀ) ⊗ I₃ − Q φ_ζζ⁻¹ Qᵀ with n = [N_A, −N_B], Q = φ_qζ (108 × 2);
        c_p = p w_p by default.  Since ∇²(½g²) = ∇g∇gᵀ + g ∇²g, ``outer = −c`` turns the sum
        into Σ c_p g_p ∇²g_p (g the signed gap).  Points are grouped (zero-padded) so that each
        sum is one batched GEMM.
        """
        P = len(r["w"])
        pw = self.penalty * r["w"] if coef is None else coef
        n = np.concatenate([r["NA"], -r["NB"]], axis=1)                        # (P, 36)
        d, Yz = r["d"], r["Yz"]
        # φ_qζ[:, (slot, i), k] = −[0, N_B,ζk]_slot d_i − n_slot (Y_ζk)_i
        mz = np.concatenate([np.zeros((P, 18, 2)), r["NBz"]], axis=1)           # (P, 36, 2)
        Q = -(mz[:, :, None, :] * d[:, None, :, None]) - (n[:, :, None, None] * Yz[:, None, :, :])
        Q = Q.reshape(P, 108, 2)
        Hzz = np.einsum("pik,pil->pkl", Yz, Yz) - np.einsum("pikl,pi->pkl", r["Yzz"], d)
        W = np.matmul(Q, np.linalg.inv(Hzz)) * pw[:, None, None]               # (P, 108, 2)
        order = np.argsort(pair_index, kind="stable")
        counts = np.bincount(pair_index, minlength=n_pairs)
        M = int(counts.max())
        slot = np.arange(P) - np.repeat(np.cumsum(counts) - counts, counts)
        pad = np.full((n_pairs, M), P, dtype=np.int64)                          # P = zero row
        pad[pair_index[order], slot] = order
        zero2 = np.zeros((1, 108, 2))
        Qp = np.concatenate([Q, zero2])[pad].transpose(0, 1, 3, 2).reshape(n_pairs, 2 * M, 108)
        Wp = np.concatenate([W, zero2])[pad].transpose(0, 1, 3, 2).reshape(n_pairs, 2 * M, 108)
        K = -np.matmul(Qp.transpose(0, 2, 1), Wp)
        npad = np.concatenate([n, np.zeros((1, 36))])[pad]                      # (pairs, M, 36)
        wpad = np.concatenate([pw, [0.0]])[pad]
        nn = np.matmul(npad.transpose(0, 2, 1), wpad[:, :, None] * npad)        # (pairs, 36, 36)
        K4 = K.reshape(n_pairs, 36, 3, 36, 3)
        for i in range(3):
            K4[:, :, i, :, i] += nn
        if outer is not None:
            G = (n[:, :, None] * r["n"][:, None, :]).reshape(P, 108)              # ∇g_p
            Gp = np.concatenate([G, np.zeros((1, 108))])[pad]
            opad = np.concatenate([outer, [0.0]])[pad]
            K += np.matmul(Gp.transpose(0, 2, 1), opad[:, :, None] * Gp)
        return K

    def _mortar_jacobian(self, r: dict, mat, fixed_mask) -> None:
        """p Σ_s Σ_pp' C_pp' ∇g_p ∇g_p'ᵀ + Σ_p τ_p ∇²g_p for the projected sliding gap.

        One dense matrix per segment over its A nodes and the nodes of the B elements its
        points project onto (usually one element, two near a boundary), inserted once; segments
        are batched by that number of B elements.
        """
        g, tau, _ = self._lambda(r)
        valid = r["valid"]
        size = max(np.sqrt(b.section.area) for b in self.model.beams)
        curv = valid & (np.abs(g) > 1e-15 * size) & (tau != 0.0)
        segs, srow = self._segments(r)
        itf_of_seg = self.pts["itf"][self.seg_start[segs]]
        seg_first = np.searchsorted(self.local, self.seg_start[segs])
        eB = r["eB"]
        first_b = np.full(len(segs), np.iinfo(np.int64).max)
        np.minimum.at(first_b, srow, eB)                     # first B element of each segment
        last_b = np.full(len(segs), -1)
        np.maximum.at(last_b, srow, eB)
        span = last_b - first_b + 1
        for k in range(len(self.interfaces)):
            for width in np.unique(span[itf_of_seg == k]):
                sk = np.flatnonzero((itf_of_seg == k) & (span == width))
                self._mortar_block(r, g, tau, curv, segs, srow, seg_first, first_b, sk, int(width),
                                   mat, fixed_mask)

    def _mortar_block(self, r, g, tau, curv, segs, srow, seg_first, first_b, sk, width, mat,
                      fixed_mask) -> None:
        """The segments ``sk`` (one interface, each spanning ``width`` B elements)."""
        from petsc4py import PETSc
        valid = r["valid"]
        n_s, P_s = len(sk), int(self.seg_size[segs[sk[0]]])
        D = 54 + 18 * (2 * width + 1)
        pts = np.flatnonzero(np.isin(srow, sk))           # local points of these segments
        s_loc = np.searchsorted(sk, srow[pts])
        p_loc = pts - seg_first[sk][s_loc]
        j = (r["eB"][pts] - first_b[srow[pts]]).astype(np.int64)
        # (1) p Vᵀ C V, V[p] = ∇g_p = [N_A, −N_B] ⊗ n_p on [A nodes, B element j nodes]
        ng = r["n"][pts] * valid[pts][:, None]
        V = np.zeros((n_s, P_s, D))
        V[s_loc[:, None], p_loc[:, None], np.arange(54)] = \
            (r["NA"][pts][:, :, None] * ng[:, None, :]).reshape(-1, 54)
        colsB = 54 + 36 * j[:, None] + np.arange(54)
        V[s_loc[:, None], p_loc[:, None], colsB] = \
            -(r["NB"][pts][:, :, None] * ng[:, None, :]).reshape(-1, 54)
        C = np.asarray([self.C[s] for s in segs[sk]])
        K = self.penalty * np.matmul(V.transpose(0, 2, 1), np.matmul(C, V))
        # (2) Σ τ_p ∇²g_p = Σ (τ_p/g_p)[∇²(½g_p²) − ∇g_p∇g_pᵀ], summed per (segment, j)
        use = curv[pts]
        if np.any(use):
            sel = pts[use]
            ru = {key: (v[sel] if isinstance(v, np.ndarray) and v.shape[:1] == valid.shape else v)
                  for key, v in r.items()}
            group = s_loc[use] * width + j[use]
            uniq, inv = np.unique(group, return_inverse=True)
            Gs = self.pair_hessians(ru, inv, len(uniq), coef=tau[sel] / g[sel],
                                    outer=-tau[sel] / g[sel])
            gs, gj = np.divmod(uniq, width)
            for jj in range(width):
                m = gj == jj
                if not np.any(m):
                    continue
                ij = np.concatenate([np.arange(54), 54 + 36 * jj + np.arange(54)])
                K[gs[m][:, None, None], ij[None, :, None], ij[None, None, :]] += Gs[m]
        eA = self.pts["eA"][self.seg_start[segs[sk]]]
        els = self._conn[first_b[sk][:, None] + np.arange(width)]            # (n_s, width, 3)
        bnodes = np.concatenate([els[:, :, :2].reshape(n_s, -1), els[:, -1:, 2]], axis=1)
        nodes = np.concatenate([self._conn[eA], bnodes], axis=1)
        rows = (18 * nodes[:, :, None] + np.arange(18)).reshape(n_s, D)
        # the B elements of a segment need not be contiguous (points on e and e + 2): the
        # nodes of an element in between that no point projects onto stay out of the matrix
        used = np.zeros((n_s, D), dtype=bool)
        used[:, :54] = True
        used[s_loc[:, None], colsB] = True
        rows = np.where(fixed_mask[rows] | ~used, -1, rows).astype(PETSc.IntType)
        mat.setValuesRCV(rows, rows, K, PETSc.InsertMode.ADD_VALUES)

    def add_jacobian(self, xl, needed, mat, fixed_mask) -> None:
        if len(self.local) == 0:
            return
        r = self._evaluate(xl, needed, hessian=True)
        if self.projection is not None:
            self._mortar_jacobian(r, mat, fixed_mask)
            return
        keep = r["w"] > 0.0
        if not np.any(keep):
            return
        r = {k: (v[keep] if isinstance(v, np.ndarray) and v.shape[:1] == keep.shape else v)
             for k, v in r.items()}
        pair = r["eA"].astype(np.int64) * self.model.n_elements + r["eB"]
        uniq, inv = np.unique(pair, return_inverse=True)
        if self.mode == "unilateral":
            # p w [φ'' ∇g∇gᵀ + φ' ∇²g] = c ∇²(½g²) + (p w φ'' − c) ∇g∇gᵀ with c = p w φ'/g
            _, d1, d2 = self.penalty_function(r["g"])
            pw = self.penalty * r["w"]
            with np.errstate(divide="ignore", invalid="ignore"):
                c = np.where(r["g"] != 0.0, pw * d1 / r["g"], 0.0)
            K = self.pair_hessians(r, inv, len(uniq), coef=c, outer=pw * d2 - c)
        else:
            K = self.pair_hessians(r, inv, len(uniq))
        eA, eB = np.divmod(uniq, self.model.n_elements)
        nodes = np.concatenate([self._conn[eA], self._conn[eB]], axis=1)         # (pairs, 6)
        rows = (18 * nodes[:, :, None] + np.arange(18)).reshape(len(uniq), 108)
        from petsc4py import PETSc
        rows = np.where(fixed_mask[rows], -1, rows).astype(PETSc.IntType)
        mat.setValuesRCV(rows, rows, K, PETSc.InsertMode.ADD_VALUES)

    # ---------------------------------------------------------------- projected (mortar-type) gap
    def _build_projection(self) -> None:
        """C_s = W Φ (Φᵀ W Φ)⁻¹ Φᵀ W per segment (interface × A element): Π_con = p/2 Σ gᵀ C g.

        Φ holds the Legendre polynomials P_a(ξ) P_b(τ), a ≤ axial degree, b ≤ curve degree,
        τ = 2t/T − 1; W the reference area weights.  gᵀ C g = ∫ (Π g)² dA with Π the L²
        projection onto that space; with a full basis C = W and the scheme is pointwise.
        """
        from numpy.polynomial import legendre as leg
        ka, kc = self.projection
        seg = self.pts["seg"]
        order = np.argsort(seg, kind="stable")
        if not np.array_equal(order, np.arange(self.n_points)):
            raise RuntimeError("contact points must be stored segment by segment")
        self.seg_start = np.searchsorted(seg, np.arange(self.n_segments))
        self.seg_size = np.diff(np.append(self.seg_start, self.n_points))
        self.C, self.B = [None] * self.n_segments, [None] * self.n_segments
        # the segments of one interface share their points (ξ, τ), hence Φ; only the reference
        # area weights differ: one batched Cholesky per interface
        for k in range(len(self.interfaces)):
            segs = np.flatnonzero(self.pts["itf"][self.seg_start] == k)
            if len(segs) == 0:
                continue
            n = int(self.seg_size[segs[0]])
            sl = slice(self.seg_start[segs[0]], self.seg_start[segs[0]] + n)
            xi, tau = self.pts["xi"][sl], 2.0 * self.pts["t"][sl] / self.t_end_a[sl] - 1.0
            kc_eff = min(kc, len(np.unique(tau)) - 1)
            Pa = leg.legvander(xi, ka)
            Pb = leg.legvander(tau, kc_eff)
            Phi = (Pa[:, :, None] * Pb[:, None, :]).reshape(n, -1)
            w = self.pts["w"][self.seg_start[segs][:, None] + np.arange(n)]     # (S, n)
            WPhi = w[:, :, None] * Phi[None]                                    # (S, n, m)
            M = np.matmul(Phi.T[None], WPhi)
            Bs = np.linalg.solve(np.linalg.cholesky(M), WPhi.transpose(0, 2, 1))  # m = B g
            Cs = np.matmul(Bs.transpose(0, 2, 1), Bs)
            for j, s in enumerate(segs):
                self.B[s], self.C[s] = Bs[j], Cs[j]
        self.mu = [np.zeros(Bs.shape[0]) for Bs in self.B]         # augmented-Lagrangian multipliers

    def _segments(self, r: dict):
        """Local segments and, per local point, its segment row/column in the local arrays."""
        seg = self.pts["seg"][self.local]
        segs = np.unique(seg)
        return segs, np.searchsorted(segs, seg)

    def _lambda(self, r: dict):
        """Signed gaps g, point tractions τ = Bᵀ(μ + p B g) and Π_con = Σ_s μ·m + p/2 |m|², m = B g.

        With μ = 0 this is the pure penalty p/2 gᵀ C g; the multipliers μ are updated between
        solves (``augment``) so that the projected gaps m vanish (augmented Lagrangian).
        """
        g = r["g"] * r["valid"]
        tau = np.zeros_like(g)
        energy = 0.0
        segs, _ = self._segments(r)
        pos = np.searchsorted(self.local, self.seg_start[segs])
        for s, p0 in zip(segs, pos):
            n = self.seg_size[s]
            m = self.B[s] @ g[p0:p0 + n]
            tau[p0:p0 + n] = self.B[s].T @ (self.mu[s] + self.penalty * m)
            energy += float(self.mu[s] @ m) + 0.5 * self.penalty * float(m @ m)
        return g, tau, energy

    def scale_multipliers(self, factor: float) -> None:
        """Multiplier predictor for a load increment: contact tractions grow with the load."""
        if hasattr(self, "mu"):
            self.mu = [factor * m for m in self.mu]

    def gap_tolerance(self) -> float:
        """Absolute projected-gap floor of the augmented Lagrangian [m] (for vanishing tractions)."""
        return 1e-6 * min(np.sqrt(b.section.area) for b in self.model.beams)

    def augment(self, xl: np.ndarray, needed: np.ndarray) -> tuple[float, float, float]:
        """Uzawa update μ ← μ + p m on the local segments.  Returns the local sums Σ|p m|²,
        Σ|μ + p m|² (for the relative multiplier change) and the largest projected-gap RMS
        |m| / √(segment area) [m], all before the update."""
        if self.projection is None or len(self.local) == 0:
            return 0.0, 0.0, 0.0
        r = self._evaluate(xl, needed, hessian=False)
        g = r["g"] * r["valid"]
        segs, _ = self._segments(r)
        pos = np.searchsorted(self.local, self.seg_start[segs])
        dsq = tsq = worst = 0.0
        for s, p0 in zip(segs, pos):
            n = self.seg_size[s]
            m = self.B[s] @ g[p0:p0 + n]
            area = self.pts["w"][self.seg_start[s]:self.seg_start[s] + n].sum()
            worst = max(worst, float(np.linalg.norm(m) / np.sqrt(area)))
            self.mu[s] = self.mu[s] + self.penalty * m
            dsq += float(np.sum((self.penalty * m) ** 2))
            tsq += float(np.sum(self.mu[s] ** 2))
        return dsq, tsq, worst

    # ---------------------------------------------------------------- checks and reports
    def _evaluate_all(self, q_model: np.ndarray) -> dict:
        """Evaluate every point at a full model-ordered state (replicated data, no PETSc), leaving
        the rank's own working state (local points, numbering, windows, projections) untouched."""
        saved = (self.local, self.eB.copy(), self.xiB.copy(), self.tB.copy(),
                 getattr(self, "_conn", None), getattr(self, "_allowed", None))
        self.local = np.arange(self.n_points)
        self._conn = self.model.connectivity()
        avail, want, missing = getattr(self, "_avail", None), getattr(self, "_want", None), self.missing
        cache, self._cache = self._cache, None
        self._avail = np.ones(self.model.n_elements, dtype=bool)
        self._allowed = (np.zeros(self.n_points, dtype=np.int64),
                         np.full(self.n_points, self.model.n_elements, dtype=np.int64))
        try:
            return self._evaluate(q_model.reshape(-1, 6, 3), np.arange(self.model.n_nodes), hessian=False)
        finally:
            self.local, self.eB, self.xiB, self.tB, self._conn, self._allowed = saved
            self._avail, self._want, self.missing, self._cache = avail, want, missing, cache

    def _check_reference_gaps(self) -> None:
        """Sliding holds the reference gap (zero); unilateral contact must not start penetrating."""
        r = self._evaluate_all(self.model.q0)
        size = max(np.sqrt(b.section.area) for b in self.model.beams)
        if self.mode == "unilateral":
            if not r["ok"] or np.min(r["g"][r["valid"]], initial=0.0) < -1e-9 * size:
                raise ConfigError("contact", "the bodies interpenetrate in the reference configuration "
                                             f"(gap {np.min(r['g']):.3e} m); separate them")
            return
        gap = np.linalg.norm(r["d"], axis=1)
        if not r["ok"] or gap.max() > 1e-9 * size:
            raise ConfigError("contact", f"the interfaces do not match in the reference configuration "
                                         f"(largest gap {gap.max():.3e} m); neighbours must share "
                                         "their interface curve and element boundaries")

    def describe(self) -> list[str]:
        proj = ("pointwise gap" if self.projection is None else
                f"gap projected on degree {self.projection[0]} in xi x {self.projection[1]} along the curve")
        al = (f", augmented Lagrangian (multiplier change < {self.spec.gap_tolerance:.0e})"
              if self.augmented else "")
        lines = [f"contact: {self.mode}, penalty p_n = {self.penalty:.4g} Pa/m, {proj}{al}, "
                 f"{self.n_points} points ({self.spec.axial_points} axial x "
                 f"{self.spec.curve_points} per curve piece)"]
        for itf in self.interfaces:
            lines.append(f"  interface {itf.name}: {itf.n_points} points on {itf.a.name}, "
                         f"projected onto {itf.b.name}")
        return lines

    def _gap_sums(self, r: dict, points: np.ndarray) -> np.ndarray:
        """Per interface (rows): [largest |d| of the active points, Σ |d|² over them, active
        points, largest projected gap RMS |B g| / √area of a segment, points], over ``points``
        (``r`` evaluated on them, in that order).  Rows reduce over ranks by max, sum, sum, max,
        sum (``gap_report``)."""
        itf = self.pts["itf"][points]
        act = r["w"] > 0.0
        dist = np.linalg.norm(r["d"], axis=1)
        out = np.zeros((len(self.interfaces), 5))
        for k in range(len(self.interfaces)):
            sel, on = act & (itf == k), itf == k
            out[k, 0] = dist[sel].max(initial=0.0)
            out[k, 1] = float(np.sum(dist[sel] ** 2))
            out[k, 2], out[k, 4] = sel.sum(), on.sum()
        if self.projection is not None:       # RMS of the projected gap per segment
            g = r["g"] * r["valid"]
            seg = self.pts["seg"][points]
            for s in np.unique(seg):
                p0, n = int(np.searchsorted(seg, s)), int(self.seg_size[s])
                sl = slice(self.seg_start[s], self.seg_start[s] + n)
                rms = np.linalg.norm(self.B[s] @ g[p0:p0 + n]) / np.sqrt(self.pts["w"][sl].sum())
                k = self.pts["itf"][self.seg_start[s]]
                out[k, 3] = max(out[k, 3], rms)
        return out

    def gap_sums(self, xl: np.ndarray, needed: np.ndarray) -> np.ndarray:
        """``_gap_sums`` of this rank's points at the local state (the projection of the last
        residual at the same state is reused)."""
        if len(self.local) == 0:
            return np.zeros((len(self.interfaces), 5))
        return self._gap_sums(self._evaluate(xl, needed, hessian=False), self.local)

    def gap_report(self, sums: np.ndarray) -> dict:
        """Per-interface gap statistics from (rank-reduced) ``_gap_sums``."""
        out = {}
        for k, itf in enumerate(self.interfaces):
            mx, sq, na, mp, npts = sums[k]
            out[itf.name] = {"max_gap": float(mx), "rms_gap": float(np.sqrt(sq / na)) if na else 0.0,
                             "max_projected_gap": float(mp), "active_points": int(na),
                             "points": int(npts)}
        return out

    def gaps(self, q_model: np.ndarray) -> dict:
        """Distances of the active points to the other surface per interface, at a gathered
        state (every point evaluated here; runs use ``Problem.contact_gaps``)."""
        r = self._evaluate_all(q_model)
        return self.gap_report(self._gap_sums(r, np.arange(self.n_points)))


def build_contact(model: Model, spec: ContactSpec, log=print) -> Contact:
    """Contact from the config; prints the interfaces and the penalty."""
    interfaces = find_interfaces(model, spec)
    c = Contact(model, spec, interfaces)
    for line in c.describe():
        log("[ancf]   " + line)
    return c
