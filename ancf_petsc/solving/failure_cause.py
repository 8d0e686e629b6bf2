"""What stopped a failed run, as one code (summary.json ``failure_cause``, the envelope's ``cause``).

The failure message says it in words (solver_messages.py, continuity.py, critical_point.py); the
code lets a sweep count its failures by cause: on the gait envelope a kink of B's C⁰ surface, a
critical point of the load path and Newton's course call for different fixes (docs/gait.md).
A failure that has several findings takes the most specific one, in this order: an inverted
element, a contact point lost from its search window, a jump of the residual (what the contact's
projections show changing there), a critical point of the tangent, a less stable state on the
way, half the failed step below ``solver.min_increment``, then Newton's course.
"""
from __future__ import annotations

#: the codes, with what each means (docs/running.md, "summary.json")
CAUSES = {
    "inverted_element": "an element's Jacobian determinant reached zero (J <= 0)",
    "projection_lost": "a contact point's closest-point projection failed or left its search window",
    "c0_kink": "a contact point has its closest point on two B elements at their common node: B's "
               "surface is only C0 there, and the residual jumps",
    "two_closest_points": "a contact point has two closest places on B about as near, and the residual jumps",
    "fade_weight_jump": "a contact point's fade weight jumps between two nearby states",
    "residual_jump": "the residual jumps between two nearby states (not explained by the contact)",
    "critical_point": "the tangent at the last converged state is nearly singular on a mode of the beams: "
                      "a limit or bifurcation point that load control cannot pass",
    "unstable_state": "a converged state on the way was less stable than the last accepted one",
    "min_increment": "half the failed step is below solver.min_increment: no cut-back was tried",
    "linear_solver": "the linear solver failed",
    "violated_state": "the solves converged on active sets that violate unilateral contact",
    "newton_cycle": "Newton's residual norms repeat with a period of 2 or more",
    "newton_stall": "Newton's residual norm stalls above the tolerance",
    "newton_wander": "Newton's iterates neither converge nor repeat",
    "newton_linear": "Newton converges only linearly (a nearly singular tangent)",
    "friction_statuses": "friction's stick-slip statuses do not settle",
    "active_set_iterations": "unilateral contact's active set still changed when the iterations ran out",
    "newton_budget_exceeded": "the run spent solver.max_newton_iterations",
    "newton_budget": "a solve ran out of a -snes_max_it given below the run's own budget",
    "unreachable_tolerance": "a -snes_atol given below 20 x the residual's rounding floor: Newton cannot reach it",
    "nonlinear_method": "a -snes_type other than Newton, a -snes_lag_jacobian or -snes_lag_preconditioner "
                        "other than 1, or a -snes_linesearch_damping below 1 was given in the run's options "
                        "and did not converge",
    "step_tolerance": "a -snes_stol given above the run's own ended solves on the step length before |F| was small",
    "rounding_noise": "|F| is at the residual's rounding at the failing state, above the run's absolute "
                      "tolerance (stiff terms magnify the rounding of the positions)",
    "petsc_error": "PETSc or an external package raised an error (e.g. MUMPS could not factor the tangent)",
}
# (any other failure: its SNES reason in lower case, e.g. diverged_fnorm_nan)
#: the codes of a jump of the residual (continuity.py ``Jump.kind``)
JUMP_CAUSES = ("c0_kink", "two_closest_points", "fade_weight_jump", "residual_jump")
#: the findings that come before a critical point in the order (module docstring)
BEFORE_CRITICAL = ("inverted_element", "projection_lost") + JUMP_CAUSES + ("rounding_noise",)


class Detail(str):
    """A part of a failure message (its text) that knows its cause code (``kind``)."""
    kind: str

    def __new__(cls, text: str, kind: str = "") -> "Detail":
        out = super().__new__(cls, text)
        out.kind = kind
        return out


def give_up_cause(inverted: bool, lost: bool, jump, unstable_at: tuple | None, newton: str) -> str:
    """The code of a level given up by the stepper (module docstring's order): ``jump`` the
    residual's jump (continuity.Jump) or None, ``unstable_at`` the level's less stable state or
    None, ``newton`` the message part on Newton's course (a ``Detail``, or plain text: "")."""
    if inverted:
        return "inverted_element"
    if lost:
        return "projection_lost"
    if jump is not None:
        return jump.kind
    if unstable_at is not None:
        return "unstable_state"
    return getattr(newton, "kind", "")


def with_critical_point(cause: str) -> str:
    """The code once the tangent at the last converged state shows a critical point: that, unless
    a finding before it in the order explains the failure."""
    return cause if cause in BEFORE_CRITICAL else "critical_point"
