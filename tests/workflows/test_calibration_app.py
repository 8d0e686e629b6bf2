"""ancf-fit end to end on the one-element bar (issue 28): files and figures, a calibration stopped
by SIGINT or SIGKILL resumes from its log to the uninterrupted answer, mpirun -n 2 and -n 3 give
the serial answer, and a multi-start fit runs as a SLURM array (the script run by bash, the other
tasks as ancf-fit --task) and is collected without solving its starts again."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import time

import numpy as np
import pytest

from calibration_cases import LEVELS, TRUE, bar_case, write_csv
from helpers import MPI_ENV, ROOT, VENV_BIN, petsc_init

FIT = os.path.join(VENV_BIN, "ancf-fit")
ENV = dict(os.environ, **MPI_ENV)


def noisy_case(directory, **extra) -> str:
    """The bar case with twin data (the truth + a fixed noise draw) in data.csv."""
    petsc_init()
    from ancf_petsc.workflows.calibration import load_fit
    from ancf_petsc.workflows.calibration.twin import draw, exact_data
    path = bar_case(directory, **extra)
    spec = load_fit(path)
    data = draw(spec, exact_data(spec, TRUE), np.random.default_rng(7))
    write_csv(os.path.join(directory, "data.csv"), {"level": LEVELS, "u_mm": data["elongation"] * 1e3,
                                                   "ry": data["lateral"]})
    return path


def run(args, ranks: int = 1, timeout: float = 300) -> subprocess.CompletedProcess:
    cmd = [FIT] + args
    if ranks > 1:
        cmd = ["mpirun", "--oversubscribe", "-n", str(ranks)] + cmd
    return subprocess.run(cmd, capture_output=True, text=True, env=ENV, cwd=ROOT, timeout=timeout)


def result(out_dir) -> dict:
    with open(os.path.join(out_dir, "fit.json")) as fh:
        return json.load(fh)


def values(res: dict) -> np.ndarray:
    return np.array([p["value"] for p in res["parameters"]])


def same_answer(res: dict, ref: dict) -> bool:
    """The same optimum to 1e-3 of a standard error: the samples solved after a resume (or on
    another rank) start from other states, so they agree to the solver's tolerance, and the
    optimiser stops within its own tolerance (xtol 1e-8) of the same point."""
    return all(abs(p["value"] - q["value"]) <= 1e-3 * q["se"] for p, q in zip(res["parameters"], ref["parameters"]))


def near_truth(res: dict) -> bool:
    """The true values within 4 reported standard errors (the coverage of the intervals is the
    twin test's, tests/workflows/test_calibration_fit.py)."""
    return all(abs(p["value"] - t) <= 4 * p["se"] for p, t in zip(res["parameters"], TRUE))


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    d = str(tmp_path_factory.mktemp("fit"))
    path = noisy_case(d, identifiability={"points": 7})
    p = run([path, "--out", os.path.join(d, "serial")])
    assert p.returncode == 0, p.stderr
    return d, path, result(os.path.join(d, "serial")), p.stdout


def test_a_fit_writes_its_report_figures_and_log(serial):
    d, _, res, stdout = serial
    out = os.path.join(d, "serial")
    for f in ("fit.json", "report.md", "fit.png", "profiles.png", "samples.jsonl"):
        assert os.path.getsize(os.path.join(out, f)) > 0, f
    assert near_truth(res) and values(res) == pytest.approx(TRUE, rel=0.05)
    assert [p["verdict"] for p in res["parameters"]] == ["determined", "determined"]
    assert res["status"] == "converged" and res["samples"] == {"completed": res["throughput"]["samples"]}
    lines = open(os.path.join(out, "samples.jsonl")).read().splitlines()
    assert len(lines) == 1 + res["throughput"]["samples"]
    first = json.loads(lines[1])
    assert {"parameters", "residuals", "status", "reason_code", "u"} <= set(first)
    assert "[fit] mu = 1.19" in stdout and "determined" in stdout


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGKILL], ids=["SIGINT", "SIGKILL"])
def test_a_stopped_calibration_resumes_from_its_log(serial, sig):
    d, path, ref, _ = serial
    out = os.path.join(d, f"stopped_{sig.name}")
    log = os.path.join(out, "samples.jsonl")
    proc = subprocess.Popen([FIT, path, "--out", out, "--quiet"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=ENV, cwd=ROOT)
    t0 = time.time()
    while time.time() - t0 < 120:
        if os.path.exists(log) and sum(1 for _ in open(log)) > 12:
            break
        time.sleep(0.02)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    done = sum(1 for _ in open(log)) - 1
    assert 10 < done < ref["throughput"]["samples"]
    if sig == signal.SIGINT:
        assert proc.returncode == 130 and err.count("\n") == 1 and "interrupted" in err, err
    p = run([path, "--out", out])
    assert p.returncode == 0, p.stderr
    assert "resuming:" in p.stdout
    res = result(out)
    assert res["throughput"]["resumed"] >= done - 1          # a line cut by SIGKILL is dropped
    assert same_answer(res, ref), (values(res), values(ref))
    assert [p["verdict"] for p in res["parameters"]] == [p["verdict"] for p in ref["parameters"]]


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [2, 3])
def test_mpirun_gives_the_serial_answer(serial, ranks):
    d, path, ref, _ = serial
    out = os.path.join(d, f"ranks{ranks}")
    p = run([path, "--out", out, "--quiet"], ranks=ranks)
    assert p.returncode == 0, p.stderr
    res = result(out)
    assert same_answer(res, ref), (values(res), values(ref))
    se = np.array([p["se"] for p in res["parameters"]])
    assert se == pytest.approx(np.array([p["se"] for p in ref["parameters"]]), rel=1e-4)
    assert [p["verdict"] for p in res["parameters"]] == [p["verdict"] for p in ref["parameters"]]
    ranks_used = {json.loads(line)["rank"] for line in open(os.path.join(out, "samples.jsonl")).readlines()[1:]}
    assert ranks_used == set(range(ranks))


def test_a_multi_start_fit_as_a_slurm_array(tmp_path):
    d = str(tmp_path)
    path = noisy_case(d, optimizer={"starts": 3, "seed": 2}, identifiability={"profiles": False},
                      slurm={"time": "00:10:00"})
    out = os.path.join(d, "out")
    p = run([path, "--slurm"])
    assert p.returncode == 0, p.stderr
    script = open(os.path.join(out, "fit.slurm")).read()
    assert "#SBATCH --array=0-2" in script and "#SBATCH --time=00:10:00" in script and "--task" in script
    env = dict(ENV, SLURM_ARRAY_TASK_ID="0", ANCF_VENV=os.path.join(ROOT, ".venv"))
    b = subprocess.run(["bash", os.path.join(out, "fit.slurm")], capture_output=True, text=True, env=env,
                       cwd=out, timeout=300)
    assert b.returncode == 0, b.stdout + b.stderr
    for k in (1, 2):
        assert run([path, "--task", str(k), "--quiet"]).returncode == 0
    assert run([path, "--task", "3"]).returncode == 2                       # not a start
    solved = sum(result(os.path.join(out, "starts", str(k)))["throughput"]["samples"] for k in range(3))
    c = run([path, "--collect"])
    assert c.returncode == 0, c.stderr
    res = result(out)
    assert f"{solved} sample(s) taken" in c.stdout or "sample(s) taken" in c.stdout
    assert res["throughput"]["solved_now"] == 0                  # every start replayed from the logs
    assert near_truth(res)
    best = min(res["starts"], key=lambda s: s[1])
    assert res["cost"] == pytest.approx(best[1])
