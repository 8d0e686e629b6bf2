"""``-snes_mf`` (issue: its failure said "drop -pc_type none", an option the user never gave).
With -snes_mf PETSc has no matrix to precondition with and sets -pc_type none itself; with the
default -ksp_type preonly every Newton step is then the residual.  The failure line says so and
names what works: -snes_mf_operator -ksp_type gmres (checked here to reach the default's answer,
on the bar and on the paper's contact model)."""
from __future__ import annotations

import os

import numpy as np
import pytest

from helpers import CONFIGS, ONE_AND_TWO_RANKS, read_summary, solve_cli
from test_edges import assert_one_line, run_cfg, tiny

MF = "-snes_mf leaves no matrix to precondition with, so PETSc sets -pc_type none"


@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_snes_mf_failure_names_snes_mf_and_what_works(tmp_path, ranks):
    p = run_cfg(tmp_path, tiny(), ranks, extra=["-snes_mf"])
    line = assert_one_line(p, 3, "DIVERGED_MAX_IT", MF, "with -ksp_type preonly every Newton step is the "
                           "residual itself", "use -snes_mf_operator -ksp_type gmres")
    assert "drop -pc_type none" not in line


def test_snes_mf_with_a_failing_krylov_solve(tmp_path):
    p = run_cfg(tmp_path, tiny(), 1, extra=["-snes_mf", "-ksp_type", "gmres", "-ksp_max_it", "2"])
    line = assert_one_line(p, 3, "DIVERGED_LINEAR_SOLVE (the linear solver -snes_mf -ksp_type gmres (no "
                           "preconditioner) stopped with DIVERGED_MAX_IT", MF,
                           "use -snes_mf_operator -ksp_type gmres", "or leave out -snes_mf")
    assert "cholesky" not in line


def _tip(out) -> np.ndarray:
    return np.array(read_summary(out)["steps"][-1]["probes"]["tip"]["displacement"])


def test_the_suggested_matrix_free_options_reach_the_default_answer(tmp_path):
    ref = run_cfg(tmp_path, tiny(), 1, out="ref")
    mf = run_cfg(tmp_path, tiny(), 1, extra=["-snes_mf_operator", "-ksp_type", "gmres"], out="mf")
    assert ref.returncode == 0 and mf.returncode == 0, mf.stderr
    a, b = _tip(tmp_path / "ref"), _tip(tmp_path / "mf")
    assert np.abs(a - b).max() <= 1e-7 * np.abs(a).max()


@pytest.mark.slow
def test_snes_mf_operator_on_the_contact_model(tmp_path):
    p = solve_cli(os.path.join(CONFIGS, "achilles_type3_psi45.yaml"),
                  extra=["--quiet", "--output-dir", str(tmp_path / "mf"), "-snes_mf_operator", "-ksp_type",
                         "gmres"], timeout=300)
    assert p.returncode == 0, p.stderr
    assert read_summary(tmp_path / "mf")["status"] == "completed"
