"""PETSc reads option names without regard to case or leading dashes: the config's ``petsc:``
keys and the command line's names are checked and used as PETSc reads them."""
import numpy as np
import pytest

from ancf_petsc.config.solving import parse_petsc
from ancf_petsc.config.values import ConfigError
from ancf_petsc.linalg.option_syntax import check_command_line
from helpers import cantilever, probe, run_inline, solve_cli, write_config


@pytest.mark.parametrize("block, key, first", [
    ({"snes_rtol": "1e-8", "SNES_RTOL": 0.5}, "SNES_RTOL", "snes_rtol"),
    ({"-snes_rtol": "1e-3", "snes_rtol": "1e-5"}, "snes_rtol", "-snes_rtol"),
])
def test_one_option_given_twice_in_the_config_is_refused(block, key, first):
    """{snes_rtol: 1e-8, SNES_RTOL: 0.5} ran at 1e-8 and {-snes_rtol: 1e-3, snes_rtol: 1e-5} at
    1e-5, the other value dropped without a word."""
    with pytest.raises(ConfigError) as err:
        parse_petsc(block)
    assert str(err.value).startswith(f"petsc.{key}: the same PETSc option as petsc.{first}"), str(err.value)


@pytest.mark.parametrize("block, why", [
    ({"SNES_RTOL": "abc"}, "expected a number"),
    ({"PC_TYPE": "chol"}, "unknown pc type 'chol'"),
    ({"SNES_MONITOR": False}, "a monitor or viewer takes no true/false"),
    ({"HELP": True}, "PETSc reads -help only while it starts"),
])
def test_a_name_in_capitals_is_checked_as_petsc_reads_it(block, why):
    """Names in capitals passed the checks: PETSc's own error came at the solver's set-up
    ('Input string abc has no numeric value', 'Unsupported viewer 0'), and HELP: true printed
    PETSc's help in the middle of a run that then completed."""
    with pytest.raises(ConfigError) as err:
        parse_petsc(block)
    assert why in str(err.value) and str(err.value).startswith(f"petsc.{next(iter(block))}:")
    assert "expected a number" in check_command_line(["-SNES_RTOL", "abc"])


def test_a_solver_named_in_capitals_is_the_solver_used(tmp_path):
    """petsc: {PC_TYPE: lu} was not seen when the Jacobian's storage was chosen (SBAIJ, for the
    default LDLᵀ), and PETSc refused MUMPS LU on it; it is LU on AIJ, with the default's answer."""
    raw = cantilever([0.5], elements=2)
    ref = run_inline(raw, tmp_path / "default")
    s = run_inline(raw, tmp_path / "lu", petsc={"PC_TYPE": "lu"})
    assert "PC lu (mumps) on AIJ" in s["solver"] and s["status"] == "completed"
    tip, tip_ref = np.array(probe(s, "tip")), np.array(probe(ref, "tip"))
    assert np.abs(tip - tip_ref).max() <= 1e-8 * np.abs(tip_ref).max()


@pytest.mark.parametrize("value, petsc_reports", [(0, False), (True, True)])
def test_options_left_in_the_config_works_as_on_the_command_line(tmp_path, value, petsc_reports):
    """petsc: {options_left: 0} did not turn the report of unused options off: it was itself
    reported ('PETSc option -options_left (config) was never used: misspelt ...').  0 now turns the
    report off and true hands it to PETSc, as -options_left on the command line."""
    raw = cantilever([0.5], elements=2)
    raw["output"]["dir"] = str(tmp_path / "out")
    raw["petsc"] = {"options_left": value}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-snes_montor", "--quiet"])
    assert p.returncode == 0, p.stderr
    assert "was never used" not in p.stderr, p.stderr
    assert ("Option left: name:-snes_montor" in p.stdout + p.stderr) == petsc_reports


def test_an_option_under_the_prefix_in_capitals_is_checked(tmp_path):
    """With solver.options_prefix left_, -LEFT_SNES_MAX_IT abc passed the prefix's checks and PETSc
    stopped at set-up with 'Input string abc has no integer value'."""
    raw = cantilever([0.5], elements=2)
    raw["output"]["dir"] = str(tmp_path / "out")
    raw["solver"] = {"options_prefix": "left_"}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-LEFT_SNES_MAX_IT", "abc", "--quiet"])
    assert p.returncode == 2 and "PETSc option -LEFT_SNES_MAX_IT abc: expected an integer" in p.stderr, p.stderr
