"""scripts/slurm_one_model.sh: one model across the ranks of one allocation (issue 16), tried with
mpirun standing in for srun (ANCF_LAUNCH)."""
import os
import subprocess

import pytest

from helpers import MPI_ENV, ROOT, load_raw, read_summary, write_config


@pytest.mark.mpi
def test_the_one_model_recipe_runs_a_bundle_on_two_ranks_with_the_fascicle_solver(tmp_path):
    raw = load_raw("bundle_hex7.yaml")
    raw["solver"] = {"linear": "fieldsplit"}
    cfg = write_config(raw, tmp_path / "hex7.yaml")
    out = tmp_path / "out"
    env = dict(os.environ, **MPI_ENV, OUT=str(out), ANCF_LAUNCH="mpirun --oversubscribe -n 2")
    p = subprocess.run(["bash", os.path.join(ROOT, "scripts", "slurm_one_model.sh"), cfg, "-snes_monitor_short"],
                       capture_output=True, text=True, env=env, cwd=ROOT, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    s = read_summary(out)
    assert s["status"] == "completed" and s["ranks"] == 2
    assert s["linear_solver"]["choice"] == "fieldsplit" and s["partition"]["method"] == "beams"
    assert (out / "log_view.txt").stat().st_size > 0          # PETSc's performance summary
    assert "SNES Function norm" in p.stdout                  # PETSc options pass through
