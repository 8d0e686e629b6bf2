"""A restarted run's status, counts and final line cover every level on disk, not only the
levels the restarted process solved."""
from helpers import CONFIGS, load_raw, run_inline


def _restart(raw, out):
    from ancf_petsc.api import solve
    from ancf_petsc.config.parse import parse_config
    spec = parse_config(dict(raw, output={"dir": str(out), "vtk": False}), base_dir=CONFIGS)
    return solve(spec, log=lambda *_: None, restart=str(out))


def test_a_restarted_unstable_run_stays_unstable(tmp_path):
    """The bar pushed at its tip (-400 N, every level an unstable equilibrium) restarted with no
    level to go read 'completed', exit 0, unstable_levels [] (the restarted process's levels
    alone); now 'unstable' naming both levels, and the result lists both."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["loads"][0]["traction_force"] = [-400.0, 0.0, 0.0]
    raw["steps"] = [0.1, 0.2]
    s = run_inline(dict(raw, output={"vtk": False}), tmp_path)
    assert s["status"] == "unstable" and s["unstable_levels"] == [0.1, 0.2], s["message"]
    res = _restart(raw, tmp_path)
    assert res.status == "unstable" and res.exit_code == 4, res.message
    assert res.summary["unstable_levels"] == [0.1, 0.2] and "2 of 2 levels" in res.message
    assert len(res.records) == 2 == len(res.summary["steps"])
    res = _restart(dict(raw, steps=[0.1, 0.2, 0.3]), tmp_path)
    assert res.status == "unstable" and "3 of 3 levels" in res.message, res.message
    assert len(res.records) == 3 == len(res.summary["steps"])


def test_a_restart_that_converges_no_level_keeps_the_last_converged_one(tmp_path):
    """The bar to 0.1, then restarted towards 0.2 with a Newton budget of one iteration: it fails
    at once, and summary.json had no last_converged (the restarted process had converged
    nothing) though level 1 is on disk; now {"step": 1, "load_factor": 0.1}."""
    raw = load_raw("uniaxial_neohookean.yaml")
    run_inline(dict(raw, steps=[0.1], output={"vtk": False}), tmp_path)
    res = _restart(dict(raw, steps=[0.1, 0.2], solver={"max_newton_iterations": 1}), tmp_path)
    assert res.status == "failed" and len(res.summary["steps"]) == 1, res.message
    assert res.summary["last_converged"] == {"step": 1, "load_factor": 0.1}


def test_a_restarted_run_counts_the_newton_budget_of_its_levels_on_disk(tmp_path):
    """solver.max_newton_iterations is the whole run's: the bar given 20 stops at 0.7 after 21
    iterations; solved to 0.5 (16) and restarted to 1.0 with the same budget, it completed (31 in
    all, the budget started again at 0).  Now it stops where the uninterrupted run does."""
    raw = dict(load_raw("uniaxial_neohookean.yaml"), solver={"max_newton_iterations": 20})
    whole = run_inline(dict(raw, output={"vtk": False}), tmp_path / "whole")
    assert whole["status"] == "failed" and whole["steps"][-1]["load_factor"] == 0.6
    run_inline(dict(raw, steps=raw["steps"][:5], output={"vtk": False}), tmp_path / "run")
    res = _restart(raw, tmp_path / "run")
    assert res.status == "failed" and res.summary["reason_code"] == "NEWTON_BUDGET_EXCEEDED", res.message
    assert res.summary["steps"][-1]["load_factor"] == 0.6
    assert "after 21 Newton iterations (solver.max_newton_iterations = 20; 16 of them before --restart)" \
        in res.message, res.message
