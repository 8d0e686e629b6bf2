"""The weight of a contact point's partner place: 1 on B's surface, falling smoothly to 0 past the
ends of B's interface curve and of B's beam (contact/weights.py says how Newton treats it).

A partner place (ξ_B, t_B) past an end of the interface curve (the spline's end piece continues)
keeps the full weight up to CURVE_OVERHANG of the curve's length beyond it and loses it over the
band up to CURVE_FADE_END; past B's beam ends (the end element's polynomial continues) the band is
END_FADE element lengths from the end.  The fade is the quintic smoothstep (C²), so that its slope
and curvature vanish at the edges of a band and the differentiated weights' Jacobian is
continuous; ``end_weight_slope`` and ``end_weight_curvature`` are its ζ-derivatives.
"""
from __future__ import annotations

import numpy as np

from .. import native

#: a point whose closest point lies past an end of B's interface curve (the spline's end piece
#: continues smoothly) keeps its full weight up to CURVE_OVERHANG of the curve's length beyond
#: it; its weight then falls smoothly (C²) to zero at CURVE_FADE_END, so that no point leaves the
#: contact at once (a point switching off at 1.25 made Newton cycle between two states: the
#: bulk-modulus sweep of the paper's columns, K = 0.90 GPa at ψ = 0°).  The band was 0.25-0.30
#: until the gait envelope (contact/weights.py): at twists of 90-180° points cross it within a
#: load step, and the steep weight made Newton cycle; 0.25-0.50 measured best of 0.3/0.5/0.75
#: that keeps the extrapolated spline short
CURVE_OVERHANG = 0.25
CURVE_FADE_END = 0.5
#: likewise past B's beam ends (in element lengths): the end element's polynomial continues and
#: the weight falls from 1 at the end to 0 at a quarter of an element beyond it
END_FADE = 0.25


def curve_limits(t_end: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the continuation of a curve of length ``t_end`` ends (weight 0): −CURVE_FADE_END·T
    and (1 + CURVE_FADE_END)·T, the clamp of ``Projector.wrap``."""
    return -CURVE_FADE_END * t_end, (1.0 + CURVE_FADE_END) * t_end


def fade(u: np.ndarray) -> np.ndarray:
    """1 − (10u³ − 15u⁴ + 6u⁵) on [0, 1], 1 below, 0 above: a C² step from 1 to 0 (its slope
    and curvature vanish at both ends, so that a partner place held at the end of a fade band
    (``Projector.wrap``) has neither, and Newton's Jacobian is continuous across the band's
    edges)."""
    v = np.clip(u, 0.0, 1.0)
    return 1.0 - v * v * v * (10.0 - 15.0 * v + 6.0 * v * v)


def fade_slope(u: np.ndarray) -> np.ndarray:
    """d/du of ``fade``: −30u²(1 − u)² on [0, 1], 0 elsewhere."""
    return np.where((u > 0.0) & (u < 1.0), -30.0 * u * u * (1.0 - u) ** 2, 0.0)


def _compiled(xiB, tB, t_end, at_first, at_last) -> tuple | None:
    """``contact.control_native`` and its arrays (contiguous float64, flags as uint8) for
    ``end_weight`` and ``end_weight_slope``; None when it is not built (or ANCF_NATIVE=0) or the
    arguments are not arrays of one length (scalars, broadcasting: the numpy code takes those)."""
    module = native.load("contact.control_native")
    args = (xiB, tB, t_end, at_first, at_last)
    if module is None or not all(isinstance(a, np.ndarray) and a.ndim == 1 and len(a) == len(xiB)
                                 for a in args):
        return None
    return (module,) + tuple(np.ascontiguousarray(a, dtype=float) for a in args[:3]) + tuple(
        np.ascontiguousarray(a, dtype=bool).view(np.uint8) for a in args[3:])


def _fade_arguments(xiB, tB, t_end, at_first, at_last) -> tuple:
    """The fades' arguments at partner places (``end_weight``): u_t past the curve's ends, u_x
    past the beam's; whether t_B is below the curve's start, and ξ_B's overhang (signed)."""
    below = -tB > tB - t_end
    u_t = (np.where(below, -tB, tB - t_end) / t_end - CURVE_OVERHANG) / (CURVE_FADE_END - CURVE_OVERHANG)
    raw = np.where(at_last, xiB - 1.0, 0.0) + np.where(at_first, -1.0 - xiB, 0.0)
    return u_t, np.maximum(raw, 0.0) / (2.0 * END_FADE), below, raw


def band_positions(xiB: np.ndarray, tB: np.ndarray, t_end: np.ndarray, at_first: np.ndarray,
                   at_last: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where partner places sit against the fade bands: u_t past the curve's nearer end (0 at the
    band's start, 1 at its end, −CURVE_OVERHANG / band at the curve's end) and ξ_B's overhang past
    the beam's end (signed; B's first/last element only)."""
    u_t, _, _, raw = _fade_arguments(xiB, tB, t_end, at_first, at_last)
    return u_t, raw


def end_weight(xiB: np.ndarray, tB: np.ndarray, t_end: np.ndarray, at_first: np.ndarray,
               at_last: np.ndarray) -> np.ndarray:
    """Weight of a partner place (ξ_B, t_B): 1 on B's surface, falling past the curve's ends
    (overhang as a share of the curve's length T) and past the beam's ends (``at_first``/
    ``at_last``: on B's first/last element, in element lengths)."""
    fast = _compiled(xiB, tB, t_end, at_first, at_last)
    if fast is not None:                  # bitwise the numpy below (contact/control_native.pyx)
        return fast[0].end_weight(*fast[1:], CURVE_OVERHANG, CURVE_FADE_END, END_FADE)
    u_t, u_x, _, _ = _fade_arguments(xiB, tB, t_end, at_first, at_last)
    return fade(u_t) * fade(u_x)


def fade_curvature(u: np.ndarray) -> np.ndarray:
    """d²/du² of ``fade``: −60u(1 − u)(1 − 2u) on (0, 1), 0 elsewhere."""
    return np.where((u > 0.0) & (u < 1.0), -60.0 * u * (1.0 - u) * (1.0 - 2.0 * u), 0.0)


def end_weight_curvature(xiB: np.ndarray, tB: np.ndarray, t_end: np.ndarray, at_first: np.ndarray,
                         at_last: np.ndarray) -> np.ndarray:
    """∂²w/∂ζ² (P, 2, 2) of ``end_weight`` at the partner places (ξ_B, t_B)."""
    u_t, u_x, below, raw = _fade_arguments(xiB, tB, t_end, at_first, at_last)
    sx = np.where(at_last, 1.0, 0.0) - np.where(at_first, 1.0, 0.0)
    du_x = sx * (raw > 0.0) / (2.0 * END_FADE)
    du_t = np.where(below, -1.0, 1.0) / (t_end * (CURVE_FADE_END - CURVE_OVERHANG))
    f_t, f_x = fade(u_t), fade(u_x)
    out = np.empty((len(xiB), 2, 2))
    out[:, 0, 0] = f_t * fade_curvature(u_x) * du_x ** 2
    out[:, 1, 1] = fade_curvature(u_t) * du_t ** 2 * f_x
    out[:, 0, 1] = out[:, 1, 0] = fade_slope(u_t) * du_t * fade_slope(u_x) * du_x
    return out


def end_weight_slope(xiB: np.ndarray, tB: np.ndarray, t_end: np.ndarray, at_first: np.ndarray,
                     at_last: np.ndarray) -> np.ndarray:
    """∂w/∂ζ (P, 2) of ``end_weight`` at the partner places (ξ_B, t_B)."""
    fast = _compiled(xiB, tB, t_end, at_first, at_last)
    if fast is not None:                  # bitwise the numpy below (contact/control_native.pyx)
        return fast[0].end_weight_slope(*fast[1:], CURVE_OVERHANG, CURVE_FADE_END, END_FADE)
    u_t, u_x, below, raw = _fade_arguments(xiB, tB, t_end, at_first, at_last)
    sx = np.where(at_last, 1.0, 0.0) - np.where(at_first, 1.0, 0.0)
    f_t, f_x = fade(u_t), fade(u_x)
    dw_dt = (fade_slope(u_t) * np.where(below, -1.0, 1.0) / (t_end * (CURVE_FADE_END - CURVE_OVERHANG))
             * f_x)
    dw_dxi = f_t * fade_slope(u_x) * sx * (raw > 0.0) / (2.0 * END_FADE)
    return np.stack([dw_dxi, dw_dt], axis=1)
