"""A level inside a gap of the load path (solving/step_over.py): the second subject's sliding 180°
gastrocnemius-biased column (4 elements) in levels of 1000, 1200 and 1600 N has no equilibrium
from ~1599.3 N to past 1616 N (a contact point on a C0 edge of the soleus); its level of 1600 N
is reported at 1640 N (10 % of its 400 N increment past it), near the state a direct step to
1640 N converges to; 2 and 3 ranks: tests/parallel/test_mpi.py.  (Until the outlines were
started at their farthest vertex, geometry_input/polyline.py, the gap was the 30°
soleus-biased column's at 2500 N; that column now has none.)"""
import re

import numpy as np
import pytest

from ancf_petsc import status
from ancf_petsc.solving.records import StepRecord
from ancf_petsc.solving.run import final_status
from ancf_petsc.solving.step_over import CREEP_FAILURES
from ancf_petsc.workflows.envelope import SUBJECT2, EnvelopeCell, cell_config

from solving.test_fade_switch import run


def gap_column(last: float = 1600.0, step_over: bool = True) -> dict:
    """The column to ``last`` in three levels (a coarser min_increment: fewer halvings into the gap)."""
    raw = cell_config(EnvelopeCell(SUBJECT2, 180.0, "gastrocnemius", "sliding", levels=(1000.0, 1200.0, last)))
    raw["output"] = {"vtk": False}
    raw["solver"] = dict(raw.get("solver") or {}, min_increment=0.05, step_over_jumps=step_over)
    return raw


def tips(summary: dict) -> np.ndarray:
    return np.array([p["displacement"] for p in summary["steps"][-1]["probes"].values()])


@pytest.mark.slow
def test_a_level_in_a_gap_is_reported_just_past_it(tmp_path):
    res = run(gap_column(), tmp_path / "over")
    s = res.summary
    assert res.status == "completed" and s["reason_code"] == status.LEVELS_PASSED_OVER, res.message
    last = s["steps"][-1]
    # 1600 + 0.1 of the level's increment (400 N): step_over.STEP_OVER's last share
    assert last["load_factor"] == pytest.approx(1640.0, abs=1e-9) and last["residual_norm"] < 1e-6
    gap = last["passed_over"]
    # stepped over at the CREEP_FAILURES-th failure at the level, not after every halving
    assert last["cutbacks"] == CREEP_FAILURES, last["cutbacks"]
    assert gap["level"] == 1600.0 and 1590.0 < gap["last_converged"] < 1600.0 and gap["reported_at"] == last["load_factor"]
    assert "1600 at 1640" in res.message and "not reached where the residual jumps" in res.message
    # the state a direct step from 1200 N to 1640 N reaches: near it
    direct = run(gap_column(1640.0), tmp_path / "direct")
    assert direct.status == "completed" and direct.summary["reason_code"] == status.COMPLETED
    assert np.abs(tips(s) - tips(direct.summary)).max() < 1e-3 * np.abs(tips(direct.summary)).max()


@pytest.mark.slow
def test_without_the_step_over_the_level_fails_on_the_jump(tmp_path):
    """``solver.step_over_jumps: false``: the column stops below the level, naming the C0 kink."""
    raw = gap_column(step_over=False)
    raw["contact"]["fade_forces"] = "variational"        # no switch to pointwise forces after it
    res = run(raw, tmp_path)
    assert res.status == "failed" and res.summary["failure_cause"] == "c0_kink", res.message
    last = float(re.search(r"\(last converged ([0-9.]+)\)", res.message).group(1))
    assert 1599.0 < last < 1600.0, res.message


@pytest.mark.slow
def test_a_run_with_a_level_passed_over_restarts(tmp_path):
    """The column whose 1600 N is reported at 1640 N, restarted (with 1700 N added) was refused:
    'the config's steps differ from the run's converged levels at step 3: 1640 was solved, the
    config asks for 1600; restart with the steps that made them', its own steps.  Now it goes on
    to the uninterrupted run's 1700 N (1e-10) and still says the level was passed over."""
    whole = run(dict(gap_column(), steps=[1000.0, 1200.0, 1600.0, 1700.0]), tmp_path / "whole")
    assert whole.status == "completed" and whole.summary["steps"][2]["passed_over"], whole.message
    assert run(gap_column(), tmp_path / "run").summary["reason_code"] == status.LEVELS_PASSED_OVER
    res = run(dict(gap_column(), steps=[1000.0, 1200.0, 1600.0, 1700.0]), tmp_path / "run",
              restart=str(tmp_path / "run"))
    assert res.status == "completed" and res.summary["reason_code"] == status.LEVELS_PASSED_OVER, res.message
    assert [s["load_factor"] for s in res.summary["steps"]] == [1000.0, 1200.0, 1640.0, 1700.0]
    assert np.abs(tips(res.summary) - tips(whole.summary)).max() <= 1e-10 * np.abs(tips(whole.summary)).max()


@pytest.mark.slow
def test_a_level_the_step_over_passed_too_is_reported_with_it(tmp_path):
    """Levels of 1600 and 1600.2 N: the step over of 1600 N lands at 1640 N, past 1600.2 N too,
    and the run stopped with a traceback (UnboundLocalError in stepper._reach: nothing left to
    solve for 1600.2 N), also on a restart after 1600 N.  Now 1600.2 N is reported at 1640 N
    as well, passed over from the same state, and the run goes on to 1700 N."""
    steps = [1000.0, 1200.0, 1600.0, 1600.2, 1700.0]
    whole = run(dict(gap_column(), steps=steps), tmp_path / "whole")
    s = whole.summary
    assert whole.status == "completed" and s["reason_code"] == status.LEVELS_PASSED_OVER, whole.message
    assert [st["load_factor"] for st in s["steps"]] == [1000.0, 1200.0, 1640.0, 1640.0, 1700.0]
    first, second = s["steps"][2], s["steps"][3]
    assert second["passed_over"] == dict(first["passed_over"], level=1600.2) and second["iterations"] == 0
    assert second["probes"] == first["probes"]
    assert "1600 at 1640 (not reached from 1596.88), 1600.2 at 1640 (not reached" in whole.message
    assert run(gap_column(), tmp_path / "run").summary["reason_code"] == status.LEVELS_PASSED_OVER
    # restarted after 1600 N to 1600.2 N, then after 1600.2 N to 1700 N (the increment the level
    # passed over with 2500 N hands on is the path's: it was 0 from a restart's last level)
    res = run(dict(gap_column(), steps=steps[:4]), tmp_path / "run", restart=str(tmp_path / "run"))
    assert res.status == "completed" and res.summary["steps"][3]["passed_over"]["level"] == 1600.2, res.message
    res = run(dict(gap_column(), steps=steps), tmp_path / "run", restart=str(tmp_path / "run"))
    assert res.status == "completed" and len(res.summary["steps"]) == 5, res.message
    assert np.abs(tips(res.summary) - tips(s)).max() <= 1e-10 * np.abs(tips(s)).max()


def record(lam: float, passed=None, unsettled=False) -> StepRecord:
    return StepRecord(load_factor=lam, iterations=3, substeps=1, cutbacks=0, reason="CONVERGED_FNORM_ABS",
                      residual_norm=1e-9, wall_time=0.0, weights_unsettled=unsettled, passed_over=passed)


def test_the_final_status_names_the_levels_passed_over():
    state, code, message = final_status([record(1.0), record(2.001, (2.0, 1.9996, 2.001))], None, False)
    assert (state, code) == ("completed", status.LEVELS_PASSED_OVER)
    assert message.startswith("completed, but 1 level(s) not reached where the residual jumps") and "2 at 2.001 (not reached from 1.9996)" in message
    state, code, message = final_status([record(1.0, unsettled=True), record(2.001, (2.0, 1.9996, 2.001))], None, False)
    assert code == status.LEVELS_PASSED_OVER and "contact weights not settled at 1 of 2 levels" in message
    assert final_status([record(1.0), record(2.0)], None, False) == ("completed", status.COMPLETED, "completed")


def test_no_step_over_past_a_history_last_frame():
    """Past a load curve's last point the loads are held: a solve there is the level itself
    (step_over.py skips it: petsc/loading.py ``AppliedLoads.unchanged``)."""
    from petsc4py import PETSc
    from ancf_petsc.model.loading import LoadCurve, LoadGroup
    from ancf_petsc.petsc.loading import AppliedLoads

    def applied(groups):
        vec = lambda a: PETSc.Vec().createWithArray(np.array(a, dtype=float), comm=PETSc.COMM_SELF)
        return AppliedLoads(groups, [vec(g.forces) for g in groups], [vec(g.moves) for g in groups], vec([0, 0]))
    force = np.array([0.0, 1.0])
    proportional = LoadGroup(None, np.zeros(2), np.zeros(2))       # empty: λ moves nothing
    history = LoadGroup(LoadCurve(((1.0, 0.0), (2.0, 1.0), (3.0, 0.5))), force, np.zeros(2))
    assert not applied([proportional, history]).unchanged(2.0, 2.001)
    assert applied([proportional, history]).unchanged(3.0, 3.001)
    assert not applied([LoadGroup(None, force, np.zeros(2))]).unchanged(3.0, 3.001)
