"""A -snes_type other than Newton or a -snes_linesearch_damping below 1, given in the run's options,
is named as the cause of the failure it brings: on the uniaxial bar ksponly ended 'with
STALLED_ABOVE_TOLERANCE' and no word, damping 0.5 was blamed on 'a nearly singular tangent, as near
a limit or bifurcation point', ngmres on 'the tangent does not predict the residual'."""
import pytest

from helpers import load_raw, read_summary, solve_cli, write_config


@pytest.mark.parametrize("options, named", [
    (["-snes_type", "ksponly"], "-snes_type ksponly, given in the run's options, takes one linear step"),
    (["-snes_type", "ngmres"], "-snes_type ngmres, given in the run's options, is not Newton's method"),
    (["-snes_linesearch_damping", "0.5"], "-snes_linesearch_damping 0.5, given in the run's options"),
    (["-snes_linesearch_damping", "0.5", "-snes_linesearch_type", "bt"], "-snes_linesearch_damping 0.5, given"),
    # |F| never measured after a step: 'Newton stalls at |F| ... more iterations do not help'
    (["-snes_linesearch_norms", "false"], "-snes_linesearch_norms false, given in the run's options, keeps"),
])
def test_a_given_nonlinear_method_is_named_in_the_failure_it_causes(tmp_path, options, named):
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.1]
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=options + ["--quiet"])
    assert p.returncode == 3, p.stdout + p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert named in line and "singular tangent" not in line and "does not predict" not in line, line
    assert "stalls" not in line, line
    assert read_summary(tmp_path / "out")["failure_cause"] == "nonlinear_method"


@pytest.mark.parametrize("option", ["snes_lag_jacobian", "snes_lag_preconditioner"])
def test_a_lagged_tangent_is_named_in_the_failure_it_causes(tmp_path, option):
    """-snes_lag_jacobian -2 on the elastica: 'Newton converges only linearly here ... a nearly
    singular tangent, as near a limit or bifurcation point' at load factor 0.00059 of 0.2."""
    raw = load_raw("elastica_svk.yaml")
    raw["steps"] = [0.2]
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=[f"-{option}", "-2", "--quiet"])
    line = p.stderr.strip().splitlines()[-1]
    assert p.returncode == 3 and f"(-{option} -2, given in the run's options, keeps an old tangent" in line, line
    assert "singular tangent" not in line and read_summary(tmp_path / "out")["failure_cause"] == "nonlinear_method"


def test_a_damping_of_one_and_newtontr_are_not_blamed(tmp_path):
    """Damping 1 is the default's whole step; newtontr has no line search to damp (the option is
    reported unused) and solves the bar."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.1]
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    cfg = write_config(raw, tmp_path / "c.yaml")
    for options in (["-snes_linesearch_damping", "1"], ["-snes_type", "newtontr", "-snes_linesearch_damping", "0.5"]):
        p = solve_cli(cfg, extra=options + ["--quiet"])
        assert p.returncode == 0 and read_summary(tmp_path / "out")["status"] == "completed", p.stderr


def test_an_atol_the_unloaded_state_meets_is_refused(tmp_path):
    """-snes_atol at or above |F| at rest at the first loaded level: the level was accepted at
    rest, without a Newton step (the paper's tendon at 2 elements with -snes_atol 150: 100 N at
    zero displacement, 'completed'); refused before anything is written, exit 2."""
    raw = load_raw("uniaxial_neohookean.yaml")         # 4.5 N at the first level, 0.1
    raw["steps"] = [0.1, 1.0]
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    cfg = write_config(raw, tmp_path / "c.yaml")
    p = solve_cli(cfg, extra=["-snes_atol", "5", "--quiet"])
    lines = [s for s in p.stderr.splitlines() if s.startswith("ancf-solve:")]
    assert p.returncode == 2 and len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    assert lines[0].startswith("ancf-solve: PETSc option -snes_atol 5: at or above the loads of the first "
                               "level (load factor 0.1, 4.5 N)"), lines[0]
    assert not (tmp_path / "out" / "summary.json").exists() and not (tmp_path / "out" / "results.h5").exists()
    p = solve_cli(cfg, extra=["-snes_atol", "1", "--quiet"])        # loose, but below the loads
    assert p.returncode == 0 and read_summary(tmp_path / "out")["steps"][0]["iterations"] > 0, p.stderr


def test_a_restart_goes_on_from_its_loaded_state_whatever_the_atol(tmp_path):
    """The atol check is of the rest state at the first level: a restart after converged levels
    goes on from a loaded state, and was refused all the same (b2ec0c8)."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.update(steps=[0.1, 0.2, 10.0], solver={"max_cutbacks": 0}, output={"dir": str(tmp_path / "out"), "vtk": False})
    cfg = write_config(raw, tmp_path / "c.yaml")
    assert solve_cli(cfg, extra=["-snes_max_it", "4", "--quiet"]).returncode == 3
    p = solve_cli(cfg, extra=["--restart", str(tmp_path / "out"), "-snes_atol", "5", "--quiet"])
    assert p.returncode == 0 and read_summary(tmp_path / "out")["status"] == "completed", p.stderr
