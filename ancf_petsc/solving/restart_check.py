"""Is a restart's stored state an equilibrium?  ``io.restart`` checks that the stored model is
the config's; this checks the state itself: the residual of the stored nodal vectors (and contact
multipliers) at the stored load factor must be at the tolerance the level was accepted at.  A
results.h5 damaged or changed since (a flipped bit, a state vector edited or copied from another
run) is refused with one line, instead of a run that fails levels later ("an element was
inverted") or continues from a wrong state.
"""
from __future__ import annotations

import math

from ..contact import forget_evaluation
from ..errors import InputError
from ..io.restart_probes import check_same_probes

#: a stored level's residual recomputed may exceed the one recorded only by rounding (another
#: rank count sums in another order): this factor, on top of the rounding floor
SLACK = 10.0


def stored_residual(problem, X, load_factor: float) -> float:
    """‖F(X, λ)‖ at the stored load factor (collective; nan if an element is inverted)."""
    lam = problem.load_factor
    problem.load_factor = load_factor
    F = problem.F.duplicate()
    try:
        problem.residual(None, X, F)
        return float(F.norm())
    finally:
        problem.load_factor = lam
        F.destroy()


def fade_modes(problem):
    """Iterate over the residuals a stored level may have converged with: with the fade weights
    differentiated (``contact.fade: newton``) a level's last solve used the partner places' own
    weights and their variation (the force −p g ∇w of a point in a fade band), but for a level
    from rest whose kept weights needed no update (contact/weights.py): the differentiated
    residual first, then the kept one; one residual otherwise.  The mode is left as it was."""
    c = getattr(problem, "contact", None)
    w = getattr(c, "weights", None)
    if w is None or w.rule != "newton":
        yield None
        return
    before = w.differentiated
    try:
        for mode in (True, False):
            w.differentiated = mode
            forget_evaluation(c)
            yield mode
    finally:
        w.differentiated = before
        forget_evaluation(c)


def allowed_residual(atol: float, recorded: float | None, rounding_floor: float) -> float:
    """The largest residual the stored level may show: its acceptance test (the absolute
    tolerance, or the residual it was accepted with) with room for rounding."""
    return max(atol, SLACK * (recorded or 0.0), 20.0 * rounding_floor)


def check_restart_state(problem, stepper, point, X, directory: str) -> None:
    """InputError on every rank (the norm is collective) if the stored state at ``point`` is not
    converged, or (then) if the config's probes measure other places at it."""
    steps = point.summary.get("steps") or []
    recorded = steps[-1].get("residual_norm") if steps else None
    _, atol, _, _ = stepper.solver.snes.getTolerances()
    bound = allowed_residual(atol, recorded, stepper.solver.rounding_floor)
    sound = False
    for _ in fade_modes(problem):
        fnorm = stored_residual(problem, X, point.load_factor)
        if math.isfinite(fnorm) and fnorm <= bound:
            sound = True
            break
    if sound:
        check_same_probes(point, problem.model, directory)
        return
    what = ("an element of it is inverted (J <= 0)" if not math.isfinite(fnorm)
            else f"its residual |F| = {fnorm:.3e} is above the tolerance {bound:.3e}"
            + (f" (recorded when it converged: {recorded:.3e})" if recorded is not None else ""))
    raise InputError("--restart", f"the stored state of level {point.step} (load factor "
                     f"{point.load_factor:g}) in {directory}/results.h5 is not an equilibrium: "
                     f"{what}; the file was changed or damaged since: run afresh with --output-dir")
