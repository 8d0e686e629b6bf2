"""SLURM scripts that survive sbatch and a move (issue 25): sbatch runs a copy of the script from
its spool directory, so nothing may be derived from "$0"; a sweep prepared on one machine runs on
another (every path in sweep.slurm, runs.txt and the runs' configs is relative to the sweep
directory); a partition with a blank is refused."""
from __future__ import annotations

import json
import os
import shutil
import subprocess

import pytest
import yaml

from helpers import CONFIGS, MPI_ENV, ROOT

from test_sweep import run_main, write_sweep

ONE_MODEL = os.path.join(ROOT, "scripts", "slurm_one_model.sh")


def _spool_copy(script: str, tmp_path) -> str:
    """The script as sbatch runs it: a copy named slurm_script in a spool directory."""
    spool = tmp_path / "spool" / "job42"
    spool.mkdir(parents=True)
    shutil.copy(script, spool / "slurm_script")
    return str(spool / "slurm_script")


def test_one_model_script_finds_the_venv_from_the_submit_directory(tmp_path):
    script = _spool_copy(ONE_MODEL, tmp_path)
    env = dict(os.environ, ANCF_LAUNCH="echo", OUT=str(tmp_path / "out"), SLURM_SUBMIT_DIR=ROOT)
    env.pop("ANCF_VENV", None)
    p = subprocess.run(["bash", script, "c.yaml"], env=env, capture_output=True, text=True, timeout=30)
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith(os.path.join(ROOT, ".venv", "bin", "ancf-solve") + " c.yaml"), p.stdout
    for where in ({"SLURM_SUBMIT_DIR": str(tmp_path)}, {"ANCF_VENV": str(tmp_path / "nowhere")}):
        env2 = dict(env, **where)
        p = subprocess.run(["bash", script, "c.yaml"], env=env2, capture_output=True, text=True,
                           timeout=30)
        assert p.returncode == 2 and p.stdout == "", (p.stdout, p.stderr)
        assert p.stderr.startswith("slurm_one_model.sh: no ancf-solve in ") and "ANCF_VENV" in p.stderr
    assert subprocess.run(["bash", "-n", ONE_MODEL]).returncode == 0


def _achilles_base(directory) -> str:
    """The Achilles config with its sections file beside it (data/), given relatively."""
    (directory / "data").mkdir(parents=True)
    shutil.copy(os.path.join(CONFIGS, "data", "achilles_type3_sections.yaml"), directory / "data")
    shutil.copy(os.path.join(CONFIGS, "achilles_type3_psi45.yaml"), directory / "base.yaml")
    return str(directory / "base.yaml")


def test_a_sweep_prepared_here_runs_after_a_move(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    _achilles_base(a)
    (a / "sweep.yaml").write_text(yaml.safe_dump({
        "base": "base.yaml", "name": "moved", "parameters": {"geometry.twist_deg": [0, 45]},
        "output": "out"}))
    rc, out, err = run_main([str(a / "sweep.yaml"), "--slurm"])
    assert rc == 0, out + err
    assert f"cd {a / 'out'} && sbatch sweep.slurm" in out
    script = (a / "out" / "sweep.slurm").read_text()
    code = [ln for ln in script.splitlines() if not ln.startswith("# ")]
    # the environment running ancf-sweep is machine-specific (here outside the sweep's tree:
    # absolute, ANCF_VENV overrides it); nothing else names a directory
    assert not [ln for ln in code if str(tmp_path) in ln or (ROOT in ln and "ANCF_VENV" not in ln)], code
    assert "#SBATCH --output=tasks/%a/slurm-%A_%a.out" in script
    assert (a / "out" / "runs.txt").read_text().split() == ["run_0000__twist_deg=0", "run_0001__twist_deg=45"]
    cfg = yaml.safe_load((a / "out" / "run_0001__twist_deg=45" / "config.yaml").read_text())
    assert {bm["section"]["file"] for bm in cfg["beams"]} == {"../../data/achilles_type3_sections.yaml"}
    assert subprocess.run(["bash", "-n", str(a / "out" / "sweep.slurm")]).returncode == 0

    os.rename(a, b)                                   # another machine, another directory
    from ancf_petsc.config.parse import load_config
    spec = load_config(str(b / "out" / "run_0001__twist_deg=45" / "config.yaml"))
    assert spec.beams[0].section.file == str(b / "data" / "achilles_type3_sections.yaml")

    # outside the sweep directory, with the script copied to a spool directory: one line, exit 2
    copy = _spool_copy(str(b / "out" / "sweep.slurm"), tmp_path)
    env = dict(os.environ, **MPI_ENV, SLURM_ARRAY_TASK_ID="0", SLURM_SUBMIT_DIR=str(tmp_path))
    p = subprocess.run(["bash", copy], env=env, capture_output=True, text=True, timeout=30)
    assert p.returncode == 2 and "submit from the sweep directory" in p.stderr, p.stderr


def test_a_moved_uniaxial_sweep_runs_as_an_array_task(tmp_path):
    if shutil.which("srun"):
        pytest.skip("on a SLURM host, do not launch srun here")
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    path = write_sweep(str(a), {"name": "u", "parameters": {"output.vtk": [False]}, "output": "out"})
    with open(path) as fh:                            # the base beside the sweep, relatively
        body = yaml.safe_load(fh)
    shutil.copy(os.path.join(CONFIGS, "uniaxial_neohookean.yaml"), a / "base.yaml")
    body["base"] = "base.yaml"
    (a / "sweep.yaml").write_text(yaml.safe_dump(body))
    rc, out, _ = run_main([str(a / "sweep.yaml"), "--slurm"])
    assert rc == 0, out
    os.rename(a, b)
    copy = _spool_copy(str(b / "out" / "sweep.slurm"), tmp_path)
    env = dict(os.environ, **MPI_ENV, SLURM_ARRAY_TASK_ID="0", SLURM_ARRAY_JOB_ID="9",
               SLURM_SUBMIT_DIR=str(b / "out"))
    env.pop("ANCF_VENV", None)
    p = subprocess.run(["bash", copy], env=env, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stdout + p.stderr
    with open(b / "out" / "run_0000" / "run.json") as fh:
        assert json.load(fh)["status"] == "completed"


@pytest.mark.parametrize("option,value", [("--partition", "a b"), ("--account", "x;rm"),
                                          ("--partition", "")])
def test_partition_and_account_are_names(tmp_path, option, value):
    path = write_sweep(str(tmp_path), {"parameters": {"output.vtk": [False]}, "output": "p"})
    rc, _, err = run_main([path, "--slurm", option, value])
    assert rc == 2 and err.startswith(f"ancf-sweep: {path}: {option}: ") and "got " in err, err
    assert not (tmp_path / "p" / "sweep.slurm").exists()


def test_a_moved_sweep_keeps_its_completed_runs(tmp_path):
    """Moved, then --slurm again (a new --time): every completed run lost its summary.json and
    run.json (their config.yaml named the old output.dir) and a resubmission redid them all."""
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    shutil.copy(os.path.join(CONFIGS, "uniaxial_neohookean.yaml"), a / "base.yaml")
    (a / "sweep.yaml").write_text(yaml.safe_dump({
        "base": "base.yaml", "name": "m", "parameters": {"output.vtk": [False]}, "output": "out"}))
    assert run_main([str(a / "sweep.yaml")])[0] == 0
    os.rename(a, b)
    rc, out, _ = run_main([str(b / "sweep.yaml"), "--slurm", "--time", "00:10:00"])
    assert rc == 0, out
    run_dir = b / "out" / "run_0000"
    assert (run_dir / "summary.json").exists() and (run_dir / "run.json").exists()
    assert yaml.safe_load((run_dir / "config.yaml").read_text())["output"]["dir"] == str(run_dir)
    rc, out, _ = run_main([str(b / "sweep.yaml"), "--dry-run"])
    assert "0 to run, 1 already done" in out, out
    rc, out, _ = run_main([str(b / "sweep.yaml"), "--collect"])
    assert rc == 0 and "1 runs: 1 completed" in out, out


def test_the_commands_to_paste_are_quoted(tmp_path):
    """A sweep directory with a blank: 'submit: cd /x/my sweeps/out && sbatch ...' failed as
    pasted (cd: too many arguments); the script's own comment was quoted."""
    d = tmp_path / "my sweeps"
    d.mkdir()
    path = write_sweep(str(d), {"parameters": {"output.vtk": [False]}, "output": "out"})
    rc, out, _ = run_main([path, "--slurm"])
    assert rc == 0, out
    cd = f"cd '{d / 'out'}' && sbatch sweep.slurm"
    assert cd in out and f"afterwards: ancf-sweep '{path}' --collect" in out, out
    assert f"# Submit:   {cd}" in (d / "out" / "sweep.slurm").read_text()
