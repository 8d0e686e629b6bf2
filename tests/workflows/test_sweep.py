"""ancf-sweep end to end: grid expansion, concurrent local runs, resume, failures, SLURM script,
bad sweep files, and one run under mpirun (uniaxial config, about 1 s per run)."""
from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import shutil
import subprocess

import pytest
import yaml

from helpers import CONFIGS, MPI_ENV, ROOT, VENV_BIN

from apps.ancf_sweep import main
from ancf_petsc.io.groups import truncate_levels
from ancf_petsc.workflows.sweep import (SweepError, expand, format_value, load_sweep, parse_key_path,
    run_config)

UNIAXIAL = os.path.join(CONFIGS, "uniaxial_neohookean.yaml")


def write_sweep(directory, body: dict, name: str = "sweep.yaml") -> str:
    """Write a sweep file whose base is the uniaxial config, given relative to the sweep file."""
    body = {"base": os.path.relpath(UNIAXIAL, directory), **body}
    path = os.path.join(directory, name)
    with open(path, "w") as fh:
        yaml.safe_dump(body, fh, sort_keys=False)
    return path


def run_main(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(argv)
    return rc, out.getvalue(), err.getvalue()


def read_csv(path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


GRID = {"name": "grid", "mode": "grid",
        "parameters": {"beams[0].material.mu": [1.0e6, 2.0e6], "geometry.length": [0.1, 0.2],
                       "output.vtk": [False]},
        "run": {"jobs": 2, "petsc": ["-snes_rtol", "1e-9"], "timeout": 120},
        "output": "out/grid"}


@pytest.fixture(scope="module")
def grid(tmp_path_factory):
    """The 2 x 2 grid, run once for the module: (sweep file, output dir, exit code, stdout)."""
    d = tmp_path_factory.mktemp("sweep")
    path = write_sweep(str(d), GRID)
    rc, out, err = run_main([path])
    return path, str(d / "out" / "grid"), rc, out + err


def test_grid_runs_and_collects(grid):
    path, out_dir, rc, out = grid
    assert rc == 0, out
    assert out.count(" completed in ") == 4 and out.count(" started") == 4
    assert "4 runs: 4 completed" in out
    rows = read_csv(os.path.join(out_dir, "results.csv"))
    assert len(rows) == 4
    assert [(float(r["beams[0].material.mu"]), float(r["geometry.length"])) for r in rows] == \
        [(1e6, 0.1), (1e6, 0.2), (2e6, 0.1), (2e6, 0.2)]
    assert all(r["status"] == "completed" and float(r["load_factor"]) == 1.0 for r in rows)
    assert all(int(r["newton_iterations"]) > 0 and float(r["wall_time"]) > 0 for r in rows)
    dx = {(float(r["beams[0].material.mu"]), float(r["geometry.length"])): float(r["tip_dx"])
          for r in rows}
    for length in (0.1, 0.2):
        assert 0 < dx[(2e6, length)] < dx[(1e6, length)]          # stiffer -> shorter elongation
    for mu in (1e6, 2e6):                                          # same strain, twice the length
        assert dx[(mu, 0.2)] == pytest.approx(2 * dx[(mu, 0.1)], rel=1e-6)
    assert abs(float(rows[0]["tip_dy"])) < 1e-12 and "tip_dz" in rows[0]
    with open(os.path.join(out_dir, "failed.txt")) as fh:
        assert fh.read() == ""

    runs = expand(load_sweep(path))
    assert [r.run_id for r in runs] == [r["run_id"] for r in rows]
    assert [r.run_id for r in expand(load_sweep(path))] == [r.run_id for r in runs]   # stable
    assert runs[3].run_id == "run_0003__mu=2e+06__length=0.2"
    for r in runs:
        files = set(os.listdir(r.dir))
        assert {"config.yaml", "params.json", "log.txt", "results.h5", "summary.json",
                "run.json"} <= files
        assert not any(f.endswith(".vtu") for f in files)               # output.vtk: [false]
        with open(os.path.join(r.dir, "config.yaml")) as fh:
            cfg = yaml.safe_load(fh)
        assert cfg["output"] == {"dir": r.dir, "vtk": False}
        assert cfg["beams"][0]["material"]["mu"] == r.params["beams[0].material.mu"]
        with open(os.path.join(r.dir, "params.json")) as fh:
            assert json.load(fh)["parameters"] == r.params
    with open(os.path.join(runs[0].dir, "log.txt")) as fh:
        log = fh.read()
    assert "-snes_rtol 1e-09" in log.splitlines()[0] and "[ancf] completed" in log
    with open(os.path.join(runs[0].dir, "summary.json")) as fh:
        s = json.load(fh)
        assert "rtol 1.0e-09" in s["solver"] and s["tolerances"]["rtol"] == 1e-9


def test_rerun_skips_done_and_redoes_missing(grid):
    path, out_dir, _, _ = grid
    rc, out, _ = run_main([path])
    assert rc == 0
    assert out.count("skipped (already done)") == 5      # 4 progress lines + the summary
    assert "4 runs: 0 completed, 4 skipped (already done)" in out and " started" not in out
    runs = expand(load_sweep(path))
    os.remove(os.path.join(runs[2].dir, "summary.json"))
    rc, out, _ = run_main([path])
    assert rc == 0
    assert out.count(" started") == 1 and f"3/4 {runs[2].run_id} completed in" in out
    assert "4 runs: 1 completed, 3 skipped (already done)" in out
    assert [r["status"] for r in read_csv(os.path.join(out_dir, "results.csv"))] == ["completed"] * 4


def test_dry_run_lists_and_writes_nothing(tmp_path):
    path = write_sweep(str(tmp_path), {**GRID, "output": "dry"})
    rc, out, _ = run_main([path, "--dry-run"])
    assert rc == 0 and out.count(" todo ") == 4 and "4 to run, 0 already done" in out
    assert not (tmp_path / "dry").exists()


def test_failures_are_classified_and_listed(tmp_path):
    """list mode: a good run, a config error the model's build finds (a load on a held component:
    a swept value the config refuses is refused with the sweep, below), a run whose first load
    level diverges, a timeout."""
    body = {"mode": "list",
            "parameters": {"boundary_conditions[0].node": ["first", "last", "first"],
                           "loads[0].traction_force[0]": [45.0, 45.0, 4.5e6],
                           "solver.max_cutbacks": [2, 2, 2],        # not in the base: created
                           "output.vtk": [False, False, False]},
            "run": {"jobs": 2}}
    path = write_sweep(str(tmp_path), body)
    rc, out, _ = run_main([path])
    assert rc == 1
    assert "3 runs: 1 completed, 1 failed, 1 config_error" in out
    held = "config error: loads[0].traction_force: bar node last: r.x is held by boundary_conditions[0]"
    assert f"config_error: {held}" in out
    rows = read_csv(tmp_path / "sweeps" / "sweep" / "results.csv")
    assert [r["status"] for r in rows] == ["completed", "config_error", "failed"]
    assert "DIVERGED" in rows[2]["reason"] and "could not reach load factor 0.1" in rows[2]["reason"]
    # the machine-readable reasons: read these, not the text
    assert [r["reason_code"] for r in rows[:2]] == ["COMPLETED", "CONFIG_ERROR"]
    assert rows[2]["reason_code"].startswith("DIVERGED_"), rows[2]
    assert rows[2]["load_factor"] == "" and rows[0]["tip_dx"] != ""
    with open(tmp_path / "sweeps" / "sweep" / "failed.txt") as fh:
        failed = fh.read().splitlines()
    assert len(failed) == 2
    assert failed[0].split("\t")[:2] == [rows[1]["run_id"], "config_error"]
    assert failed[0].split("\t")[2].startswith(held)
    assert failed[1].startswith(rows[2]["run_id"] + "\tfailed\tcould not reach load factor")

    # a timeout kills the run (ancf-solve needs ~0.5 s just to import)
    path = write_sweep(str(tmp_path), {"parameters": {"output.vtk": [False]}, "run": {"timeout": 0.2}},
                       "slow.yaml")
    rc, out, _ = run_main([path])
    assert rc == 1 and "1/1 run_0000 timeout: timed out after 0.2 s" in out
    assert read_csv(tmp_path / "sweeps" / "slow" / "results.csv")[0]["status"] == "timeout"


def test_slurm_script(tmp_path):
    body = {**GRID, "output": "slurm", "slurm": {"throttle": 3, "mem": "2G", "cpus_per_task": 2}}
    path = write_sweep(str(tmp_path), body)
    rc, out, _ = run_main([path, "--slurm", "--partition", "short"])
    assert rc == 0 and "sbatch" in out and "--collect" in out
    out_dir = tmp_path / "slurm"
    script = (out_dir / "sweep.slurm").read_text()
    runs = expand(load_sweep(path))
    # the array throttle is its own setting (run.jobs = 2 is the local concurrency)
    assert "#SBATCH --array=0-3%3" in script and "SLURM_ARRAY_TASK_ID" in script
    assert "#SBATCH --ntasks=1" in script and "#SBATCH --job-name=grid" in script
    assert "#SBATCH --mem=2G" in script and "#SBATCH --cpus-per-task=2" in script
    assert "#SBATCH --partition=short" in script
    assert "#SBATCH --time=00:04:00" in script               # run.timeout 120 s + 2 min
    assert "#SBATCH --output=" in script and "ancf-sweep" in script and "--collect" in script
    assert 'VENV="${ANCF_VENV:-' in script                   # the environment is configurable
    assert (out_dir / "runs.txt").read_text().splitlines() == [r.run_id for r in runs]
    assert all(os.path.isfile(os.path.join(r.dir, "config.yaml")) for r in runs)
    assert os.path.realpath(out_dir / "tasks" / "2") == os.path.realpath(runs[2].dir)
    assert subprocess.run(["bash", "-n", str(out_dir / "sweep.slurm")]).returncode == 0
    if shutil.which("srun"):
        return                                    # on a SLURM host, do not launch srun here

    # run array task 1 as SLURM would (no srun here, so the script falls back to mpirun -n 1)
    env = dict(os.environ, **MPI_ENV, SLURM_ARRAY_TASK_ID="1", SLURM_ARRAY_JOB_ID="7")
    p = subprocess.run(["bash", str(out_dir / "sweep.slurm")], env=env, capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 0, p.stdout + p.stderr
    with open(os.path.join(runs[1].dir, "run.json")) as fh:
        assert json.load(fh)["status"] == "completed"
    p = subprocess.run(["bash", str(out_dir / "sweep.slurm")], env=env, capture_output=True,
                       text=True, timeout=60)
    assert p.returncode == 0 and "already done; skipping" in p.stdout
    # a resubmitted task (its run lost) appends to log.txt instead of overwriting it
    os.remove(os.path.join(runs[1].dir, "summary.json"))
    p = subprocess.run(["bash", str(out_dir / "sweep.slurm")], env=dict(env, SLURM_ARRAY_JOB_ID="8"),
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stdout + p.stderr
    log = open(os.path.join(runs[1].dir, "log.txt")).read()
    assert log.count("=== ancf-sweep attempt") == 2 and "job 7_1" in log and "job 8_1" in log
    rc, out, _ = run_main([path, "--collect"])
    assert rc == 1 and "4 runs: 1 completed, 3 missing" in out
    assert [r["status"] for r in read_csv(out_dir / "results.csv")] == \
        ["missing", "completed", "missing", "missing"]


def test_slurm_numbered_logs_and_environment(tmp_path):
    body = {"parameters": {"output.vtk": [False]}, "output": "num",
            "slurm": {"logs": "numbered", "venv": os.path.relpath(os.path.join(ROOT, ".venv"), tmp_path)}}
    path = write_sweep(str(tmp_path), body)
    rc, out, _ = run_main([path, "--slurm", "--throttle", "5", "--time", "1-00:00:00"])
    assert rc == 0, out
    script = (tmp_path / "num" / "sweep.slurm").read_text()
    assert "#SBATCH --array=0-0\n" in script                # a throttle above the task count is dropped
    assert "#SBATCH --time=1-00:00:00" in script and "--mem" not in script
    venv, out = os.path.join(ROOT, ".venv"), str(tmp_path / "num")
    if os.path.commonpath([venv, out]) != os.sep:       # the checkout and the sweep share a tree
        venv = "$SWEEP_OUTPUT/" + os.path.relpath(venv, out)
    assert f'VENV="${{ANCF_VENV:-{venv}}}"' in script
    rc, _, err = run_main([path, "--slurm", "--time", "two hours"])
    assert rc == 2 and err.startswith("ancf-sweep: ") and "--time: expected SLURM's time syntax" in err
    if shutil.which("srun"):
        return
    run = expand(load_sweep(path))[0]
    env = dict(os.environ, **MPI_ENV, SLURM_ARRAY_TASK_ID="0", SLURM_ARRAY_JOB_ID="3")
    for attempt in (1, 2):
        p = subprocess.run(["bash", str(tmp_path / "num" / "sweep.slurm")], env=env,
                           capture_output=True, text=True, timeout=120)
        assert p.returncode == 0, p.stdout + p.stderr
        os.remove(os.path.join(run.dir, "summary.json"))     # as if the task had been killed
    assert os.path.isfile(os.path.join(run.dir, "log.1.txt")) and os.path.isfile(os.path.join(run.dir, "log.2.txt"))
    assert os.readlink(os.path.join(run.dir, "log.txt")) == "log.2.txt"
    # ANCF_VENV at submission time wins over the script's default
    p = subprocess.run(["bash", str(tmp_path / "num" / "sweep.slurm")],
                       env=dict(env, ANCF_VENV=str(tmp_path / "nowhere")), capture_output=True,
                       text=True, timeout=60)
    assert p.returncode == 1 and "no ancf-solve at " + str(tmp_path / "nowhere") in p.stderr


@pytest.mark.mpi
def test_single_run_on_two_ranks(tmp_path, monkeypatch):
    for k, v in MPI_ENV.items():
        monkeypatch.setenv(k, v)
    path = write_sweep(str(tmp_path), {"parameters": {"beams[0].elements": [2],
                                                      "output.vtk": [False]},
                                       "run": {"ranks": 2}})
    rc, out, _ = run_main([path])
    assert rc == 0, out
    assert "started on 2 ranks" in out and "1 runs: 1 completed" in out
    run = expand(load_sweep(path))[0]
    with open(os.path.join(run.dir, "summary.json")) as fh:
        summary = json.load(fh)
    assert summary["status"] == "completed" and summary["ranks"] == 2


BAD = {
    "unknown key path": ({"parameters": {"geometry.twist_degree": [1, 2]}},
                         "parameters.geometry.twist_degree: not in the base config"),
    "index out of range": ({"parameters": {"beams[1].material.mu": [1e6]}},
                           "parameters.beams[1].material.mu: index [1] out of range"),
    "list lengths": ({"mode": "list", "parameters": {"geometry.length": [0.1, 0.2],
                                                     "beams[0].material.mu": [1e6, 2e6, 3e6]}},
                     "parameters.beams[0].material.mu: has 3 values but geometry.length has 2"),
    "empty list": ({"parameters": {"geometry.length": []}}, "parameters.geometry.length: empty"),
    "unknown sweep key": ({"parameters": {"geometry.length": [1]}, "runs": {}}, "runs: unknown key"),
    "bad run value": ({"parameters": {"geometry.length": [1]}, "run": {"jobs": 0}}, "run.jobs:"),
    "a grid value twice": ({"parameters": {"geometry.length": [0.1, 0.2, 0.1e0]}},
                           "parameters.geometry.length: values 1 and 3 are equal (0.1, 0.1)"),
    # each run skipped the word (max_it stayed 15) or stopped on the value: refused before any run
    "a PETSc option without its dash": ({"parameters": {"geometry.length": [1]},
                                         "run": {"petsc": ["snes_max_it", "3"]}},
                                        "run.petsc: 'snes_max_it' is neither an option nor an option's value"),
    "a PETSc value refused": ({"parameters": {"geometry.length": [1]}, "run": {"petsc": {"snes_max_it": 2.5}}},
                              "run.petsc: PETSc option -snes_max_it 2.5: expected an integer"),
    # ancf-solve took the last --output-dir: every run wrote into /tmp/elsewhere, over the one
    # before, and each was recorded 'crashed: exit code 0 but summary.json says status None'
    "ancf-solve's own option": ({"parameters": {"geometry.length": [0.1, 0.2]},
                                 "run": {"petsc": ["--output-dir", "/tmp/elsewhere"]}},
                                "run.petsc: '--output-dir' is ancf-solve's own option, not PETSc's"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_sweep_file(tmp_path, case):
    body, message = BAD[case]
    path = write_sweep(str(tmp_path), body)
    rc, out, err = run_main([path])
    assert rc == 2
    assert len(err.splitlines()) == 1 and message in err, err
    assert not (tmp_path / "sweeps").exists()


def test_petsc_options_on_the_sweeps_command_line_are_pointed_to_run_petsc(tmp_path, capsys):
    path = write_sweep(str(tmp_path), {"parameters": {"geometry.length": [1]}})
    with pytest.raises(SystemExit) as exc:
        main([path, "--dry-run", "-snes_max_it", "3"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and len(err.splitlines()) == 1, err
    assert "-snes_max_it: PETSc options of the runs go in the sweep file's run.petsc" in err, err


def test_bad_sweep_file_console_script(tmp_path):
    path = write_sweep(str(tmp_path), BAD["list lengths"][0])
    exe = os.path.join(VENV_BIN, "ancf-sweep")
    if not os.path.exists(exe):
        pytest.skip("console script not installed (pip install -e .)")
    p = subprocess.run([exe, path], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert p.returncode == 2 and len(p.stderr.splitlines()) == 1 and "Traceback" not in p.stderr
    assert p.stderr.startswith("ancf-sweep: ") and "has 3 values" in p.stderr


def test_key_paths_ids_and_data_files(tmp_path):
    assert parse_key_path("loads[0].force[2]") == ("loads", 0, "force", 2)
    with pytest.raises(ValueError):
        parse_key_path("geometry..length")
    assert [format_value(v) for v in (45, 0.86e9, 1e-3, True, "neo-hookean", [1.0, 0, 0])] == \
        ["45", "8.6e+08", "0.001", "true", "neo-hookean", "1,0,0"]
    # colliding last keys get longer labels; relative section files become absolute
    base = os.path.relpath(os.path.join(CONFIGS, "achilles_type3_psi45.yaml"), tmp_path)
    (tmp_path / "a.yaml").write_text(
        f"base: {base}\nparameters:\n  beams[0].material.mu: [1e8, 2e8]\n"
        "  beams[1].material.mu: [3e8]\n  geometry.twist_deg: [0, 45]\n")
    sweep = load_sweep(str(tmp_path / "a.yaml"))
    runs = expand(sweep)
    assert len(runs) == 4
    assert runs[1].run_id == "run_0001__beams0.material.mu=1e+08__twist_deg=45"
    assert runs[1].params["beams[0].material.mu"] == 1e8          # 1e8 read as a number
    cfg = run_config(sweep, runs[1])
    for beam in cfg["beams"]:              # absolute, or relative to the run directory when
        f = beam["section"]["file"]          # the data and the sweep share a tree (a move keeps it)
        assert os.path.isfile(os.path.normpath(os.path.join(runs[1].dir, f))), f
        assert os.path.isabs(f) == (os.path.commonpath([CONFIGS, runs[1].dir]) == os.sep), f
    assert cfg["beams"][1]["material"]["mu"] == 3e8 and cfg["output"]["dir"] == runs[1].dir
    with pytest.raises(SweepError, match="loads"):
        (tmp_path / "b.yaml").write_text(f"base: {base}\nparameters:\n  loads[0].force[3]: [1]\n")
        load_sweep(str(tmp_path / "b.yaml"))


def test_new_solver_outcomes_are_classified(tmp_path):
    """ancf-solve's unstable (exit 4), interrupted (143/130) and disk-full (exit 2, OUTPUT_ERROR)
    endings each get their own sweep status from summary.json (stderr is not read); unstable
    runs count as done; a run that ends without a summary is classified by its exit code."""
    from ancf_petsc.workflows.sweep import classify, run_state, RunSpec

    def case(summary: dict | None, rc: int):
        d = tmp_path / f"r{rc}{(summary or {}).get('status')}"
        d.mkdir()
        if summary is not None:
            (d / "summary.json").write_text(json.dumps({**summary, "steps": []}))
        return classify(str(d), rc), d

    (st, reason), d = case({"status": "unstable", "message": "1 of 2 levels are unstable"}, 4)
    assert (st, reason) == ("unstable", "1 of 2 levels are unstable")
    assert run_state(RunSpec(0, "r", {}, str(d))).status == "unstable"
    msg = "interrupted by SIGTERM on the way to load factor 0.2 (last converged level 0.15)"
    (st, reason), _ = case({"status": "interrupted", "message": msg}, 143)
    assert (st, reason) == ("interrupted", msg)
    msg = "output error: /x: no space left on device for level 3"
    (st, reason), _ = case({"status": "failed", "reason_code": "OUTPUT_ERROR", "message": msg}, 2)
    assert (st, reason) == ("failed", msg)
    assert case(None, -9)[0] == ("crashed", "killed by SIGKILL")
    assert case(None, 1)[0] == ("crashed", "exit code 1")
    assert case(None, 130)[0][0] == "interrupted"
    (st, reason), _ = case(None, 2)            # the sweep checks the config itself: none here
    assert st == "config_error" and reason.endswith("config.yaml: no such config file"), reason


def test_a_killed_run_is_continued_from_its_last_level(tmp_path):
    """A run that stopped early (status interrupted, as SLURM's time limit leaves it) is not
    started again but continued with ancf-solve --restart, locally and by the array script."""
    path = write_sweep(str(tmp_path), {"parameters": {"output.vtk": [False]}, "output": "again"})
    rc, out, _ = run_main([path])
    assert rc == 0, out
    run = expand(load_sweep(path))[0]
    summary_path = os.path.join(run.dir, "summary.json")
    with open(summary_path) as fh:
        s = json.load(fh)
    assert len(s["steps"]) >= 2
    s["status"], s["steps"] = "interrupted", s["steps"][:1]
    with open(summary_path, "w") as fh:
        json.dump(s, fh)
    # and results.h5 with it (a restart continues from results.h5's last level, whose entry
    # completes summary.json)
    truncate_levels(os.path.join(run.dir, "results.h5"), 1, s["steps"][0]["load_factor"])
    its = int(read_csv(tmp_path / "again" / "results.csv")[0]["newton_iterations"])
    rc, out, _ = run_main([path])
    assert rc == 0, out
    with open(summary_path) as fh:
        s = json.load(fh)
    assert s["status"] == "completed" and s["restarted_from"]["step"] == 1
    # results.csv counts the whole run's Newton iterations, not the restarted process's alone
    assert s["newton_iterations"] < its
    assert int(read_csv(tmp_path / "again" / "results.csv")[0]["newton_iterations"]) == its
    rc, _, _ = run_main([path, "--slurm"])
    script = (tmp_path / "again" / "sweep.slurm").read_text()
    assert 'WHERE=(--restart "$RUN_DIR")' in script and '"${WHERE[@]}"' in script
    assert subprocess.run(["bash", "-n", str(tmp_path / "again" / "sweep.slurm")]).returncode == 0


def test_the_shipped_muscle_ratio_sweep_expands_to_valid_configs():
    """configs/sweeps/muscle_ratio.yaml (cited by the README and configs/achilles_psi45_equal_muscles.yaml,
    missing before issue 39): six runs from the soleus alone to the gastrocnemii alone, each a
    valid config whose end forces sum to 1 N per unit load factor."""
    from ancf_petsc.config.parse import parse_config
    sweep = load_sweep(os.path.join(CONFIGS, "sweeps", "muscle_ratio.yaml"))
    runs = expand(sweep)
    shares = []
    for run in runs:
        raw = run_config(sweep, run)
        spec = parse_config(raw, base_dir=run.dir)
        forces = [ld.force[0] for ld in spec.loads]
        assert abs(sum(forces) - 1.0) < 1e-12
        shares.append(forces[0])
    assert shares == [1.0, 0.75, 0.5, 1.0 / 3.0, 0.25, 0.0]


def test_the_shipped_gait_envelope_sweep_expands_to_39_strides():
    """configs/sweeps/gait_envelope.yaml (docs/gait.md): 13 twists x 3 biases, each a valid
    config whose history file (relocated by the sweep) holds the bias's stride."""
    from ancf_petsc.config.parse import parse_config
    sweep = load_sweep(os.path.join(CONFIGS, "sweeps", "gait_envelope.yaml"))
    runs = expand(sweep)
    assert len(runs) == 39
    twists, files = set(), set()
    for run in runs:
        raw = run_config(sweep, run)
        spec = parse_config(raw, base_dir=run.dir)
        assert spec.history is not None
        twists.add(raw["geometry"]["twist_deg"])
        files.add(os.path.basename(raw["history"]["file"]))
        assert os.path.isfile(os.path.normpath(os.path.join(run.dir, raw["history"]["file"])))
    assert twists == set(range(0, 181, 15))
    assert files == {f"stride_walking_{b}.csv" for b in ("gastrocnemius", "uniform", "soleus")}


def test_a_config_error_found_by_the_contact_setup_keeps_its_reason(tmp_path):
    """A run refused by a check past the model (the interfaces' conforming meshes, in the contact
    setup) is classified with the solver's one-line reason, not 'see log.txt'."""
    from ancf_petsc.workflows.sweep.execute import classify
    with open(os.path.join(CONFIGS, "achilles_type3_psi45.yaml")) as fh:
        raw = yaml.safe_load(fh)
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["beams"][0]["elements"] = 3
    with open(tmp_path / "config.yaml", "w") as fh:
        yaml.safe_dump(raw, fh)
    status, reason = classify(str(tmp_path), 2)
    assert status == "config_error"
    assert reason.startswith("config error: beams[1].elements: 4 element(s) against 3 of soleus") \
        and "same number of elements" in reason, reason


def test_a_run_that_completed_as_the_sweep_was_stopped_is_recorded_completed(tmp_path, monkeypatch):
    """Stopping the sweep as a run finishes: mpirun exits 1 when it forwards the signal, but the
    run's summary.json says completed; run.json then says completed too (it said interrupted,
    with reason code COMPLETED)."""
    from types import SimpleNamespace
    from ancf_petsc.workflows.sweep import execute
    from ancf_petsc.workflows.sweep.processes import Active
    script = f"printf '{{\"status\": \"completed\", \"steps\": []}}' > {tmp_path / 'summary.json'}; exit 1"
    monkeypatch.setattr(execute, "solve_command", lambda sweep, run: ["sh", "-c", script])

    class StoppedAfterStart(Active):
        def start(self, cmd, **popen):
            proc = super().start(cmd, **popen)
            self.cancelled.set()
            return proc
    out = execute.execute_run(SimpleNamespace(timeout=60, ranks=2), SimpleNamespace(dir=str(tmp_path)),
                              StoppedAfterStart())
    record = json.load(open(tmp_path / "run.json"))
    assert out.status == record["status"] == "completed" and record["reason_code"] == "COMPLETED"


def test_a_key_path_sets_one_beams_material_when_beams_share_it_by_an_anchor(tmp_path):
    """Two bars written ``material: &m {...}`` and ``material: *m`` (one object under both keys):
    sweeping beams[0].material.mu to 2 MPa set bar2's mu too (its tip 11.18 mm for its 1 MPa's
    24.60 mm), as did a fit's parameter; now the key path's own."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.workflows.calibration.parameters import Parameter, apply
    base = yaml.safe_load(open(UNIAXIAL))
    bar = base["beams"][0]
    bar2 = dict(bar, name="bar2", section=dict(bar["section"], center=[0.0, 0.02]))
    text = yaml.safe_dump(dict(base, beams=[bar, bar2]), sort_keys=False)
    assert "material: *" in text                         # an alias, as a user writes it
    (tmp_path / "anchored.yaml").write_text(text)
    with open(tmp_path / "sweep.yaml", "w") as fh:
        yaml.safe_dump({"base": "anchored.yaml", "parameters": {"beams[0].material.mu": [2.0e6]}}, fh)
    sweep = load_sweep(str(tmp_path / "sweep.yaml"))
    run = expand(sweep)[0]
    mus = [b.material["mu"] for b in parse_config(run_config(sweep, run), base_dir=CONFIGS).beams]
    assert mus == [2.0e6, 1.0e6]
    raw = yaml.safe_load(text)
    fitted = apply(raw, [Parameter("mu", [parse_key_path("beams[0].material.mu")], 1e5, 1e7, 1e6)], [3.0e6])
    assert [float(b["material"]["mu"]) for b in fitted["beams"]] == [3.0e6, 1.0e6]
    assert float(raw["beams"][1]["material"]["mu"]) == 1.0e6


def test_collect_does_not_report_a_run_solved_with_an_edited_base_config(tmp_path):
    """A base config edited after the runs (bulk modulus 50 -> 20 MPa): --dry-run said 'todo',
    but --collect listed the 50 MPa answers as completed runs of the edited sweep, exit 0."""
    shutil.copy(UNIAXIAL, tmp_path / "base.yaml")
    path = write_sweep(str(tmp_path), {"parameters": {"output.vtk": [False]}, "output": "o"})
    body = yaml.safe_load(open(path))
    body["base"] = "base.yaml"
    (tmp_path / "sweep.yaml").write_text(yaml.safe_dump(body))
    assert run_main([path])[0] == 0
    text = (tmp_path / "base.yaml").read_text()
    (tmp_path / "base.yaml").write_text(text.replace("bulk_modulus: 50.0e6", "bulk_modulus: 20.0e6"))
    rc, out, _ = run_main([path, "--collect"])
    row = read_csv(tmp_path / "o" / "results.csv")[0]
    assert rc == 1 and "1 runs: 0 completed, 1 missing" in out, out
    assert row["status"] == "missing" and not row.get("tip_dx") and "edited" in row["reason"], row
    (tmp_path / "base.yaml").write_text(text)       # as it ran: completed again
    rc, out, _ = run_main([path, "--collect"])
    assert rc == 0 and read_csv(tmp_path / "o" / "results.csv")[0]["tip_dx"] != ""


def _a_stopped_run_that_cannot_restart(tmp_path, name: str):
    """A completed uniaxial run made 'interrupted' after level 1, its restart data removed:
    ancf-solve --restart refuses it (exit 2) without writing summary.json."""
    import h5py
    path = write_sweep(str(tmp_path), {"parameters": {"output.vtk": [False]}, "output": name}, f"{name}.yaml")
    assert run_main([path])[0] == 0
    run = expand(load_sweep(path))[0]
    summary_path = os.path.join(run.dir, "summary.json")
    with open(summary_path) as fh:
        s = json.load(fh)
    s.update(status="interrupted", reason_code="SIGTERM", steps=s["steps"][:1],
             message="interrupted by SIGTERM in the Newton solve at load factor 0.2 (last converged 0.1)")
    with open(summary_path, "w") as fh:
        json.dump(s, fh)
    truncate_levels(os.path.join(run.dir, "results.h5"), 1, s["steps"][0]["load_factor"])
    with h5py.File(os.path.join(run.dir, "results.h5"), "a") as h5:
        del h5["steps/step_0001/restart"]
    return path, run


def test_an_attempt_that_writes_no_summary_is_not_read_from_the_one_before(tmp_path):
    """A restart ancf-solve refused (exit 2, 'config error: --restart: ... written without restart
    data') was recorded 'interrupted by SIGTERM ...' (reason_code SIGTERM), the stopped attempt's
    summary.json, on every further ancf-sweep; so was a SLURM task whose launch failed."""
    path, run = _a_stopped_run_that_cannot_restart(tmp_path, "local")
    rc, out, _ = run_main([path])
    row = read_csv(tmp_path / "local" / "results.csv")[0]
    assert rc == 1 and row["status"] == "config_error" and row["reason_code"] == "CONFIG_ERROR", out
    assert row["reason"].startswith("config error: --restart: ") and "without restart data" in row["reason"]
    if shutil.which("srun"):
        return                                    # on a SLURM host, do not launch srun here
    path, run = _a_stopped_run_that_cannot_restart(tmp_path, "array")
    assert run_main([path, "--slurm"])[0] == 0
    env = dict(os.environ, **MPI_ENV, SLURM_ARRAY_TASK_ID="0")
    p = subprocess.run(["bash", str(tmp_path / "array" / "sweep.slurm")], env=env,
                       capture_output=True, text=True, timeout=120)
    with open(os.path.join(run.dir, "run.json")) as fh:
        record = json.load(fh)
    assert p.returncode == 2 and record["status"] == "config_error", (p.stdout, p.stderr, record)
    assert "without restart data" in record["reason"]


def test_a_run_made_with_other_petsc_options_is_run_again(tmp_path):
    """run.petsc changed after the sweep ran (here -snes_atol 1e-4 dropped: tip 0.024604212893
    against 0.024604212883 m): every run was 'skipped (already done)', the old answer kept with
    no word (run.petsc is not in config.yaml; params.json records it now)."""
    body = {"parameters": {"output.vtk": [False]}, "output": "o", "run": {"petsc": ["-snes_atol", "1e-4"]}}
    path = write_sweep(str(tmp_path), body)
    assert run_main([path])[0] == 0
    loose = read_csv(tmp_path / "o" / "results.csv")[0]["tip_dx"]
    write_sweep(str(tmp_path), dict(body, run={}))
    rc, out, _ = run_main([path, "--dry-run"])
    assert "1 to run, 0 already done" in out, out
    rc, out, _ = run_main([path, "--collect"])
    assert rc == 1 and "run.petsc" in read_csv(tmp_path / "o" / "results.csv")[0]["reason"]
    rc, out, _ = run_main([path])
    assert rc == 0 and "skipped" not in out, out
    assert read_csv(tmp_path / "o" / "results.csv")[0]["tip_dx"] != loose


def test_a_run_whose_data_file_was_edited_is_run_again(tmp_path):
    """The load history a sweep's runs read (history.file: load.csv) edited after they ran, its
    peak 45 -> 20 N: every run was 'skipped (already done)' and results.csv kept the 45 N tip
    (24.60 mm, against 9.75 mm at 20 N) with no word: config.yaml names the file, not its
    contents. params.json records the digests of the files the run reads now."""
    raw = yaml.safe_load(open(UNIAXIAL))
    raw.pop("steps")
    raw["history"] = {"file": "load.csv", "time": "time"}
    raw["loads"][0].update(traction_force=[1.0, 0.0, 0.0], column="f")
    (tmp_path / "base.yaml").write_text(yaml.safe_dump(raw, sort_keys=False))
    (tmp_path / "load.csv").write_text("time,f\n0,0\n1,20\n2,45\n")
    body = {"base": "base.yaml", "parameters": {"output.vtk": [False]}, "output": "o"}
    (tmp_path / "sweep.yaml").write_text(yaml.safe_dump(body))
    path = str(tmp_path / "sweep.yaml")
    assert run_main([path])[0] == 0
    at_45 = float(read_csv(tmp_path / "o" / "results.csv")[0]["tip_dx"])
    (tmp_path / "load.csv").write_text("time,f\n0,0\n1,10\n2,20\n")
    assert "1 to run, 0 already done" in run_main([path, "--dry-run"])[1]
    rc, out, _ = run_main([path, "--collect"])
    row = read_csv(tmp_path / "o" / "results.csv")[0]
    assert rc == 1 and row["status"] == "missing" and "data file" in row["reason"] and not row.get("tip_dx")
    rc, out, _ = run_main([path])
    assert rc == 0 and "skipped" not in out, out
    (tmp_path / "sweep.yaml").write_text(yaml.safe_dump(dict(body, output="fresh")))
    assert run_main([path])[0] == 0                  # the edited file, in a new directory
    at_20 = float(read_csv(tmp_path / "fresh" / "results.csv")[0]["tip_dx"])
    assert float(read_csv(tmp_path / "o" / "results.csv")[0]["tip_dx"]) == at_20 < 0.5 * at_45
    if shutil.which("srun"):
        return                                    # on a SLURM host, do not launch srun here
    # an array task resubmitted after the edit (no --slurm again) solves it again too
    assert run_main([path, "--slurm"])[0] == 0
    (tmp_path / "load.csv").write_text("time,f\n0,0\n1,20\n2,45\n")
    assert run_main([path, "--collect"])[0] == 1
    env = dict(os.environ, **MPI_ENV, SLURM_ARRAY_TASK_ID="0")
    task = ["bash", str(tmp_path / "fresh" / "sweep.slurm")]
    p = subprocess.run(task, env=env, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and "load.csv was edited since it ran" in p.stdout, (p.stdout, p.stderr)
    assert run_main([path, "--collect"])[0] == 0
    assert float(read_csv(tmp_path / "fresh" / "results.csv")[0]["tip_dx"]) == at_45
    p = subprocess.run(task, env=env, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and "already done; skipping" in p.stdout, (p.stdout, p.stderr)


def _stop_after_level_1(run) -> float:
    """Make a completed uniaxial run look stopped after its first level (SLURM's time limit),
    its run.json as the sweep recorded that attempt; returns the attempt's wall time."""
    summary_path = os.path.join(run.dir, "summary.json")
    with open(summary_path) as fh:
        s = json.load(fh)
    s.update(status="interrupted", reason_code="SIGTERM", steps=s["steps"][:1])
    with open(summary_path, "w") as fh:
        json.dump(s, fh)
    truncate_levels(os.path.join(run.dir, "results.h5"), 1, s["steps"][0]["load_factor"])
    with open(os.path.join(run.dir, "run.json")) as fh:
        record = json.load(fh)
    record.update(status="interrupted", reason_code="SIGTERM", wall_time=7.5)
    with open(os.path.join(run.dir, "run.json"), "w") as fh:
        json.dump(record, fh)
    return 7.5


@pytest.mark.parametrize("how", ["local", "array"])
def test_a_continued_runs_wall_time_is_the_whole_runs(tmp_path, how):
    """results.csv gave a run continued with --restart the wall time of its last attempt only
    (the 4-element tendon stopped at 300 N and continued: 0.67 s against 2.39 s uninterrupted),
    while its newton_iterations count the whole run (a74a832): resubmitted cells looked cheap.
    run.json now carries the attempts it continues (earlier_wall_time), locally and in the
    array script, and results.csv adds them."""
    if how == "array" and shutil.which("srun"):
        pytest.skip("on a SLURM host, do not launch srun here")
    path = write_sweep(str(tmp_path), {"parameters": {"output.vtk": [False]}, "output": "o"})
    assert run_main([path])[0] == 0
    run = expand(load_sweep(path))[0]
    earlier = _stop_after_level_1(run)
    if how == "local":
        assert run_main([path])[0] == 0
    else:
        assert run_main([path, "--slurm"])[0] == 0
        env = dict(os.environ, **MPI_ENV, SLURM_ARRAY_TASK_ID="0")
        p = subprocess.run(["bash", str(tmp_path / "o" / "sweep.slurm")], env=env,
                           capture_output=True, text=True, timeout=120)
        assert p.returncode == 0 and "continuing" in p.stdout, (p.stdout, p.stderr)
        assert run_main([path, "--collect"])[0] == 0
    with open(os.path.join(run.dir, "summary.json")) as fh:
        assert json.load(fh)["restarted_from"]["step"] == 1
    with open(os.path.join(run.dir, "run.json")) as fh:
        last = json.load(fh)["wall_time"]
    row = read_csv(tmp_path / "o" / "results.csv")[0]
    assert row["status"] == "completed" and float(row["wall_time"]) == pytest.approx(earlier + last, abs=1e-3)


def test_a_run_another_process_is_solving_is_left_alone(tmp_path):
    """A second ancf-sweep of the same sweep (another terminal) started every run the first was
    solving: it truncated their log.txt, wrote over their run.json and summary.json, and its
    ancf-solve, refused by the output directory's lock, was recorded 'config_error: input error
    (exit code 2); see log.txt'. A run whose directory a live process holds is now not started."""
    from ancf_petsc.io.files import DirectoryLock
    path = write_sweep(str(tmp_path), {"parameters": {"output.vtk": [False]}, "output": "o"})
    run = expand(load_sweep(path))[0]
    os.makedirs(run.dir)
    lock = DirectoryLock(run.dir)
    lock.acquire()                                  # as a running ancf-solve holds it: this process
    rc, out, _ = run_main([path])
    assert rc == 1 and f"being run by another process (pid {os.getpid()}" in out, out
    assert not os.path.exists(os.path.join(run.dir, "log.txt"))
    assert not os.path.exists(os.path.join(run.dir, "run.json"))
    lock.release()                                  # the other process is done
    assert run_main([path])[0] == 0


def test_an_attempt_stopped_before_it_starts_keeps_the_record_before(tmp_path, monkeypatch):
    """A Ctrl-C between a restart attempt's run.json and its ancf-solve (Active.start: None)
    removed run.json: the interrupted attempt's record and wall time were gone, and results.csv
    gave the continued run the last attempt's wall time only."""
    from ancf_petsc.workflows.sweep import execute
    from ancf_petsc.workflows.sweep.processes import Active
    path = write_sweep(str(tmp_path), {"parameters": {"output.vtk": [False]}, "output": "o"})
    assert run_main([path])[0] == 0
    sweep = load_sweep(path)
    run = expand(sweep)[0]
    _stop_after_level_1(run)
    with open(os.path.join(run.dir, "run.json")) as fh:
        before = json.load(fh)
    monkeypatch.setattr(Active, "start", lambda self, cmd, **popen: None)
    assert execute.execute_run(sweep, run) is None
    with open(os.path.join(run.dir, "run.json")) as fh:
        assert json.load(fh) == before
    monkeypatch.undo()
    assert run_main([path])[0] == 0
    row = read_csv(tmp_path / "o" / "results.csv")[0]
    with open(os.path.join(run.dir, "run.json")) as fh:
        assert float(row["wall_time"]) == pytest.approx(before["wall_time"] + json.load(fh)["wall_time"], abs=1e-3)


def test_a_run_that_completed_as_its_time_ran_out_is_recorded_completed(tmp_path):
    """run.timeout 2 s on the 4-element tendon as a SLURM task: `timeout` signalled ancf-solve
    as it finished its last level (400 N), summary.json said completed, and run.json said
    'timeout: timed out after 2 s; last converged load factor 400' (the local sweep: '1
    timeout', exit 1) while results.csv and --collect said completed; a run stopped by Ctrl-C
    just so was already recorded completed."""
    from ancf_petsc.workflows.sweep import RunSpec, classify, run_state
    from ancf_petsc.workflows.sweep.execute import finish_slurm_task
    (tmp_path / "summary.json").write_text(json.dumps({"status": "completed", "steps": [{"load_factor": 400.0}]}))
    assert classify(str(tmp_path), 124, timed_out=True, timeout=2.0) == ("completed", "")
    assert finish_slurm_task(str(tmp_path), 124, 3.1, timeout=2.0).status == "completed"
    assert run_state(RunSpec(0, "r", {}, str(tmp_path))).status == "completed"
    (tmp_path / "summary.json").write_text(json.dumps({"status": "interrupted", "steps": [{"load_factor": 300.0}]}))
    assert classify(str(tmp_path), 124, timed_out=True, timeout=2.0) == (
        "timeout", "timed out after 2 s; last converged load factor 300")


@pytest.mark.parametrize("flags", [[], ["--dry-run"], ["--slurm"]])
def test_a_swept_value_the_config_refuses_is_refused_with_the_sweep(tmp_path, flags):
    """beams[0].elements: [1, 0] ran the good run and recorded the other 'config_error' when its
    turn came (on a cluster: after the array was queued).  The sweep is now refused at once, one
    line naming the parameter, the run and the config's own error, exit 2; nothing is written."""
    path = write_sweep(str(tmp_path), {"mode": "grid", "output": "bad",
                                       "parameters": {"beams[0].elements": [1, 0],
                                                      "beams[0].material.mu": [1e6, 2e6]}})
    rc, out, err = run_main([path, *flags])
    assert rc == 2 and err.count("\n") == 1, err
    assert "parameters.beams[0].elements: run run_0002__elements=0__mu=1e+06" in err
    assert err.rstrip().endswith("is no valid config: beams[0].elements: must be >= 1; got 0"), err
    assert not (tmp_path / "bad").exists()
