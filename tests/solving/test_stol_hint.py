"""A -snes_stol given above the run's own ends solves on the step length before |F| is small: the
bending column with -snes_stol 1e-3 took 3 497 Newton iterations in 399 sub-steps instead of 36,
each cut-back saying only 'stopped on the step length'.  The cut-back line now names the option."""
from helpers import load_raw, read_summary, solve_cli, write_config


def test_a_given_stol_is_named_where_solves_stop_on_the_step_length(tmp_path):
    raw = load_raw("bending_neohookean.yaml")
    raw["steps"] = [0.25]
    raw["solver"] = {"max_cutbacks": 1}
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    cfg = write_config(raw, tmp_path / "c.yaml")
    p = solve_cli(cfg, extra=["-snes_stol", "1e-3"])
    lines = [s for s in (p.stdout + p.stderr).splitlines() if "stopped on the step length" in s]
    assert lines, p.stdout + p.stderr
    assert "-snes_stol 0.001, given in the run's options" in lines[0], lines[0]
    q = solve_cli(cfg)                       # the run's own stol: no such line
    assert q.returncode == 0 and "-snes_stol" not in q.stdout + q.stderr, q.stdout + q.stderr


def test_a_given_stol_is_named_in_the_failure_it_causes(tmp_path):
    """-snes_stol 1e-2 on the uniaxial bar: the run failed 'with STALLED_ABOVE_TOLERANCE' and no
    word of the option (failure_cause stalled_above_tolerance); only the cut-back lines named it."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.1]
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    cfg = write_config(raw, tmp_path / "c.yaml")
    p = solve_cli(cfg, extra=["-snes_stol", "1e-2", "--quiet"])
    assert p.returncode == 3, p.stdout + p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert "STALLED_ABOVE_TOLERANCE (stopped on the step length" in line, line
    assert "-snes_stol 0.01, given in the run's options" in line, line
    summary = read_summary(tmp_path / "out")
    assert summary["status"] == "failed" and summary["failure_cause"] == "step_tolerance", summary["failure_cause"]
