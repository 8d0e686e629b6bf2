"""PETSc options of the process, not of a solve, under the config's ``petsc:``.  PETSc reads
``-help``, ``-info``, ``-options_file`` ... only while it starts, before the config is read: they
did nothing and were reported as "never used: misspelt"; now they are a config error that says to
give them on the command line.  ``log_view`` is read when PETSc finishes: the config's value is
applied (the log printed at the end, as for ``-log_view`` on the command line)."""
from __future__ import annotations

import copy
import os
import subprocess
import sys

import pytest

from helpers import CONFIGS, MPI_ENV, ONE_AND_TWO_RANKS, ROOT
from test_edges import TIMEOUT, UNIAXIAL, assert_one_line, run_cfg, solver_lines, tiny

from ancf_petsc.config.parse import parse_config
from ancf_petsc.config.values import ConfigError
from ancf_petsc.linalg.option_syntax import START_UP_OPTIONS


@pytest.mark.parametrize("name,value,words", [
    ("help", None, "petsc.help: PETSc reads -help only while it starts, before the config is read; "
                   "give it on the command line (ancf-solve CONFIG.yaml -help)"),
    ("info", True, "petsc.info: PETSc reads -info only while it starts"),
    ("options_file", "my.opts", "(ancf-solve CONFIG.yaml -options_file my.opts)"),
])
def test_start_up_options_in_the_config_are_refused(name, value, words):
    raw = copy.deepcopy(UNIAXIAL)
    raw["petsc"] = {name: value}
    with pytest.raises(ConfigError) as err:
        parse_config(raw, base_dir=CONFIGS)
    assert words in str(err.value) and "\n" not in str(err.value), str(err.value)


def test_petsc_reads_start_up_options_only_while_it_starts():
    """Given after PetscInitialize (as the config's options are), PETSc never reads them; -help
    only makes each solver list its own options: PETSc's help for every program is not printed."""
    script = ("import petsc4py; petsc4py.init([]); from petsc4py import PETSc\n"
              "from ancf_petsc.linalg.diagnostics import options_used\n"
              f"names = {list(START_UP_OPTIONS)!r}\n"
              "for n in names: PETSc.Options().setValue(n, '')\n"
              "s = PETSc.SNES().create(); s.setFromOptions(); s.destroy()\n"
              "print('USED', [n for n, u in zip(names, options_used(names)) if u])\n")
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=TIMEOUT,
                       env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert "USED ['help']" in p.stdout, (p.stdout[-2000:], p.stderr[-2000:])
    assert "Nonlinear solver (SNES) options" in p.stdout and "Options for all PETSc programs" not in p.stdout


@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_help_in_the_config_on_the_command_line(tmp_path, ranks):
    p = run_cfg(tmp_path, tiny(petsc={"help": None}), ranks)
    assert_one_line(p, 2, "ancf-solve: config error: petsc.help: PETSc reads -help only while it "
                          "starts", "ancf-solve CONFIG.yaml -help")
    assert "Nonlinear solver (SNES) options" not in p.stdout


@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_log_view_in_the_config_is_applied(tmp_path, ranks):
    log = tmp_path / "log.txt"
    p = run_cfg(tmp_path, tiny(petsc={"log_view": f":{log}"}), ranks)
    assert p.returncode == 0 and not solver_lines(p.stderr), p.stderr      # no "never used"
    text = log.read_text()
    assert "PETSc Performance Summary" in text and "ANCF load stepping" in text
    assert f"with {ranks} processor" in text
    # to standard output, once under mpirun
    p = run_cfg(tmp_path, tiny(petsc={"log_view": None}), ranks, out="o2")
    assert p.returncode == 0 and not solver_lines(p.stderr), p.stderr
    assert p.stdout.count("PETSc Performance Summary") == 1, p.stdout[-3000:]
    # the command line's wins
    other = tmp_path / "cl.txt"
    p = run_cfg(tmp_path, tiny(petsc={"log_view": f":{tmp_path / 'cfg.txt'}"}), ranks, out="o3",
                extra=["-log_view", f":{other}"])
    assert p.returncode == 0 and other.exists() and not (tmp_path / "cfg.txt").exists(), p.stderr


def test_log_view_false_is_refused():
    raw = copy.deepcopy(UNIAXIAL)
    raw["petsc"] = {"log_view": False}
    with pytest.raises(ConfigError) as err:
        parse_config(raw, base_dir=CONFIGS)
    assert str(err.value).startswith("petsc.log_view: a monitor or viewer takes no true/false"), str(err.value)
