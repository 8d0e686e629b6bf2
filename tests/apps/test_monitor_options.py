"""Monitors, viewers and prefixed options with values PETSc refuses: one line naming the option
and its value, exit 2, never blamed on the solver (``-snes_monitor false`` used to be reported
as "-pc_factor_mat_solver_type mumps cannot do cholesky here").  PETSc 3.18 reads a monitor's
value as a viewer: ``false`` stops it with "Unsupported viewer false"."""
from __future__ import annotations

import copy
import os
import subprocess
import sys

import pytest

from helpers import CONFIGS, MPI_ENV, ONE_AND_TWO_RANKS, ROOT
from test_edges import TIMEOUT, UNIAXIAL, assert_one_line, run_cfg, tiny

from ancf_petsc.linalg.option_syntax import AT_FINISH_OPTIONS, VIEWERS, check_value

MONITOR = "a monitor or viewer takes no true/false"


@pytest.mark.parametrize("name,value,words", [
    ("snes_monitor", "false", (MONITOR, "'Unsupported viewer false'", "leave the option out")),
    ("ksp_converged_reason", "0", (MONITOR,)),
    ("sub_ksp_monitor", "true", (MONITOR,)),
    ("ksp_view", "foo", ("unknown viewer 'foo'",)),
    ("sub_ksp_type", "foo", ("unknown ksp type 'foo'",)),        # ksp_ is not stripped off twice
])
def test_refused_values(name, value, words):
    why = check_value(name, value)
    assert why is not None and "\n" not in why, why
    for w in words:
        assert w in why, why


@pytest.mark.parametrize("value", [None, "", "ascii", "draw", "ascii:run.log", ":run.log::append",
                                   "ascii::ascii_info_detail"])
def test_viewer_values_petsc_takes(value):
    assert check_value("snes_monitor", value) is None


def test_monitor_false_in_the_config():
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.config.values import ConfigError
    raw = copy.deepcopy(UNIAXIAL)
    raw["petsc"] = {"snes_monitor": False}
    with pytest.raises(ConfigError) as err:
        parse_config(raw, base_dir=CONFIGS)
    assert str(err.value).startswith(f"petsc.snes_monitor: {MONITOR}: PETSc reads 'false'"), str(err.value)
    raw["petsc"] = {"snes_monitor": True, "ksp_view": "ascii:view.txt"}
    assert parse_config(raw, base_dir=CONFIGS).petsc == {"snes_monitor": "", "ksp_view": "ascii:view.txt"}


#: one process per option: after a failed *ViewFromOptions, PETSc 3.18 skips every later one in
#: the process (PetscObjectViewFromOptions leaves its re-entry flag set on the error path)
VIEWER_DRIVER = """
import sys
import petsc4py
petsc4py.init([sys.argv[0], "-" + sys.argv[1], "false"])
from petsc4py import PETSc


def residual(snes, x, f):
    x.copy(f)
    f.shift(-1.0)


def jacobian(snes, x, J, P):
    for i in range(2):
        P.setValue(i, i, 1.0)
    P.assemble()


try:
    J = PETSc.Mat().createAIJ([2, 2], nnz=1, comm=PETSc.COMM_SELF)
    jacobian(None, None, None, J)                # -mat_view: read at assembly
    x, f = J.createVecs()
    snes = PETSc.SNES().create(comm=PETSc.COMM_SELF)
    snes.setFunction(residual, f)
    snes.setJacobian(jacobian, J, J)
    snes.setFromOptions()
    snes.solve(None, x)
    print("NO ERROR")
except PETSc.Error as exc:
    print("REFUSED" if "Unsupported viewer false" in str(exc) else "OTHER " + str(exc))
"""


@pytest.mark.slow
def test_petsc_reads_each_viewer_option_as_a_viewer(tmp_path):
    """Every option of VIEWERS given 'false' stops a SNES solve with PETSc's 'Unsupported viewer'."""
    driver = tmp_path / "viewer.py"
    driver.write_text(VIEWER_DRIVER)
    for name in (v for v in VIEWERS if v not in AT_FINISH_OPTIONS):     # log_view: test_log_view...
        p = subprocess.run([sys.executable, str(driver), name], capture_output=True, text=True,
                           timeout=TIMEOUT, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
        assert p.stdout.strip().splitlines()[-1:] == ["REFUSED"], (name, p.stdout, p.stderr[-2000:])


@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_monitor_false_on_the_command_line(tmp_path, ranks):
    p = run_cfg(tmp_path, tiny(), ranks, extra=["-snes_monitor", "false"])
    line = assert_one_line(p, 2, f"ancf-solve: PETSc option -snes_monitor false: {MONITOR}")
    assert "cholesky" not in line and "mumps" not in line
    assert not (tmp_path / "out").exists()                       # refused before PETSc starts


@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_options_under_the_config_prefix_are_checked(tmp_path, ranks):
    raw = tiny(solver={"options_prefix": "left_"})
    p = run_cfg(tmp_path, raw, ranks, extra=["-left_snes_max_it", "abc"], out="a")
    line = assert_one_line(p, 2, "ancf-solve: PETSc option -left_snes_max_it abc: expected an integer")
    assert "cholesky" not in line and "mumps" not in line
    p = run_cfg(tmp_path, raw, ranks, extra=["-left_snes_monitor", "false"], out="b")
    assert_one_line(p, 2, f"ancf-solve: PETSc option -left_snes_monitor false: {MONITOR}")


def test_an_option_outside_the_tables_is_not_blamed_on_the_solver(tmp_path):
    """An option ancf-solve does not check (-ksp_monitor_solution) that PETSc refuses while the
    solver is set up: PETSc's reason, and no blame on MUMPS's Cholesky, which works."""
    p = run_cfg(tmp_path, tiny(), 1, extra=["-ksp_monitor_solution", "false"])
    line = assert_one_line(p, 2, "PETSc refused an option while setting up the solver on 1 rank(s): "
                                 "Unsupported viewer false; check the PETSc options given")
    assert "cholesky" not in line
