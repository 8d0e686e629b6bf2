"""The secant (l2) line search with the full step tried first: one residual instead of three
where the Newton step already contracts.

PETSc's ``l2`` line search (``max_it`` 1, no objective) evaluates ‖F‖² at λ and λ/2, fits a
parabola through those and ‖F(X)‖², and evaluates F once more at the parabola's minimum: three
residuals per Newton iteration, although near a solution the minimum is within rounding of the
full step.  Coulomb friction takes l2 (bt stalls at the kinks of the projection: contact/friction.py),
so a stride's iteration paid three residual evaluations (contact projection and all) for every
Jacobian.

Here the step of length λ (the damping, 1) is evaluated first; where it contracts the residual
to ``ACCEPT`` (a quarter) of ‖F(X)‖ or less it is taken as it stands (its residual is the one just evaluated);
otherwise the midpoint is evaluated and the step is l2's, from the same three values and the same
formulas (a step that is not a descent by that margin is the one the secant fit is for).  Where
F is not finite at λ, λ is halved as PETSc's l2 does.  The decision reads only global norms, so
every rank takes the same branch.  Installed as a PETSc ``shell`` line search through the C API
(petsc4py 3.18 has no Python line searches); the step-limit pre-check (petsc/step_limits.py) and
any post-check are called as PETSc's own line searches call them.
"""
from __future__ import annotations

import ctypes
import math
import traceback

from petsc4py import PETSc

from .database import option
from .diagnostics import petsc_library

#: a full step is taken as it stands where ‖F(X − λY)‖ ≤ ACCEPT ‖F(X)‖ (module docstring).
#: Measured on the paper's tendon, Coulomb μ = 0.3, levels 1 … 100 N: with 0.25 (and 0.1) the
#: same states as PETSc's l2 to 2e-10 in 52 Newton iterations against 50, 113 residuals against
#: 165; with 0.5 the first level from rest hopped 61 iterations to another frictional equilibrium
#: (8 % away; docs/gait.md, Limits, "Friction from rest in one large increment")
ACCEPT = 0.25
_NORM_2 = 1
_FAILED_DOMAIN, _FAILED_REDUCT = 2, 3          # SNESLineSearchReason
_P, _D, _B = ctypes.c_void_p, ctypes.c_double, ctypes.c_int
_USER_FUNC = ctypes.CFUNCTYPE(ctypes.c_int, _P, _P)


class FullStepFirst:
    """The line search of ``snes`` from construction on (module docstring); ``steps`` counts its
    searches, ``full_steps`` those that took the whole step, ``evaluations`` its residuals."""

    def __init__(self, snes: PETSc.SNES):
        self.lib = petsc_library()
        self.evaluations = self.full_steps = self.steps = 0
        self._callback = _USER_FUNC(self._apply)          # kept alive with the SNES
        ls = _P()
        self._check(self.lib.SNESGetLineSearch(_P(snes.handle), ctypes.byref(ls)))
        self._check(self.lib.SNESLineSearchSetType(ls, b"shell"))
        self._check(self.lib.SNESLineSearchShellSetUserFunc(ls, self._callback, None))

    @staticmethod
    def _check(code: int) -> None:
        if code != 0:
            raise PETSc.Error(code)

    def _evaluate(self, snes, at, F) -> bool:
        """F(at) into F; True where the residual left its domain (SNESSetFunctionDomainError)."""
        self._check(self.lib.SNESComputeFunction(snes, at, F))
        self.evaluations += 1
        domain = _B(0)
        self._check(self.lib.SNESGetFunctionDomainError(snes, ctypes.byref(domain)))
        return bool(domain.value)

    def _residual(self, snes, X, Y, W, F, lam: float) -> float:
        """‖F(X − λY)‖² into F, W = X − λY; inf where F is not finite or the domain was left."""
        self._check(self.lib.VecWAXPY(W, _D(-lam), Y, X))
        left = self._evaluate(snes, W, F)
        norm = _D(0.0)
        self._check(self.lib.VecNorm(F, _NORM_2, ctypes.byref(norm)))
        return math.inf if left or not math.isfinite(norm.value) else norm.value ** 2

    def _apply(self, ls, _ctx) -> int:
        try:
            self._search(_P(ls))
        except PETSc.Error as exc:
            return exc.ierr or 1
        except Exception:                                   # noqa: BLE001 - a C callback: a bug here
            traceback.print_exc()
            return 1
        return 0

    def _search(self, ls) -> None:
        lib = self.lib
        X, F, Y, W, snes = _P(), _P(), _P(), _P(), _P()
        self._check(lib.SNESLineSearchGetVecs(ls, *(ctypes.byref(v) for v in (X, F, Y, W)), None))
        self._check(lib.SNESLineSearchGetSNES(ls, ctypes.byref(snes)))
        xnorm, gnorm, ynorm, lam = _D(), _D(), _D(), _D()
        self._check(lib.SNESLineSearchGetNorms(ls, ctypes.byref(xnorm), ctypes.byref(gnorm), ctypes.byref(ynorm)))
        self._check(lib.SNESLineSearchGetLambda(ls, ctypes.byref(lam)))
        steptol, maxstep, rtol, atol, ltol, max_its = _D(), _D(), _D(), _D(), _D(), ctypes.c_int32()
        self._check(lib.SNESLineSearchGetTolerances(ls, *(ctypes.byref(v) for v in (
            steptol, maxstep, rtol, atol, ltol, max_its))))
        changed = _B(0)
        self._check(lib.SNESLineSearchPreCheck(ls, X, Y, ctypes.byref(changed)))
        self.steps += 1
        f0, lam, limit = gnorm.value ** 2, lam.value, maxstep.value
        f1 = self._residual(snes, X, Y, W, F, lam)
        while not math.isfinite(f1):                        # l2: cut λ until F is finite
            if lam <= steptol.value:
                self._check(lib.SNESLineSearchSetReason(ls, _FAILED_REDUCT))
                return
            limit, lam = 0.95 * lam, 0.5 * lam
            f1 = self._residual(snes, X, Y, W, F, lam)
        if f1 <= ACCEPT ** 2 * f0:
            self.full_steps += 1
            self._finish(ls, snes, X, Y, W, F, lam, evaluated=True)
            return
        fmid = self._residual(snes, X, Y, W, F, 0.5 * lam)
        step = secant_minimum(f0, fmid, f1, lam)
        if step is not None and step < steptol.value:
            step = 0.5 * lam
        if step is not None and step <= limit:
            lam = step
        self._finish(ls, snes, X, Y, W, F, lam, evaluated=False)
        if lam <= steptol.value:
            self._check(lib.SNESLineSearchSetReason(ls, _FAILED_REDUCT))

    def _finish(self, ls, snes, X, Y, W, F, lam: float, evaluated: bool) -> None:
        """X ← X − λY after the post-check, F at it (kept where it was evaluated there), norms."""
        lib = self.lib
        if not evaluated:
            self._check(lib.VecWAXPY(W, _D(-lam), Y, X))
        self._check(lib.SNESLineSearchSetLambda(ls, _D(lam)))
        changed_y, changed_w = _B(0), _B(0)
        self._check(lib.SNESLineSearchPostCheck(ls, X, Y, W, ctypes.byref(changed_y), ctypes.byref(changed_w)))
        if changed_y.value and not changed_w.value:
            self._check(lib.VecWAXPY(W, _D(-lam), Y, X))
        self._check(lib.VecCopy(W, X))
        if (not evaluated or changed_y.value or changed_w.value) and self._evaluate(snes, X, F):
            self._check(lib.SNESLineSearchSetReason(ls, _FAILED_DOMAIN))
            return
        self._check(lib.SNESLineSearchComputeNorms(ls))


def secant_minimum(f0: float, fmid: float, f1: float, lam: float) -> float | None:
    """PETSc l2's step from ‖F‖² at 0, λ/2 and λ: the secant (Newton) step on the parabola's
    one-sided derivatives, always downhill; None at a critical-point breakdown (f'' = 0 or not
    finite), where l2 keeps λ."""
    d1 = (3.0 * f1 - 4.0 * fmid + f0) / lam
    d0 = (-3.0 * f0 + 4.0 * fmid - f1) / lam
    d2 = (d1 - d0) / lam
    if d2 == 0.0:
        return None
    step = lam - d1 / d2 if d2 > 0.0 else lam + d1 / d2
    return step if math.isfinite(step) else None


def install_full_step_first(snes: PETSc.SNES, linesearch: str, enabled: bool,
                            prefix: str = "") -> FullStepFirst | None:
    """The line search of ``snes`` where PETSc's own would be l2 with one secant iteration and
    no objective (``enabled``: ``solver.full_step_first`` and no energy merit), else None."""
    max_it = option("snes_linesearch_max_it", prefix)
    if not enabled or linesearch != "l2" or (max_it is not None and max_it.strip() != "1"):
        return None
    return FullStepFirst(snes)
