"""Contact weights whose fixed point does not settle (contact/weights.py, solving/newton.py): a
level accepted after the last weight update reports the residual with the state's own weights,
never the converged residual of the stale ones."""
from __future__ import annotations

from petsc4py import PETSc

from ancf_petsc.contact.laws import NEWTON
from ancf_petsc.solving.newton import MAX_WEIGHT_UPDATES, PhasedNewton

CONVERGED = PETSc.SNES.ConvergedReason.CONVERGED_FNORM_ABS


class _Steps:
    """A contact law's part whose weights change ``changes`` times (no statuses)."""

    decides_activity = False
    bounded = False            # no friction bounds (contact_steps.ContactSteps.bounded)

    def __init__(self, changes: int):
        self.changes, self.refreshes, self.frozen = changes, 0, False

    def begin_increment(self, from_rest):
        pass

    def phases(self, from_rest):
        return [NEWTON]

    def begin(self, phase, previous):
        pass

    def status_changes(self):
        return 0

    def refresh_weights(self):
        self.refreshes += 1
        return self.refreshes <= self.changes

    def residual_norm(self, X):
        return 3.5e-4


def _solve(changes: int):
    steps, solves = _Steps(changes), []
    newton = PhasedNewton(steps, lambda X: (solves.append(1), (CONVERGED, 2))[1])
    reason, its = newton.solve(None, 1.0, False)
    return newton, steps, reason, its, len(solves)


def test_weights_that_settle_report_nothing():
    newton, steps, reason, its, solves = _solve(changes=2)
    assert reason == CONVERGED and newton.unsettled is None
    assert solves == 3 and its == 6 and steps.refreshes == 3


def test_weights_that_never_settle_report_the_residual_with_their_own_weights():
    newton, steps, reason, its, solves = _solve(changes=10 ** 6)
    assert solves == 1 + MAX_WEIGHT_UPDATES
    # one refresh per update, then the check of the last solve's state
    assert steps.refreshes == MAX_WEIGHT_UPDATES + 1
    assert newton.unsettled == 3.5e-4


def test_weights_that_settle_at_the_last_update_report_nothing():
    newton, steps, reason, its, solves = _solve(changes=MAX_WEIGHT_UPDATES)
    assert solves == 1 + MAX_WEIGHT_UPDATES and newton.unsettled is None


def _record(lam: float, unsettled: bool):
    from ancf_petsc.solving.records import StepRecord
    return StepRecord(load_factor=lam, iterations=3, substeps=1, cutbacks=0, reason="CONVERGED_FNORM_ABS",
                      residual_norm=1e-9, wall_time=0.0, negative_eigenvalues=0,
                      weights_unsettled=unsettled)


def test_a_run_with_unsettled_levels_says_so_in_its_reason_and_message():
    from ancf_petsc import status
    from ancf_petsc.solving.run import final_status
    settled = [_record(0.5, False), _record(1.0, False)]
    assert final_status(settled, None, False) == ("completed", status.COMPLETED, "completed")
    state, code, message = final_status([_record(0.5, False), _record(0.875, True), _record(1.0, True)],
                                        None, False)
    assert (state, code) == ("completed", status.WEIGHTS_UNSETTLED)
    assert "2 of 3 levels" in message and "0.875, 1" in message and "contact.fade: newton" in message
    assert status.exit_code(state, code) == status.EXIT_OK


class _StatusSteps(_Steps):
    """A unilateral law's part whose exact rule changes ``flips`` statuses at a checked state."""

    decides_activity = True

    def __init__(self, flips: int):
        super().__init__(0)
        self.contact, self.checked, self.flips = object(), [], flips

    def update_status(self, X):
        self.checked.append(X)
        return self.flips


def test_the_solve_for_new_weights_is_checked_by_the_exact_rule(monkeypatch):
    """The weights' solve after a failed prediction keeps the status the check before set; its
    state is checked again, and where that changes the status the phases go on (reason None)
    instead of accepting it: accepted unchecked, the 135° uniform unilateral stride's frame 1
    had multipliers pulling (tests/contact/test_gait_envelope.py)."""
    from ancf_petsc.solving import newton as newton_module
    monkeypatch.setattr(newton_module, "forget_evaluation", lambda contact: None)
    for flips, expected in ((3, None), (0, CONVERGED)):
        steps = _StatusSteps(flips)
        newton = PhasedNewton(steps, lambda X: (CONVERGED, 4))
        assert newton._reweigh("X", 1.0, 7, None) == (expected, 11, False)
        assert steps.checked == ["X"]


def test_a_level_given_up_on_violated_conditions_names_them():
    """A level whose every attempt converged on a pending unilateral status ends on
    UNILATERAL_CONDITIONS_VIOLATED, with what that means."""
    from ancf_petsc.solving.records import VIOLATED_STATE, reason_name
    from ancf_petsc.solving.solver_messages import failure_detail
    assert reason_name(VIOLATED_STATE) == "UNILATERAL_CONDITIONS_VIOLATED"
    assert "multiplier pulling" in failure_detail(None, VIOLATED_STATE)
