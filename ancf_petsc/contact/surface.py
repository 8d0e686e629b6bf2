"""A beam's interface surface: the shared section curve S(t) swept along the element, (ξ, S(t)).

The element's shape functions (eq. 6: Lagrange in ξ times the section monomials in y, z) are
evaluated on that surface with their derivatives in ζ = (ξ, t), which the closest-point
projection (eqs. 26–27) and the gap derivatives need.
"""
from __future__ import annotations

import numpy as np

from .. import native
from ..physics.bspline import SplineSet, compiled
from ..physics.elements import DEFAULT_ELEMENT, ELEMENTS
from ..physics.elements.base import derivative_table, quadratic_lagrange, quadratic_lagrange_second
from .descent import newton_step

#: 3363's node block (the default of the functions below; a model passes its own, Model.block)
BLOCK_3363 = ELEMENTS[DEFAULT_ELEMENT].block


def _monomials_on_curve(block, S, S1, S2=None, S3=None):
    """The block's section monomials m (P, V) at S(t) and their t-derivatives m_t, m_tt (S2
    given), m_ttt (S3 given) by the chain rule (physics/elements: the derivatives of a monomial
    are monomials).  Terms of degree above the block's order are skipped (they are 0)."""
    y, z = S[:, 0], S[:, 1]
    pairs = ((0, 0), (1, 0), (0, 1))
    if S2 is not None and block.order >= 2:
        pairs += ((2, 0), (1, 1), (0, 2))
    if S3 is not None and block.order >= 3:
        pairs += ((3, 0), (2, 1), (1, 2), (0, 3))
    d = dict(zip(pairs, block.monomial_derivatives(y, z, pairs)))    # one pass for all of them
    y1, z1 = S1[:, :1], S1[:, 1:]
    out = [d[0, 0], d[1, 0] * y1 + d[0, 1] * z1]
    if S2 is None:
        return out
    y2, z2 = S2[:, :1], S2[:, 1:]
    mtt = d[1, 0] * y2 + d[0, 1] * z2
    if block.order >= 2:                # (y²/2)'' = y'² + y y'', (yz)'' = 2 y'z' + y''z + y z''
        mtt += d[2, 0] * y1 ** 2 + d[0, 2] * z1 ** 2 + d[1, 1] * (2.0 * y1 * z1)
    out.append(mtt)
    if S3 is None:
        return out
    # (y²/2)‴ = 3 y′y″ + y y‴, (yz)‴ = y‴z + 3(y″z′ + y′z″) + y z‴, and the cubic terms
    mttt = d[1, 0] * S3[:, :1] + d[0, 1] * S3[:, 1:]
    if block.order >= 2:
        mttt += d[2, 0] * (3.0 * y1 * y2) + d[0, 2] * (3.0 * z1 * z2) + d[1, 1] * (3.0 * (y1 * z2 + y2 * z1))
    if block.order >= 3:
        mttt += (d[3, 0] * y1 ** 3 + d[2, 1] * (3.0 * y1 ** 2 * z1) + d[1, 2] * (3.0 * y1 * z1 ** 2)
                 + d[0, 3] * z1 ** 3)
    out.append(mttt)
    return out


def section_shift(beam) -> np.ndarray:
    """Add to a base-curve point (tendon frame, before offset) to get beam section coordinates."""
    sec = beam.section
    offset = np.asarray(sec.shape_params.get("offset", (0.0, 0.0)), dtype=float)
    return offset - sec.centroid


#: up to this many interface curves, each is evaluated by scipy's compiled spline routine (one
#: call per curve and derivative, all its points at once: ~5x faster than the vectorised numpy
#: recursion for the Achilles' 3); beyond, one vectorised pass over all curves (``SplineSet``)
COMPILED_CURVES_MAX = 8


class InterfaceCurves:
    """S(t) + shift, S'(t) and S''(t) of several interface curves (one per interface) for points
    on any of them; each value is bitwise the curve's own ``curve(t) + shift``, ``curve(t, 1)``,
    ``curve(t, 2)`` (0 below degree 2)."""

    def __init__(self, curves: list, shifts: list):
        self.shifts = np.array(shifts, dtype=float).reshape(len(curves), 2)
        self.t_end = np.array([c.t_end for c in curves])
        self.flipped = np.array([c.is_reversed for c in curves], dtype=bool)
        self.splines = [[c.bspline(nu) for nu in range(3 if c.degree >= 2 else 2)] for c in curves]
        self.slot = np.full((len(curves), 3), -1, dtype=np.int64)     # SplineSet index of (curve, nu)
        flat = [s for curve in self.splines for s in curve]
        self.slot[np.repeat(np.arange(len(curves)), [len(c) for c in self.splines]),
                 np.concatenate([np.arange(len(c)) for c in self.splines])] = np.arange(len(flat))
        self.set = SplineSet(flat)
        self.per_curve = compiled() is not None and len(curves) <= COMPILED_CURVES_MAX
        self._native = _packed_curves(self.splines, self.shifts, self.t_end, self.flipped)

    def __call__(self, which: np.ndarray, t: np.ndarray):
        """(S + shift, S', S'') (P, 2) each at parameters t of curves ``which`` (P,)."""
        if self._native is not None:
            return self._native[0](np.ascontiguousarray(which, dtype=np.int64),
                                   np.ascontiguousarray(t, dtype=float), *self._native[1:])
        P = len(t)
        x = np.where(self.flipped[which], self.t_end[which] - t, t)
        if self.per_curve:
            S, S1, S2 = np.empty((P, 2)), np.empty((P, 2)), np.zeros((P, 2))
            for k, splines in enumerate(self.splines):
                sel = np.flatnonzero(which == k)
                if len(sel) == 0:
                    continue
                xk = x[sel]
                S[sel] = splines[0](xk) + self.shifts[k]
                S1[sel] = -splines[1](xk) if self.flipped[k] else splines[1](xk)
                if len(splines) > 2:
                    S2[sel] = splines[2](xk)
            return S, S1, S2
        has2 = self.slot[which, 2] >= 0
        lanes = np.concatenate([self.slot[which, 0], self.slot[which, 1], self.slot[which[has2], 2]])
        vals = self.set(lanes, np.concatenate([x, x, x[has2]]))
        S = vals[:P] + self.shifts[which]
        S1 = np.where(self.flipped[which][:, None], -vals[P:2 * P], vals[P:2 * P])
        S2 = np.zeros((P, 2))
        S2[has2] = vals[2 * P:]
        return S, S1, S2


def _packed_curves(splines: list, shifts, t_end, flipped) -> tuple | None:
    """``descent_native.curves`` and its arguments after (which, t): every curve's splines'
    knots and coefficients packed into flat arrays; None when it is not built or a spline does
    not fit (not two columns, degree above 30)."""
    module = native.load("contact.descent_native")
    if module is None or any(s.c.reshape(len(s.c), -1).shape[1] != 2 or s.k > 30
                             for curve in splines for s in curve):
        return None
    spec = np.full((3 * len(splines), 4), -1, dtype=np.int64)
    knots, coefs, nk, nc = [], [], 0, 0
    for i, curve in enumerate(splines):
        for nu, s in enumerate(curve):
            spec[3 * i + nu] = (nk, len(s.t), nc, s.k)
            knots.append(s.t)
            coefs.append(s.c.reshape(len(s.c), 2))
            nk, nc = nk + len(s.t), nc + len(s.c)
    return (module.curves, np.ascontiguousarray(t_end, dtype=float), np.concatenate(knots),
            np.ascontiguousarray(np.concatenate(coefs)), spec, np.ascontiguousarray(shifts),
            np.asarray(flipped, dtype=np.uint8))


def shape_on_curve(xi: np.ndarray, S: np.ndarray, S1: np.ndarray, S2: np.ndarray | None = None,
                   block=BLOCK_3363):
    """N (P, S), N_ζ (P, S, 2) and, if S2 is given, N_ζζ (P, S, 2, 2) at section points S(t)
    with derivatives S1 = S'(t), S2 = S''(t); S = ``block.slots`` (18 for 3363)."""
    L, dL = block.axial(xi)
    SLOTS = block.slots
    P = len(xi)

    def outer(a, b, out):
        """(axial factor) x (monomial factor) of every point into ``out`` (P, slots)."""
        np.multiply(a[:, :, None], b[:, None, :], out=out.reshape(P, a.shape[1], b.shape[1]))
        return out

    # N = L m, N_ζ = (N_ξ, N_t) = (L' m, L m_t), each formed once into its own array (not all of
    # [L, L', L''] x [m, m_t, m_tt] and then picked: a third of the projection's surface cost)
    if S2 is None:
        m, mt = _monomials_on_curve(block, S, S1)
    else:
        m, mt, mtt = _monomials_on_curve(block, S, S1, S2)
    N = outer(L, m, np.empty((P, SLOTS)))
    Nz = np.empty((2, P, SLOTS))
    outer(dL, m, Nz[0])
    outer(L, mt, Nz[1])
    if S2 is None:
        return N, Nz.transpose(1, 2, 0)
    # N_ξξ = L'' m, N_ξt = N_tξ = L' m_t, N_tt = L m_tt
    Nzz = np.empty((2, 2, P, SLOTS))
    outer(block.axial_second(xi), m, Nzz[0, 0])
    outer(dL, mt, Nzz[0, 1])
    Nzz[1, 0] = Nzz[0, 1]
    outer(L, mtt, Nzz[1, 1])
    return N, Nz.transpose(1, 2, 0), Nzz.transpose(2, 3, 0, 1)


def shape_third_on_curve(xi: np.ndarray, S: np.ndarray, S1: np.ndarray, S2: np.ndarray,
                         S3: np.ndarray, block=BLOCK_3363) -> tuple[np.ndarray, np.ndarray]:
    """N_ζζ (P, S, 2, 2) and N_ζζζ (P, S, 2, 2, 2) at section points S(t) with derivatives S1,
    S2, S3 (for the second-order sensitivity of the closest point, contact/gap.py)."""
    L, dL = block.axial(xi)
    m, mt, mtt, mttt = _monomials_on_curve(block, S, S1, S2, S3)     # once for both (as shape_on_curve's)
    P, SLOTS = len(xi), block.slots

    def outer(a, b):
        return (a[:, :, None] * b[:, None, :]).reshape(P, SLOTS)

    ddl = block.axial_second(xi)
    N_zz = np.empty((P, SLOTS, 2, 2))
    N_zz[:, :, 0, 0], N_zz[:, :, 1, 1] = outer(ddl, m), outer(L, mtt)
    N_zz[:, :, 0, 1] = N_zz[:, :, 1, 0] = outer(dL, mt)
    out = np.zeros((P, SLOTS, 2, 2, 2))
    out[:, :, 0, 0, 1] = out[:, :, 0, 1, 0] = out[:, :, 1, 0, 0] = outer(ddl, mt)    # L″ m_t
    out[:, :, 0, 1, 1] = out[:, :, 1, 0, 1] = out[:, :, 1, 1, 0] = outer(dL, mtt)    # L′ m_tt
    out[:, :, 1, 1, 1] = outer(L, mttt)                                              # L m_ttt
    return N_zz, out


class SurfaceKernels:
    """B's shape functions on its interface surface (``shape_on_curve`` with N_ζζ) and the
    closest-point step (``descent.newton_step``) for one node block: compiled
    (``descent_native``, bitwise the numpy code) where the block has three axial nodes with
    quadratic Lagrange functions and section order ≤ 15 and the module is built, else numpy."""

    def __init__(self, block):
        self.block = block
        module = None
        if (block.axial is quadratic_lagrange and block.axial_second is quadratic_lagrange_second
                and block.axial_nodes == 3 and block.order <= 15):
            module = native.load("contact.descent_native")
        self.compiled = module is not None
        if self.compiled:
            pairs = ((0, 0), (1, 0), (0, 1)) + (((2, 0), (1, 1), (0, 2)) if block.order >= 2 else ())
            ey, ez, coef, live = derivative_table(block.monomials, pairs)
            V = len(block.monomials)
            self._table = (ey.reshape(-1, V).astype(np.int64), ez.reshape(-1, V).astype(np.int64),
                           coef.reshape(-1, V), live.reshape(-1, V).astype(np.uint8), block.order)
            self._shapes, self._step = module.shapes, module.newton_step
            self._products = module.surface_products

    def shapes(self, xi: np.ndarray, S: np.ndarray, S1: np.ndarray, S2: np.ndarray):
        """N (P, S), N_ζ (P, S, 2), N_ζζ (P, S, 2, 2) (``shape_on_curve``)."""
        if self.compiled:
            return self._shapes(np.ascontiguousarray(xi, dtype=float), S, S1, S2, *self._table)
        return shape_on_curve(xi, S, S1, S2, self.block)

    def surface(self, qB: np.ndarray, NB: np.ndarray, NBz: np.ndarray, NBzz: np.ndarray):
        """Y (P, 3), Y_ζ (P, 3, 2), Y_ζζ (P, 3, 2, 2) of the surface with B's nodal vectors qB
        (P, S, 3) from ``shapes``' N, N_ζ, N_ζζ: numpy's matmuls, or the compiled module making
        the same BLAS calls on the same operands where their layout is ``shapes``' (bitwise)."""
        P, S = NB.shape
        NBzz4 = NBzz.reshape(P, S, 4)
        if (self.compiled and qB.flags.c_contiguous and NB.flags.c_contiguous
                and NBz.strides[1] == NBzz4.strides[1] == 8 and min(NBz.strides[2], NBzz4.strides[2]) >= 8 * S):
            Y, Yz, Yzz = self._products(qB, NB, NBz, NBzz4)
            return Y, Yz, Yzz.reshape(P, 3, 2, 2)
        Y = np.matmul(NB[:, None, :], qB)[:, 0]
        Yz = np.matmul(qB.transpose(0, 2, 1), NBz)                 # (P, 3, 2)
        return Y, Yz, np.matmul(qB.transpose(0, 2, 1), NBzz4).reshape(P, 3, 2, 2)

    def step(self, Yz: np.ndarray, Yzz: np.ndarray, d: np.ndarray, pinned: np.ndarray,
             metric: bool) -> tuple[np.ndarray, np.ndarray]:
        """dζ and φ_ζ (P, 2) each (``descent.newton_step``)."""
        if self.compiled:
            return self._step(Yz, Yzz, d, pinned.view(np.uint8), metric)
        return newton_step(Yz, Yzz, d, pinned, metric)


def curve_shape(beam, curve, xi: np.ndarray, t: np.ndarray, second: bool = False):
    """``shape_on_curve`` of ``beam`` on ``curve`` at (ξ, t)."""
    S = curve(t) + section_shift(beam)
    S1 = curve(t, 1)
    S2 = (curve(t, 2) if curve.degree >= 2 else np.zeros_like(S1)) if second else None
    return shape_on_curve(xi, S, S1, S2, beam.layout.block)


def closest_parameter(curve, points: np.ndarray, samples: int = 400) -> np.ndarray:
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
