"""``ancf-report --existing`` on a paper column whose config asked for some of Table 1's levels
only: the others were not asked, not 'not reached' (which says the run stopped before them)."""
import os

from helpers import paper_column, report_existing, solved_run


def test_levels_a_completed_column_did_not_ask_for_are_not_called_not_reached(tmp_path):
    """The paper's tendon (psi 45) solved at 10 and 400 N only, completed: Table 1 said 'not
    reached' at the 11 levels between and 'ψ = 45°: not reached 20, ..., 300 N (the run ended
    completed)'; now 'not asked'.  A column that failed keeps 'not reached' (test_achilles.py)."""
    raw = paper_column()
    raw["steps"], raw["output"] = [10.0, 400.0], {"vtk": False}
    text = report_existing([solved_run(raw, tmp_path)], tmp_path / "rep")
    assert "| not reached |" not in text and "ψ = 45°: not reached" not in text
    assert "ψ = 45°: not asked 20, 30, 40, 45, 60, 80, 90, 100, 150, 200, 300 N (not among the run's steps)" in text
    assert "| 100 | 1.481 | not asked |  |" in text and "| 400 | 6.187 | 6.205 | +0.28 % |" in text


def test_a_killed_column_is_not_said_to_have_ended_running():
    """A paper column killed at 100 N (summary.json still 'running'): 'not reached 150, 200, 300,
    400 N (the run ended running)'; now it says the run has no final status."""
    from ancf_petsc import paper as rp
    from ancf_petsc.paper.existing import levels_missing
    from helpers import PAPER_INPUTS
    loads = rp.read_paper(PAPER_INPUTS.table1_csv)["load_N"][:9]
    probes = {k: {"displacement": [1e-3, 0.0, 0.0]} for k in ("soleus", "medial_gastrocnemius", "lateral_gastrocnemius")}
    killed = {"status": "running", "steps": [{"load_factor": float(f), "probes": probes} for f in loads]}
    t1 = rp.table1_from(PAPER_INPUTS, {45: killed})
    assert levels_missing(t1, {45: killed}) == ("ψ = 45°: not reached 150, 200, 300, 400 N (the run has no final "
                                               "status: still running, or killed)")


def test_a_column_that_reached_no_level_draws_no_empty_slip_chart(tmp_path):
    """The paper's column failing at its first level (a Newton budget of 2): ancf-report drew
    slip_psi45.png with no level on it, axes and the title 'the soleus slides past the
    gastrocnemius subtendons' only."""
    raw = paper_column()
    raw["solver"], raw["output"] = {"max_newton_iterations": 2}, {"vtk": False}
    text = report_existing([solved_run(raw, tmp_path, returncode=3)], tmp_path / "rep")
    assert not os.path.exists(tmp_path / "rep" / "slip_psi45.png")
    assert "ψ = 45°: not reached 10, 20" in text
