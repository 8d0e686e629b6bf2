"""How far a Newton step carries contact points' partner places through the fade bands, in band
widths: the step limit that keeps Newton from stepping over a band (petsc/step_limits.py).

A point's weight falls from 1 to 0 across a fade band (contact/fade.py: past the ends of B's
interface curve, from CURVE_OVERHANG to CURVE_FADE_END of its length T, and past B's beam ends,
over END_FADE of an element).  The band is narrow beside a section (the traced second subject:
T ≈ 3.5 mm, the band 0.9 mm), so that a full Newton step can carry a partner place from full
weight across the band, where the weight's quintic is far from its linearisation.  Measured on
the second subject's unilateral walking strides (4 elements, twist 90°): partner places moved
1.4 mm per iterate, and Newton cycled with period 3 (|F| 0.044 / 0.465 / 0.421 N, one point's
weight 1 → 0.34 → 1) until the frame was cut back; at 90° gastrocnemius-biased and 120°
soleus-biased the strides stopped (frames 27 and 36).  ``solver.band_step`` (e.g. 1.5; default 0, off)
holds a full Newton step to that many band widths of the linearised move ζ′ Δq of each partner place
whose step starts or ends past its curve's or beam's end (petsc/step_limits.py); measured in
docs/gait.md (forty-fourth session).
"""
from __future__ import annotations

import numpy as np

from .fade import CURVE_FADE_END, CURVE_OVERHANG, END_FADE, band_positions
from .gap import closest_point_gradient


def band_moves(c, yl: np.ndarray) -> float:
    """The largest move, in fade-band widths, of a local contact point's partner place by the
    step ``yl`` (n, V, 3: the local nodal vectors' change) from the state of ``c``'s last
    evaluation, among places whose move starts or ends past their curve's or beam's end; 0 where
    none does (or without an evaluation)."""
    st = c.last_evaluation
    if st is None or len(st.pr.idx) == 0:
        return 0.0
    pr = st.pr

    def y_of(els: np.ndarray) -> np.ndarray:
        return yl[st.lpos(c.conn[els])].reshape(len(els), -1)

    dq = np.concatenate([y_of(c.points.eA[pr.idx]), y_of(pr.eB)], axis=1)
    dz = np.einsum("pzj,pj->pz", closest_point_gradient(pr), dq)
    pj = c.projector
    first, last, _ = pj.wrap_bounds(pj.points.itf[pr.idx])
    args = (pj.t_end[pr.idx], pr.eB == first, pr.eB == last)
    u_t0, raw0 = band_positions(pr.xiB, pr.tB, *args)
    u_t1, raw1 = band_positions(pr.xiB + dz[:, 0], pr.tB + dz[:, 1], *args)
    past_end = -CURVE_OVERHANG / (CURVE_FADE_END - CURVE_OVERHANG)        # u_t at the curve's end
    near_t = np.maximum(u_t0, u_t1) > past_end
    near_x = np.maximum(raw0, raw1) > 0.0
    move_t = np.abs(dz[:, 1]) / (pj.t_end[pr.idx] * (CURVE_FADE_END - CURVE_OVERHANG))
    move_x = np.abs(dz[:, 0]) / (2.0 * END_FADE)
    moves = np.concatenate([move_t[near_t], move_x[near_x]])
    return float(moves.max(initial=0.0))
