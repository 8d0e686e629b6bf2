"""A SNES convergence test that stops a Newton iteration caught in a cycle (issue 39).

Coulomb friction's semi-smooth iteration can cycle between stick and slip statuses: |F| repeats
with a period of 2–3 iterations until ``snes_max_it`` (measured on the paper's tendon, μ = 3, the
load step 90 → 100 N: period 3, |F| 0.62 / 0.41 / 0.37 N from the 15th iteration to the 200th).
This test is PETSc's default (SNESConvergedDefault, restated: rtol, atol, stol, the function
budget and the divergence tolerance) plus one rule: from ``MIN_ITERATIONS`` on, a cycle of
period ≥ 2 (``solver_messages.newton_cycle``) ends the solve as DIVERGED_MAX_IT, so the increment
goes to friction's Tresca fixed point or a cut-back at once.  A second rule ends a solve that
wanders: no new smallest |F| in the last ``WANDER_WINDOW`` iterations (the μ = 0.3 walking stride
at 4 elements, frame 12 with the fade weights differentiated: |F| between 1 and 750 N for 196
iterations after its best, 1.03 N at the 4th, before friction's ``snes_max_it`` 200 sent it to
the Tresca fixed point, which converged).  A stall (period 1) is left to the other tests.  It is installed for models whose contact has state-dependent bounds (friction)
unless ``-snes_convergence_test`` is given.

A unilateral law installs it too, with its own window (``UnilateralLaw.wander_window``, 15): its
default ``-snes_max_it`` 60 lets a Newton iteration whose active set settles late go on while
|F| still finds new lows, and the window ends one that has stopped finding them after as many
iterations as the general budget gave every solve before (docs/gait.md, 2026-11-29).
"""
from __future__ import annotations

import math

from petsc4py import PETSc

from ..linalg.database import option
from .solver_messages import newton_cycle

#: iterations before a cycle may end a solve (a status change needs a few iterations to show)
MIN_ITERATIONS = 12
#: iterations without a new smallest |F| that end a solve as wandering (``wandering``)
WANDER_WINDOW = 40
#: PETSc's default divergence tolerance (fnorm > divtol × |F₀|: DIVERGED_DTOL)
DEFAULT_DIVTOL = 1.0e4

Reason = PETSc.SNES.ConvergedReason


class CycleStop:
    """``snes.setConvergenceTest(CycleStop(history, config_options, prefix))``; ``history()``
    the |F| of the solve's iterates so far (the monitor's, called before the test); the
    divergence tolerance and forced first iteration from the command line or the config's
    ``petsc:`` (else ``divtol``); ``cycle`` the (period, min, max |F|) of the cycle that ended the
    last solve, or None."""

    def __init__(self, history, config_options: dict, prefix: str = "", window: int = WANDER_WINDOW,
                 divtol: float = DEFAULT_DIVTOL):
        self.history = history
        self.window = window

        def given(name: str):
            value = option(name, prefix)
            return config_options.get(name) if value is None else value
        self.divtol = float(given("snes_divergence_tolerance") or divtol)
        self.force = str(given("snes_force_iteration") or "false").lower() in ("", "1", "true", "yes")
        self.ttol = self.rnorm0 = 0.0
        self.cycle: tuple[int, float, float] | None = None
        self.wandered = False           # the last solve ended on the window's rule

    def __call__(self, snes: PETSc.SNES, its: int, norms) -> int:
        xnorm, snorm, fnorm = norms
        rtol, atol, stol, _ = snes.getTolerances()
        if its == 0:
            self.ttol, self.rnorm0, self.cycle, self.wandered = fnorm * rtol, fnorm, None, False
        if math.isnan(fnorm) or math.isinf(fnorm):
            return Reason.DIVERGED_FNORM_NAN
        if fnorm < atol and (its > 0 or not self.force):
            return Reason.CONVERGED_FNORM_ABS
        max_funcs = snes.getMaxFunctionEvaluations()
        if max_funcs >= 0 and snes.getFunctionEvaluations() >= max_funcs:
            return Reason.DIVERGED_FUNCTION_COUNT
        if its == 0:
            return Reason.ITERATING
        if fnorm <= self.ttol:
            return Reason.CONVERGED_FNORM_RELATIVE
        if snorm < stol * xnorm:
            return Reason.CONVERGED_SNORM_RELATIVE
        if self.divtol > 0 and fnorm > self.divtol * self.rnorm0:
            return Reason.DIVERGED_DTOL
        if its >= MIN_ITERATIONS:
            cycle = newton_cycle(self.history())
            if cycle is not None and cycle[0] >= 2:
                self.cycle = cycle
                return Reason.DIVERGED_MAX_IT
            if wandering(self.history(), self.window):
                self.wandered = True
                return Reason.DIVERGED_MAX_IT
        return Reason.ITERATING


def wandering(history: list[float], window: int = WANDER_WINDOW) -> bool:
    """True when none of the last ``window`` norms is below the smallest before them."""
    if len(history) <= window:
        return False
    return min(history[-window:]) >= min(history[:-window])
