"""Contact quadrature points on body A's side of every interface (paper eq. 29's triple sum).

Per interface and A element (a *segment*): axial Gauss points × Gauss points on every polynomial
piece of the shared curve, weighted by the reference area element |X_ξ × X_t|.  Points are stored
segment by segment; every segment of an interface has the same points (ξ, t).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..physics.cubature import gauss_legendre
from .interfaces import ContactSetupError
from .surface import curve_shape


@dataclass
class ContactPoints:
    itf: np.ndarray        # (P,) interface index
    eA: np.ndarray         # (P,) global A element
    xi: np.ndarray         # (P,) ξ on A
    t: np.ndarray          # (P,) parameter on A's curve
    tau: np.ndarray        # (P,) the same, scaled to [−1, 1] over the curve
    w: np.ndarray          # (P,) reference area weight [m²]
    eB0: np.ndarray        # (P,) B element of the matching reference point
    seg: np.ndarray        # (P,) segment (interface × A element), non-decreasing
    NA: np.ndarray         # (P, 18) A's shape functions at the point
    seg_start: np.ndarray  # (S,) first point of each segment
    seg_size: np.ndarray   # (S,) points per segment
    seg_itf: np.ndarray    # (S,) interface of each segment
    seg_eA: np.ndarray     # (S,) A element of each segment

    @property
    def n_points(self) -> int:
        return len(self.w)

    @property
    def n_segments(self) -> int:
        return len(self.seg_start)


def build_points(model, interfaces, axial_points: int, curve_points: int) -> ContactPoints:
    """The quadrature points of every interface (``Interface.n_points`` is set on the way)."""
    xa, wa = gauss_legendre(axial_points)
    xc, wc = gauss_legendre(curve_points)
    cols = {k: [] for k in ("itf", "eA", "xi", "t", "tau", "w", "eB0", "seg", "NA")}
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
        N, Nz = curve_shape(a, curve, XI, T)
        q0e = model.q0[a.connectivity].reshape(a.n_elements, model.block.slots, 3)
        Xz = np.einsum("pak,eai->epik", Nz, q0e)        # (E, P, 3, 2): X_ξ, X_t
        dA = np.linalg.norm(np.cross(Xz[..., 0], Xz[..., 1]), axis=-1)
        E, P = a.n_elements, len(T)
        elems = np.repeat(np.arange(E), P)
        cols["itf"].append(np.full(E * P, k))
        cols["eA"].append(a.element_offset + elems)
        cols["xi"].append(np.tile(XI, E))
        cols["t"].append(np.tile(T, E))
        cols["tau"].append(np.tile(2.0 * T / curve.t_end - 1.0, E))
        cols["w"].append((W0 * dA).ravel())
        cols["eB0"].append(itf.b.element_offset + elems)
        cols["seg"].append(n_seg + elems)
        cols["NA"].append(np.tile(N, (E, 1)))
        n_seg += E
        itf.n_points = E * P
    c = {k: np.concatenate(v) for k, v in cols.items()}
    seg_start = np.searchsorted(c["seg"], np.arange(n_seg))
    seg_size = np.diff(np.append(seg_start, len(c["seg"])))
    return ContactPoints(itf=c["itf"], eA=c["eA"], xi=c["xi"], t=c["t"], tau=c["tau"], w=c["w"],
                         eB0=c["eB0"], seg=c["seg"], NA=c["NA"], seg_start=seg_start,
                         seg_size=seg_size, seg_itf=c["itf"][seg_start], seg_eA=c["eA"][seg_start])


def check_points_across(interfaces, curve_points: int, across: int) -> None:
    """Refuse an interface with fewer contact points across (``curve_points`` per piece of its
    curve) than pressure functions across (``across``: projection.curve + curve_spans): their
    weighted gaps would repeat each other (the two bars side by side with 1 point across their
    straight face: both linear functions held its middle only, the bars' transverse end
    displacement 10 % off, the multipliers' split arbitrary)."""
    for itf in interfaces:
        pieces = len(itf.curve.breakpoints) - 1
        if pieces * curve_points < across:
            raise ContactSetupError(
                f"interface {itf.name}: {pieces * curve_points} contact point(s) across ({pieces} piece(s) of "
                f"curve {itf.curve.name} x {curve_points}) determine fewer than its {across} pressure "
                f"functions across (projection.curve + curve_spans); give contact.curve_points: "
                f"{-(-across // pieces)} or more, or fewer functions; got {curve_points}", key="contact.curve_points")
