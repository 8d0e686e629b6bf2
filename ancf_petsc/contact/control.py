"""The control of the closest-point descent's iteration (``projection.Projector.descend``): the
test of the last step and the next trial of every point, compiled (contact/control_native.pyx,
bitwise the numpy code: one call each instead of ~40 numpy calls) or numpy (descent.Backtracking
and ``Projector.wrap``, the reference)."""
from __future__ import annotations

import numpy as np

from .. import native
from .descent import ARMIJO, ROUNDING, Backtracking
from .fade import CURVE_FADE_END, CURVE_OVERHANG, END_FADE


class DescentControl:
    """``assess`` and ``advance`` of one descent iteration for the points of a ``Projector``
    (its ``wrap`` and ``wrap_bounds``); ``compiled``: whether the compiled module may run."""

    def __init__(self, projector, compiled: bool = True):
        self._projector = projector
        self._module = native.load("contact.control_native") if compiled else None

    @property
    def compiled(self) -> bool:
        return self._module is not None

    def assess(self, search: Backtracking, d: np.ndarray, valid: np.ndarray, dz: np.ndarray,
               r: np.ndarray, tol_xi: float, tol_t: np.ndarray,
               stuck_ever: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``worse`` (Backtracking.worse at the distances d) and ``ok`` (the step dζ below the
        tolerances and not worse, or the point invalid) of every point; a non-finite step is
        zeroed with its φ_ζ r (in place) and recorded in ``stuck_ever``."""
        if self._module is None:
            worse = search.worse(d, valid)
            stuck = ~np.all(np.isfinite(dz), axis=1)
            dz[stuck], r[stuck] = 0.0, 0.0
            stuck_ever |= stuck
            ok = (np.abs(dz[:, 0]) < tol_xi) & (np.abs(dz[:, 1]) < tol_t) & ~worse | ~valid
            return worse, ok
        search.phi_now = 0.5 * np.einsum("pi,pi->p", d, d)
        worse, ok = np.empty(len(d), dtype=bool), np.empty(len(d), dtype=bool)
        self._module.assess(search.phi_now, search.phi, search.alpha, search.descent, search.slack, dz, r,
                            _u8(valid), np.ascontiguousarray(tol_t, dtype=float), tol_xi, ARMIJO,
                            _u8(stuck_ever), _u8(worse), _u8(ok))
        return worse, ok

    def advance(self, search: Backtracking, itf: np.ndarray, eB: np.ndarray, xiB: np.ndarray,
                tB: np.ndarray, d: np.ndarray, dz: np.ndarray, r: np.ndarray, worse: np.ndarray):
        """The points not ``worse`` start a step dζ (φ_ζ r) from (eB, ξB, tB), the others halve
        theirs (Backtracking.accept); returns the trials wrapped onto B (eB, ξB, tB: the compiled
        path overwrites the arrays given), their weights and the points that crossed (worse and
        on another element than their step's start)."""
        if self._module is None:
            crossed = worse & (eB != search.e)
            search.accept(~worse, eB, xiB, tB, d, dz, r)
            eB, xiB, tB = search.trial()
            eB, xiB, tB, weight = self._projector.wrap(itf, eB, xiB, tB)
            return eB, xiB, tB, weight, crossed
        crossed, weight = np.empty(len(eB), dtype=bool), np.empty(len(eB))
        first, last, T = self._projector.wrap_bounds(itf)
        self._module.advance(eB, xiB, tB, d, dz, r, _u8(worse), search.e, search.xi, search.t, search.e_back,
                             search.phi, search.phi_now, search.slack, search.descent, search.dz,
                             search.alpha, search.length, search.keep_direction, first, last, T,
                             ROUNDING, CURVE_OVERHANG, CURVE_FADE_END, END_FADE, _u8(crossed), weight)
        return eB, xiB, tB, weight, crossed


def _u8(flags: np.ndarray) -> np.ndarray:
    """A contiguous bool array as uint8 (the same memory: the compiled code writes through it)."""
    if flags.dtype != bool or not flags.flags.c_contiguous:
        raise ValueError("flags must be a contiguous bool array")
    return flags.view(np.uint8)
