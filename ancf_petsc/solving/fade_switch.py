"""The pointwise fade forces for the levels the variational ones cannot reach
(``contact.fade_forces: auto``, the default without a tangential law).

With ``contact.fade: newton`` a contact point in a fade band pushes either with the weighted
gap's exact variation, −p ∇(w g) (``variational``: a symmetric Jacobian, LDLᵀ, its inertia and
branch switching), or with τ_p ∇g_p (``pointwise``: an unsymmetric Jacobian, LU); docs/contact.md,
"The weights' forces".  Neither converges everywhere the other does (docs/gait.md): on the four
unilateral envelope grids 13 cells completed with pointwise forces only and 4 with variational
ones only; with ``auto`` 145 of the 156 complete (135 before, none lost).

``auto`` starts with variational forces; when a level cannot be reached (its cut-backs spent, no
branch to switch to, no sub-step on a less stable state) the run goes on from the last converged
state with pointwise forces to its end, its stability no longer checked.  The Jacobian
is then AIJ and the SNES, its LU and the predictors are built again; the load factor of the
switch is in the log, the final message, summary.json (``fade_forces_pointwise_from``) and each
later level's restart data, so that a restart goes on as the run did.
"""
from __future__ import annotations

from ..contact import forget_evaluation
from ..errors import InputError
from ..linalg.options import SYMMETRIC_PCS, factor_package, matrix_type
from ..petsc.aij_blocks import jacobian_matrix
from ..petsc.complementarity import ComplementarityPredictor
from ..petsc.potential import set_near_null_space
from .predictor import TangentPredictor
from .snes_solver import SNESSolver


def switchable(problem, matrix: str, petsc_options: dict, prefix: str, linear: str) -> bool:
    """Whether the run may switch: ``auto`` forces, differentiated weights (with ``settle`` both
    forms are one), the direct solver, and options that allow an AIJ matrix and LU (a config
    that asks for LDLᵀ or SBAIJ keeps the variational forces)."""
    c = problem.contact
    if c is None or c.spec.fade_forces != "auto" or not c.weights.symmetric or c.weights.rule != "newton":
        return False
    if linear != "direct" or factor_package(petsc_options, prefix, False)[0] in SYMMETRIC_PCS:
        return False
    try:
        matrix_type(problem.model, matrix, petsc_options, prefix, linear, False)
    except InputError:
        return False
    return True


class FadeForcesSwitch:
    """The stepper's one switch from variational to pointwise fade forces (``at``: the last
    converged load factor when it was made, None before)."""

    def __init__(self, stepper, petsc_options: dict, max_level: float, linear: str):
        self.matrix = stepper.spec.matrix
        self.enabled = switchable(stepper.problem, self.matrix, petsc_options, stepper.spec.options_prefix, linear)
        self.args = (petsc_options, max_level, linear)
        self.at: float | None = None

    def take(self, stepper, path, tally) -> bool:
        """At a give-up: switch (logged) and start the level again from ``path`` with the
        increment of its first attempt; False when switched already, not allowed, or when a
        sub-step of the level converged to a less stable state (a limit or bifurcation point:
        LU has no inertia to see it, so the failure stands).  Collective (the give-up is decided
        on the SNES reason and the inertia, the same on every rank)."""
        if not self.enabled or self.at is not None or tally.unstable_at is not None:
            return False
        self.switch(stepper, path.lam)
        stepper.log(f"  load factor {path.lam:.6g}: the variational fade forces reach no further; on "
                    "with the pointwise ones (contact.fade_forces: auto; LU, no inertia)")
        tally.consecutive = 0
        path.dlam = tally.first_failed or path.dlam
        return True

    def summary(self, stepper) -> dict:
        """summary.json's record of the switch, with the solver the run ended with (nothing
        without a switch)."""
        return {} if self.at is None else {"fade_forces_pointwise_from": self.at, "solver": stepper.describe()}

    def note(self) -> str:
        """What the final message adds after a switch."""
        return "" if self.at is None else f" (pointwise fade forces from load factor {self.at:g})"

    def resume(self, stepper, at: float | None, directory: str) -> None:
        """A restart of a run that switched at ``at`` (None: it did not): switch again (nothing to
        do with ``pointwise`` forces); InputError if the config keeps the variational ones."""
        if at is None or not stepper.problem.contact.weights.variational:
            return
        if not self.enabled:
            raise InputError("--restart", f"{directory} went on with pointwise fade forces from load factor "
                                          f"{at:g} (contact.fade_forces: auto); restart with auto or pointwise")
        self.switch(stepper, at)

    def switch(self, stepper, at: float) -> None:
        """Pointwise forces from load factor ``at`` on: the weights' form, an AIJ Jacobian with
        its pattern, and the stepper's SNES and predictors for it (collective)."""
        P, c = stepper.problem, stepper.problem.contact
        c.weights.variational = False
        forget_evaluation(c)
        petsc_options, max_level, linear = self.args
        P.matrix_type = P.pattern.matrix_type = matrix_type(
            P.model, self.matrix, petsc_options, stepper.spec.options_prefix, linear, False)
        old = stepper.solver
        stepper.solver.close()
        stepper.solver.destroy()
        if stepper.predictor is not None:
            stepper.predictor.destroy()
        stepper.branches.destroy()              # LU has no inertia: no branch points from here on
        stepper.branches.enabled = False
        P.J.destroy()
        P.J, P.aij_blocks = jacobian_matrix(P.pattern)
        set_near_null_space(P)
        # the floor as measured at the start: measuring it again evaluates the contact at q0
        stepper.solver = SNESSolver(P, stepper.spec, petsc_options, max_level, linear, old.rounding_floor)
        stepper.solver.chord.count, stepper.solver.chord.kept = old.chord.count, old.chord.kept
        stepper.solver.spent = old.spent
        stepper.predictor = (ComplementarityPredictor(P, stepper.solver.snes, stepper.spec.compact_factor)
                             if ComplementarityPredictor.applies(P) else None)
        stepper.tangent = TangentPredictor(P, stepper.solver.snes)
        self.at = at
