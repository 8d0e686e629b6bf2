"""Restart (`ancf-solve CONFIG --restart DIR`): a run killed with SIGKILL mid-column continues
from its last converged level and gives the answers of an uninterrupted run; a changed model
is refused with one line; another rank count is fine."""
import json
import os
import signal
import subprocess
import time

import numpy as np
import pytest

from ancf_petsc.errors import InputError

from helpers import CONFIGS, MPI_ENV, ROOT, VENV_BIN, load_raw, read_summary, solve_cli, write_config
from helpers import probes_table


def _config(tmp_path, mode="sliding", name="c", linear="auto"):
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["solver"] = dict(raw.get("solver") or {}, linear=linear)
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["contact"]["mode"] = mode
    raw["output"] = {"dir": str(tmp_path / "unused"), "vtk": False}
    return write_config(raw, tmp_path / f"{name}.yaml"), raw


def _kill_writers(out, timeout=30.0):
    """SIGKILL every process whose command line names ``out`` and wait until none is left: Open
    MPI starts the ranks in process groups of their own, so killing mpirun's group can leave a
    rank writing into ``out`` while the restart already runs there."""
    mark = str(out).encode()
    t0 = time.time()
    while time.time() - t0 < timeout:
        alive = []
        for pid in (int(d) for d in os.listdir("/proc") if d.isdigit() and int(d) != os.getpid()):
            try:
                with open(f"/proc/{pid}/cmdline", "rb") as fh:
                    if mark in fh.read():
                        alive.append(pid)
                        os.kill(pid, signal.SIGKILL)
            except (OSError, ProcessLookupError):
                pass
        if not alive:
            return
        time.sleep(0.05)
    raise AssertionError(f"processes writing into {out} survived SIGKILL for {timeout} s")


def _killed_run(cfg, out, ranks, after_levels=4, timeout=120):
    """Start ancf-solve, SIGKILL it (every process writing into ``out``, and its process group)
    once ``after_levels`` levels are written (``read_results``: summary.json, rewritten at most
    every 0.5 s, completed from results.h5)."""
    from ancf_petsc.io.reader import read_results
    exe = os.path.join(VENV_BIN, "ancf-solve")
    cmd = [exe, cfg, "--output-dir", str(out), "--quiet"]
    if ranks > 1:
        cmd = ["mpirun", "--oversubscribe", "-n", str(ranks)] + cmd
    p = subprocess.Popen(cmd, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT), cwd=ROOT,
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    t0 = time.time()
    try:
        while time.time() - t0 < timeout:
            try:
                if len(read_results(str(out)).summary["steps"]) >= after_levels:
                    break
            except (OSError, ValueError, KeyError, InputError):
                pass
            if p.poll() is not None:
                break
            time.sleep(0.02)
    finally:
        _kill_writers(out)                   # the ranks first: they are not in mpirun's group
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        p.wait()
        _kill_writers(out)
    s = read_results(str(out)).summary
    assert s["status"] == "running" and after_levels <= len(s["steps"]) < 13, (s["status"], len(s["steps"]))


@pytest.mark.mpi
@pytest.mark.slow
@pytest.mark.parametrize("ranks,restart_ranks,mode,linear", [
    (1, 1, "sliding", "auto"), (2, 2, "sliding", "auto"), (1, 2, "sliding", "auto"),
    (1, 1, "unilateral", "auto"), (1, 2, "sliding", "fieldsplit")])
def test_killed_column_restarts_to_the_uninterrupted_answers(tmp_path, ranks, restart_ranks, mode, linear):
    cfg, _ = _config(tmp_path, mode, linear=linear)
    p = solve_cli(cfg, extra=["--output-dir", str(tmp_path / "full"), "--quiet"])
    assert p.returncode == 0, p.stderr
    full = read_summary(tmp_path / "full")
    _killed_run(cfg, tmp_path / "killed", ranks)
    p = solve_cli(cfg, ranks=restart_ranks, extra=["--restart", str(tmp_path / "killed"), "--quiet"])
    assert p.returncode == 0, p.stdout + p.stderr
    s = read_summary(tmp_path / "killed")
    assert s["status"] == "completed" and s["restarted_from"]["step"] >= 4 and len(s["steps"]) == 13
    a, b = probes_table(full), probes_table(s)
    assert np.abs(a - b).max() <= 1e-10 * np.abs(a).max(), np.abs(a - b).max() / np.abs(a).max()
    import h5py
    with h5py.File(tmp_path / "killed" / "results.h5") as h5:
        assert h5["steps"].attrs["converged"] == 13 and sorted(h5["steps"])[-1] == "step_0013"


@pytest.mark.mpi
@pytest.mark.slow
def test_restart_refuses_another_model(tmp_path):
    cfg, raw = _config(tmp_path)
    raw["steps"] = raw["steps"][:2]
    p = solve_cli(write_config(raw, tmp_path / "short.yaml"), extra=["--output-dir", str(tmp_path / "run")])
    assert p.returncode == 0, p.stderr
    raw["beams"][1]["elements"] = 8
    raw["steps"] = load_raw("achilles_type3_psi45.yaml")["steps"]
    p = solve_cli(write_config(raw, tmp_path / "other.yaml"), ranks=2, extra=["--restart", str(tmp_path / "run")])
    lines = [ln for ln in p.stderr.splitlines() if ln.startswith("ancf-solve:")]
    assert p.returncode == 2 and len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    assert "beams/medial_gastrocnemius/elements (4 → 8)" in lines[0]
    assert str(tmp_path / "run") in lines[0]
    p = solve_cli(cfg, extra=["--restart", str(tmp_path / "nowhere")])
    assert p.returncode == 2 and "nowhere: no such directory" in p.stderr
    assert not os.path.exists(tmp_path / "nowhere")


# ------------------------------------------------------------------------------ free motions
@pytest.mark.mpi
@pytest.mark.slow
def test_unsupported_models_are_refused_before_solving(tmp_path):
    """No supports at all, and a strand held only by frictionless contact (the centre of a
    twisted hexagonal bundle without its support): exit 2, one line naming the beam and motion,
    on 1 and 2 ranks, before any level is solved."""
    from ancf_petsc.config.bundle import expand_bundle
    bar = load_raw("uniaxial_neohookean.yaml")
    bar.pop("boundary_conditions")
    strand = expand_bundle(dict(load_raw("bundle_hex7.yaml"),
                                bundle=dict(load_raw("bundle_hex7.yaml")["bundle"], pulled_end="free")))
    strand["boundary_conditions"] = [b for b in strand["boundary_conditions"] if b["beam"] != "fascicle0"]
    for name, raw, words in (("bar", bar, ["bar (free: translation along x, translation along y",
                                           "rotation about z)"]),
                             ("strand", strand, ["fascicle0 (free: ", "rotation about x",
                                                 "frictionless contact lets beams slide"])):
        raw["output"] = {"dir": str(tmp_path / name)}
        cfg = write_config(raw, tmp_path / f"{name}.yaml")
        for ranks in (1, 2):
            p = solve_cli(cfg, ranks=ranks, extra=["--quiet"])
            lines = [ln for ln in p.stderr.splitlines() if ln.startswith("ancf-solve:")]
            assert p.returncode == 2 and len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
            assert "boundary_conditions: nothing holds" in lines[0] and all(w in lines[0] for w in words), lines[0]
        assert not (tmp_path / name / "results.h5").exists()


def _short_run(tmp_path, raw, name="run"):
    raw = dict(raw, steps=raw["steps"][:3])
    p = solve_cli(write_config(raw, tmp_path / f"{name}.yaml"), extra=["--output-dir", str(tmp_path / name),
                                                                       "--quiet"])
    assert p.returncode == 0, p.stderr
    return raw


@pytest.mark.slow
def test_restart_compares_the_resolved_model_not_its_text(tmp_path):
    """Issue 25: a section file whose pixel scale changed between the kill and the restart (the
    same YAML) is refused; the same model written differently (``units`` left out, a number
    written another way, ``node: -1`` for ``last``, ``interfaces: auto`` written out, another
    path to the same data file) is accepted; changed steps before the restart point are refused, more levels after it are
    solved."""
    import shutil
    import yaml
    data = tmp_path / "data"
    data.mkdir()
    shutil.copy(os.path.join(CONFIGS, "data", "achilles_type3_sections.yaml"), data / "sections.yaml")
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = "data/sections.yaml"
    raw["output"] = {"vtk": False}
    raw = _short_run(tmp_path, raw)
    # the same model, written differently
    same = json.loads(json.dumps(raw))
    same.pop("units", None)
    same["beams"][0]["material"]["mu"] = float("1.031e+08")
    same["loads"][0]["node"] = -1
    same.setdefault("contact", {})["interfaces"] = [        # what interfaces: auto finds, written out
        {"a": "medial_gastrocnemius", "b": "soleus", "curve": "mg_sol"},
        {"a": "lateral_gastrocnemius", "b": "soleus"},
        {"a": "lateral_gastrocnemius", "b": "medial_gastrocnemius", "curve": "lg_mg"}]
    for b in same["beams"]:
        b["section"]["file"] = str(data / "sections.yaml")
    same["steps"] = raw["steps"] + [45]
    cfg = write_config(same, tmp_path / "same.yaml")
    p = solve_cli(cfg, extra=["--restart", str(tmp_path / "run"), "--quiet"])
    assert p.returncode == 0, p.stderr
    s = read_summary(tmp_path / "run")
    assert [st["load_factor"] for st in s["steps"]] == raw["steps"] + [45]
    # steps that differ before the restart point
    other = dict(same, steps=[10, 25, 30, 45, 60])
    p = solve_cli(write_config(other, tmp_path / "other.yaml"), extra=["--restart", str(tmp_path / "run")])
    assert p.returncode == 2 and "differ from the run's converged levels at step 2: 20 was solved" in p.stderr
    # the section data file changed (pixel scale +25 % in length: areas +56 %)
    with open(data / "sections.yaml") as fh:
        sec = yaml.safe_load(fh)
    sec["scale_m_per_px"] = 1.25 * float(sec["scale_m_per_px"])
    with open(data / "sections.yaml", "w") as fh:
        yaml.safe_dump(sec, fh)
    p = solve_cli(cfg, extra=["--restart", str(tmp_path / "run")])
    lines = [ln for ln in p.stderr.splitlines() if ln.startswith("ancf-solve:")]
    assert p.returncode == 2 and len(lines) == 1, p.stderr
    assert "written by another model" in lines[0] and "beams/soleus/" in lines[0]


def test_restart_refuses_a_run_with_another_pressure_space_at_clamped_ends(tmp_path):
    """The clamped sandwich run with the pressure functions kept at its clamped ends
    (``supported_ends: keep``) is another multiplier space than the default's folded one: a
    restart names the setting (its stored state would not be an equilibrium of this model)."""
    raw = load_raw("shear_lag_sandwich.yaml")
    raw["steps"] = [0.5]
    raw["contact"].setdefault("projection", {})["supported_ends"] = "keep"
    p = solve_cli(write_config(raw, tmp_path / "keep.yaml"),
                  extra=["--output-dir", str(tmp_path / "run"), "--quiet"])
    assert p.returncode == 0, p.stderr
    raw["steps"] = [0.5, 1.0]
    raw["contact"]["projection"].pop("supported_ends")
    p = solve_cli(write_config(raw, tmp_path / "merge.yaml"), extra=["--restart", str(tmp_path / "run")])
    lines = [ln for ln in p.stderr.splitlines() if ln.startswith("ancf-solve:")]
    assert p.returncode == 2 and len(lines) == 1, p.stderr
    assert "written by another model" in lines[0] and "supported_ends: absent →" in lines[0], lines[0]


def test_a_restart_with_more_steps_stores_the_config_it_solved_with(tmp_path):
    """The pretwisted bar solved to 0.5, then restarted to 1.0 with the config's four steps:
    results.h5 /model config_yaml said steps [0.25, 0.5] beside four levels (the first run's
    config); now the restarted config's, whose steps are the levels there."""
    import h5py
    import yaml
    from helpers import run_inline
    from ancf_petsc.api import solve
    from ancf_petsc.config.parse import parse_config
    raw = load_raw("pretwisted_bar.yaml")
    short = dict(raw, steps=[0.25, 0.5], output={"vtk": False})
    run_inline(short, tmp_path)
    spec = parse_config(dict(raw, output={"dir": str(tmp_path), "vtk": False}), base_dir=CONFIGS)
    assert solve(spec, log=lambda s: None, restart=str(tmp_path)).status == "completed"
    with h5py.File(tmp_path / "results.h5") as h5:
        stored = yaml.safe_load(h5["model"].attrs["config_yaml"])
        levels = [h5["steps"][k].attrs["load_factor"] for k in sorted(h5["steps"])]
    assert levels == [0.25, 0.5, 0.75, 1.0] and stored["steps"] == levels, stored["steps"]


@pytest.mark.mpi
@pytest.mark.slow
def test_a_restart_on_other_ranks_stores_its_partition(tmp_path):
    """A 3-element cantilever solved to 0.5 on one rank, restarted to 1.0 on two: results.h5
    /model/partition kept the first run's (elements per rank [3], every element on rank 0)
    while summary.json said ranks 2, [2, 1]; now both describe the restarted process."""
    import h5py
    raw = load_raw("bending_neohookean.yaml")
    raw["beams"][0]["elements"] = 3
    raw["output"] = {"dir": str(tmp_path / "run"), "vtk": False}
    short = write_config(dict(raw, steps=[0.25, 0.5]), tmp_path / "short.yaml")
    assert solve_cli(short, extra=["--quiet"]).returncode == 0
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), ranks=2,
                  extra=["--restart", str(tmp_path / "run"), "--quiet"])
    assert p.returncode == 0, p.stderr
    s = read_summary(tmp_path / "run")
    with h5py.File(tmp_path / "run" / "results.h5") as h5:
        part = h5["model/partition"]
        stored = part.attrs["elements_per_rank"].tolist(), part["element_rank"][()].tolist()
    assert s["ranks"] == 2 and s["partition"]["elements_per_rank"] == [2, 1]
    assert stored == ([2, 1], [0, 0, 1]), stored
