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


def elastica_in_one_step(unit: float) -> dict:
    """configs/elastica_svk.yaml at P L²/EI = 20 reached in one level, its load factor in units
    of ``unit`` (the force 20 N / unit at load factor ``unit``): the same loads."""
    from helpers import load_raw
    raw = load_raw("elastica_svk.yaml")
    raw["loads"][0]["force"] = [0.0, 0.0, 20.0 / unit]
    raw["steps"] = [unit]
    raw["output"] = {"vtk": False}
    return raw


@pytest.mark.parametrize("unit", [1e-3, 1e-4])
def test_the_cut_backs_do_not_depend_on_the_unit_of_the_load_factor(tmp_path, unit):
    """Before: as 20 N x load factor 1 the elastica took 10 sub-steps to its tip (-0.684, 0.869) L;
    as 2e4 N x 1e-3 the fixed floor 1e-4 left three halvings and the run failed (exit 3, 'Newton's
    iterates wander'), as 2e5 N x 1e-4 no cut-back at all.  Now the default floor is 1e-4 of
    the largest load factor below 1: the same sub-steps and tip to 1e-9."""
    from helpers import run_inline
    base = run_inline(elastica_in_one_step(1.0), tmp_path / "base")
    scaled = run_inline(elastica_in_one_step(unit), tmp_path / "scaled")
    assert base["status"] == scaled["status"] == "completed"
    a, b = base["steps"][-1], scaled["steps"][-1]
    assert (b["substeps"], b["iterations"]) == (a["substeps"], a["iterations"]) and a["substeps"] > 4
    tip_a, tip_b = (s["probes"]["tip"]["displacement"] for s in (a, b))
    assert max(abs(x - y) for x, y in zip(tip_a, tip_b)) < 1e-9 * max(abs(x) for x in tip_a)


def test_the_default_floor_of_load_factors_of_1_or_more_is_1e_4():
    """The paper's column (load factors in N, to 400) and the elastica (to 1) keep 1e-4; load
    factors to 0.04 (in N, for mN loads) get 4e-6; a given min_increment is kept."""
    from helpers import load_raw
    from ancf_petsc.config.parse import parse_config
    from helpers import CONFIGS
    for name, steps, expected in (("achilles_type3_psi45.yaml", None, 1e-4), ("elastica_svk.yaml", None, 1e-4),
                                  ("elastica_svk.yaml", [0.01, 0.04], 4e-6)):
        raw = load_raw(name)
        if steps:
            raw["steps"] = steps
        assert parse_config(raw, base_dir=CONFIGS).solver.min_increment == pytest.approx(expected, rel=1e-12)
    raw = dict(load_raw("elastica_svk.yaml"), steps=[0.01, 0.04], solver={"min_increment": 1e-3})
    assert parse_config(raw, base_dir=CONFIGS).solver.min_increment == 1e-3
