"""``solver.min_increment`` above half the spacing of the load levels: a failed step cannot be cut
back at all.  The config is valid (a run whose steps all converge never cuts back), so it is not
refused; a level that fails for that reason says so instead of diagnosing Newton's course ("the
iterates wander", "a nearly singular tangent", which it gave before)."""
from __future__ import annotations

import pytest

from helpers import ONE_AND_TWO_RANKS
from test_edges import assert_one_line, run_cfg, tiny

from ancf_petsc.solving.load_control import LevelTally, LoadControl
from ancf_petsc.config.specs import SolverSpec


def heavy(**solver) -> dict:
    """The two-element bar pulled 44 times harder than the test bar: the first level (0.5) needs
    cut-backs (with them it completes)."""
    raw = tiny(solver=solver)
    raw["loads"][0]["traction_force"] = [2000.0, 0.0, 0.0]
    return raw


@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_a_min_increment_that_forbids_every_cut_back_is_named_at_the_failure(tmp_path, ranks):
    p = run_cfg(tmp_path, heavy(min_increment=0.3), ranks)
    line = assert_one_line(p, 3, "could not reach load factor 0.5: SNES failed at load factor 0.5 (last "
                           "converged 0) with DIVERGED_MAX_IT (no cut-back was tried: half the failed "
                           "step from load factor 0 to 0.5 is 0.25, below solver.min_increment = 0.3; "
                           "lower solver.min_increment to at most 0.25")
    assert "wander" not in line and "singular" not in line and "limit" not in line


def test_the_same_model_completes_with_cut_backs(tmp_path):
    p = run_cfg(tmp_path, heavy(), 1)
    assert p.returncode == 0, p.stderr


def test_a_valid_config_with_a_large_min_increment_is_not_refused(tmp_path):
    """min_increment above the level spacing, but no step fails: the run completes."""
    p = run_cfg(tmp_path, tiny(solver={"min_increment": 0.6}), 1)
    assert p.returncode == 0, p.stderr


def test_floored_only_when_no_cut_back_was_tried():
    control = LoadControl(SolverSpec(min_increment=0.3, max_cutbacks=12))
    tally = LevelTally()
    dlam, give_up = control.after_failure(0.5, False, tally)
    assert give_up and control.floored(0.5, tally)
    assert control.stop_reason(dlam, tally) == "the increment 0.25 would be below solver.min_increment = 0.3"
    control = LoadControl(SolverSpec(min_increment=0.2, max_cutbacks=12))   # one cut-back, then the floor
    tally = LevelTally()
    dlam, give_up = control.after_failure(0.5, False, tally)
    assert not give_up and dlam == 0.25
    dlam, give_up = control.after_failure(dlam, False, tally)
    assert give_up and not control.floored(0.25, tally)
    control = LoadControl(SolverSpec(min_increment=0.3, max_cutbacks=0))    # max_cutbacks decides
    tally = LevelTally()
    dlam, give_up = control.after_failure(0.5, False, tally)
    assert give_up and not control.floored(0.5, tally)
    assert control.stop_reason(dlam, tally) == "1 failures in a row (solver.max_cutbacks = 0)"


def test_not_floored_where_the_level_crept_on_by_cut_backs():
    """A level whose cut-backs shrank the step, then accepted sub-steps, then failed at a step
    whose half is below the floor: cut-backs were tried, so Newton's cause is named, not the
    floor (the 180° soleus-biased unilateral stride at frame 41.84)."""
    control = LoadControl(SolverSpec(min_increment=2e-4, max_cutbacks=12))
    tally = LevelTally()
    step = 1.0
    for _ in range(12):                                   # 1 → 2**-12, below twice the floor
        step, give_up = control.after_failure(step, False, tally)
        assert not give_up
    tally.consecutive = 0                                 # a sub-step converged (stepper._accept)
    dlam, give_up = control.after_failure(step, False, tally)
    assert give_up and not control.floored(step, tally)
    assert control.stop_reason(dlam, tally).startswith("the increment 0.0001221 would be below")
