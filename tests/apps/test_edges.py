"""Broken inputs and faults at the edges (issue 14): PETSc options, the file system, signals,
unstable states.  Every case ends in its documented exit code with one line on stderr naming the
key, option or path, never a Python traceback, never a hang (every process has a timeout), on
1 and 2 ranks.  Exit codes and statuses: docs/running.md."""
from __future__ import annotations

import copy
import ctypes
import errno
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from helpers import CONFIGS, MPI_ENV, ONE_AND_TWO_RANKS, ROOT, VENV_BIN, bar_twin_fit, load_raw, \
    petsc_init, read_summary, run_inline, solve_cli, write_config

TIMEOUT = 120
UNIAXIAL = load_raw("uniaxial_neohookean.yaml")


def tiny(**change) -> dict:
    """The uniaxial bar with two elements (so two ranks both own one) and two load levels."""
    raw = copy.deepcopy(UNIAXIAL)
    raw["beams"][0]["elements"] = 2
    raw["steps"] = [0.5, 1.0]
    raw["output"] = {"vtk": False}
    raw.update(change)
    return raw


def solver_lines(stderr: str) -> list[str]:
    """ancf-solve's own lines (mpirun adds its banner about non-zero exit codes)."""
    return [ln for ln in stderr.splitlines() if ln.startswith("ancf-solve:")]


def assert_one_line(p, code: int, *words: str) -> str:
    assert "Traceback" not in p.stderr and "PETSC ERROR" not in p.stderr, p.stderr
    lines = solver_lines(p.stderr)
    assert p.returncode == code, (p.returncode, p.stdout[-2000:], p.stderr)
    assert len(lines) == 1, p.stderr
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


def run_cfg(tmp_path, raw: dict, ranks: int = 1, extra=(), name="c", out="out"):
    raw = copy.deepcopy(raw)
    raw.setdefault("output", {})["dir"] = str(tmp_path / out)
    cfg = write_config(raw, tmp_path / f"{name}.yaml")
    return solve_cli(cfg, ranks=ranks, extra=list(extra) + ["--quiet"], timeout=TIMEOUT)


# ------------------------------------------------------------------------------ config inputs
CONFIG_CASES = {
    "mu with c10": (lambda r: r["beams"][0]["material"].update(c10=5e5),
                    "beams[0].material: give either mu and bulk_modulus or the paper's c10 and d"),
    "one axial point": (lambda r: r["beams"][0].update(axial_points=1),
                        "beams[0].axial_points: must be >= 2; got 1: one point along the beam"),
    "snes_rtol abc": (lambda r: r.update(petsc={"snes_rtol": "abc"}),
                      "petsc.snes_rtol: expected a number"),
    "integer with exponent": (lambda r: r.update(petsc={"snes_max_it": "1e2"}),
                              "petsc.snes_max_it: expected an integer"),
    "type in capitals": (lambda r: r.update(petsc={"pc_type": "LU"}),
                         "petsc.pc_type: unknown pc type 'LU' (type names are lower case: lu)"),
    "a SNES type needing code": (lambda r: r.update(petsc={"snes_type": "composite"}),
                                 "petsc.snes_type: snes type 'composite' needs setup code that ancf-solve"),
    "a line search needing code": (lambda r: r.update(petsc={"snes_linesearch_type": "shell"}),
                                   "petsc.snes_linesearch_type: snes_linesearch type 'shell' needs setup code"),
    "not a boolean": (lambda r: r.update(petsc={"ksp_initial_guess_nonzero": "maybe"}),
                      "petsc.ksp_initial_guess_nonzero: expected a boolean"),
    "negative tolerance": (lambda r: r.update(petsc={"ksp_rtol": -1}), "petsc.ksp_rtol: must be >= 0"),
    # an empty list (or '', 0) was taken for no options, without a word
    "petsc as a list": (lambda r: r.update(petsc=[]), "petsc: expected a mapping of PETSc options, e.g. "
                                                      "{snes_rtol: 1e-10}; got []"),
    "an option written with =": (lambda r: r.update(petsc={"snes_max_it=3": True}),
                                 "petsc.snes_max_it=3: an option's name has no '=': write snes_max_it: 3"),
    # PETSc's SNESSetTolerances refuses it: a level ran, then a traceback, exit 1
    "relative tolerance of 1": (lambda r: r.update(petsc={"snes_rtol": 1}),
                                "petsc.snes_rtol: a relative tolerance must be below 1 (PETSc refuses it); got 1"),
    "name with a path": (lambda r: r.update(name="../../evil"), "name: it names the output directory"),
    "allow_unstable not a boolean": (lambda r: r.update(solver={"allow_unstable": "yes"}),
                                     "solver.allow_unstable: expected true or false"),
}


@pytest.mark.parametrize("case", list(CONFIG_CASES))
def test_config_values_rejected_in_process(case):
    from ancf_petsc.config.values import ConfigError
    from ancf_petsc.config.parse import parse_config
    fn, message = CONFIG_CASES[case]
    raw = copy.deepcopy(UNIAXIAL)
    fn(raw)
    with pytest.raises(ConfigError) as err:
        parse_config(raw, base_dir=CONFIGS)
    assert str(err.value).startswith(message) and "\n" not in str(err.value), str(err.value)


@pytest.mark.mpi
@pytest.mark.parametrize("case,ranks", [("mu with c10", 1), ("name with a path", 2)])
def test_config_errors_on_the_command_line(tmp_path, case, ranks):
    fn, message = CONFIG_CASES[case]
    raw = tiny()
    fn(raw)
    raw["output"].pop("dir", None)
    if case == "name with a path":
        raw.pop("output")                      # the default results/<name> is what is at stake
        work = tmp_path / "a" / "b"
        work.mkdir(parents=True)
        cfg = write_config(raw, tmp_path / "evil.yaml")
        p = subprocess.run(["mpirun", "--oversubscribe", "-n", str(ranks),
                            os.path.join(VENV_BIN, "ancf-solve"), cfg, "--quiet"],
                           capture_output=True, text=True, cwd=work, timeout=TIMEOUT,
                           env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
        assert_one_line(p, 2, "config error: " + message)
        assert sorted(os.listdir(tmp_path)) == ["a", "evil.yaml"] and os.listdir(tmp_path / "a") == ["b"]
        assert os.listdir(work) == []          # nothing written anywhere
        return
    p = run_cfg(tmp_path, raw, ranks)
    assert_one_line(p, 2, "config error: " + message)


def test_one_axial_point_is_really_singular():
    """The rule config.py enforces: with one Gauss point along ξ the free-DOF tangent of the
    three-node element at the reference state is singular; with two it is not."""
    petsc_init()
    from petsc4py import PETSc

    from ancf_petsc.petsc.problem import Problem
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.parallel.layout import block_layout
    from ancf_petsc.model.build import build_model
    smallest = {}
    for n in (1, 2):
        spec = parse_config(tiny(), base_dir=CONFIGS)
        spec.beams[0].axial_points = n                  # past the config check, on purpose
        model = build_model(spec)
        P = Problem(model, block_layout(model.connectivity(), model.n_nodes, 1, 0), PETSc.COMM_WORLD)
        P.q0.copy(P.X)
        P.jacobian(None, P.X, P.J, P.J)
        K = P.J.convert("dense").getDenseArray()
        free = ~P.fixed_mask
        K = 0.5 * (K + K.T)[np.ix_(free, free)]
        diag = np.diag(K)
        d = 1.0 / np.sqrt(np.where(diag > 0, diag, 1.0))   # the nodal vectors' scales apart
        w = np.linalg.eigvalsh(K * d[:, None] * d[None, :])
        smallest[n] = w[0] / w[-1]
    assert abs(smallest[1]) < 1e-12 and smallest[2] > 1e-6, smallest


def test_a_factorisation_mumps_gives_up_on_ends_the_run_cleanly(tmp_path):
    """The singular one-point model (past the config check): PETSc's error inside the solve
    becomes a failed run with reason PETSC_ERROR and one line, not a traceback."""
    petsc_init()
    from petsc4py import PETSc

    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    raw = tiny()
    raw["output"]["dir"] = str(tmp_path / "out")
    spec = parse_config(raw, base_dir=CONFIGS)
    spec.beams[0].axial_points = 1
    spec.petsc["mat_mumps_icntl_24"] = "0"          # no null-pivot detection: MUMPS gives up
    res = run_model(spec, PETSc.COMM_WORLD, lambda *_: None)
    assert (res.status, res.reason_code, res.exit_code) == ("failed", "PETSC_ERROR", 3)
    assert "MUMPS could not factor the tangent: it is singular" in res.message and "\n" not in res.message
    s = _check_agreement(tmp_path / "out", 0)
    assert s["reason_code"] == "PETSC_ERROR"


def test_a_bug_still_leaves_a_final_status(tmp_path, monkeypatch):
    """An unexpected exception (a bug) propagates (exit 1 with its traceback in ancf-solve), but
    summary.json does not stay 'running'."""
    from ancf_petsc.petsc.problem import Problem
    real, calls = Problem.gather, []

    def broken_gather(self, X=None, blocks=False):
        calls.append(1)
        if len(calls) == 3:                 # while writing the second level (two gathers a level)
            raise RuntimeError("simulated bug")
        return real(self, X, blocks)
    monkeypatch.setattr(Problem, "gather", broken_gather)
    raw = tiny()
    with pytest.raises(RuntimeError, match="simulated bug"):
        run_inline(raw, tmp_path / "out")
    s = _check_agreement(tmp_path / "out", 1)
    assert (s["status"], s["reason_code"]) == ("failed", "INTERNAL_ERROR")
    assert s["message"] == "RuntimeError: simulated bug"


INLINE_BUG = """
import sys
sys.path.insert(0, {tests!r})
from helpers import load_raw, petsc_init
petsc_init()
from ancf_petsc.api import solve
from ancf_petsc.config.parse import parse_config
from ancf_petsc.petsc.problem import Problem
real, calls = Problem.residual, []

def broken(self, *args):
    calls.append(1)
    if len(calls) == 12:                # within the first level's Newton solve
        raise RuntimeError("simulated bug in a callback")
    return real(self, *args)
Problem.residual = broken
raw = load_raw("achilles_type3_psi45.yaml")
raw["steps"] = [30.0]
raw["output"] = {{"dir": sys.argv[1], "vtk": False}}
solve(parse_config(raw, base_dir={configs!r}), log=lambda *_: None)
"""


def test_an_inline_run_that_raises_exits_with_its_traceback_not_a_segv(tmp_path):
    """A bug raised inside a PETSc callback of an inline (API) run propagates uncaught: the
    traceback's frames keep the SNES that PETSc passed the callback alive to the interpreter's
    exit, and PETSc's final clean-up reset its Python preconditioner (the compact factor) after
    Python had finalised: a SEGV and MPI_ABORT (exit 59) after the traceback.  The run's destroy
    now lets go of the preconditioner's context first (solving/snes_solver.py)."""
    script = tmp_path / "bug.py"
    script.write_text(INLINE_BUG.format(tests=os.path.join(ROOT, "tests"), configs=CONFIGS))
    p = subprocess.run([sys.executable, str(script), str(tmp_path / "out")], capture_output=True,
                       text=True, cwd=ROOT, timeout=TIMEOUT, env=dict(os.environ, PYTHONPATH=ROOT))
    assert p.returncode == 1, p.stdout + p.stderr
    assert p.stderr.rstrip().endswith("RuntimeError: simulated bug in a callback"), p.stderr
    assert "SEGV" not in p.stderr and "MPI_ABORT" not in p.stderr


ROOT_ONLY_FAILURE = """
import sys
sys.path.insert(0, {tests!r})
from helpers import load_raw, petsc_init
petsc_init()
from petsc4py import PETSc
from ancf_petsc.api import solve
from ancf_petsc.config.parse import parse_config
from ancf_petsc.io.results import ResultsWriter
real = ResultsWriter._write_step

def clash(self, record, *args):
    if len(self.summary["steps"]) == 1:    # rank 0 writes, and h5py complains (ValueError)
        raise ValueError("Unable to move link (an object with that name already exists)")
    return real(self, record, *args)
ResultsWriter._write_step = clash
raw = load_raw("bundle_hex7.yaml")
raw["output"] = {{"dir": sys.argv[1], "vtk": False}}
res = solve(parse_config(raw, base_dir={configs!r}), PETSc.COMM_WORLD, log=lambda *_: None)
with open(sys.argv[1] + f".rank{{PETSc.COMM_WORLD.rank}}", "w") as fh:
    fh.write(f"{{res.status}} {{res.reason_code}} {{res.message}}")
"""


@pytest.mark.mpi
def test_an_exception_in_rank_0s_file_writing_fails_every_rank(tmp_path):
    """Only rank 0 writes the files.  An exception there that is not the OS's (h5py raises
    ValueError when another process changed the file) must end the run on every rank as an
    output error, with the converged levels kept, not leave rank 1 waiting (it hung before)."""
    script = tmp_path / "clash.py"
    script.write_text(ROOT_ONLY_FAILURE.format(tests=os.path.dirname(os.path.dirname(__file__)),
                                               configs=CONFIGS))
    p = subprocess.run(["mpirun", "--oversubscribe", "-n", "2", sys.executable, str(script),
                        str(tmp_path / "out")], capture_output=True, text=True, cwd=ROOT,
                       timeout=TIMEOUT, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode == 0, p.stdout + p.stderr
    for rank in (0, 1):
        line = (tmp_path / f"out.rank{rank}").read_text()
        assert line.startswith("failed OUTPUT_ERROR ") and "ValueError: Unable to move link" in line
    s = read_summary(tmp_path / "out")
    assert (s["status"], s["reason_code"], len(s["steps"])) == ("failed", "OUTPUT_ERROR", 1)


RANK_1_BUG = """
import sys
sys.path.insert(0, {tests!r})
from helpers import load_raw, petsc_init
petsc_init()
from petsc4py import PETSc
from ancf_petsc.api import solve
from ancf_petsc.config.parse import parse_config
from ancf_petsc.solving import stepper
real, calls = stepper.LoadStepper._stop_if_requested, []

def bug(self, target, level):
    calls.append(1)
    if PETSc.COMM_WORLD.rank == 1 and len(calls) == 2:       # rank 0 goes on into a collective
        raise RuntimeError("simulated bug on one rank")
    return real(self, target, level)
stepper.LoadStepper._stop_if_requested = bug
raw = load_raw("bundle_hex7.yaml")
raw["output"] = {{"dir": sys.argv[1], "vtk": False}}
try:
    solve(parse_config(raw, base_dir={configs!r}), PETSc.COMM_WORLD, log=lambda *_: None)
except Exception:
    import traceback
    traceback.print_exc()
    sys.stderr.flush()
    PETSc.COMM_WORLD.tompi4py().Abort(1)                  # as ancf-solve does
"""


@pytest.mark.mpi
def test_a_bug_on_rank_1_alone_still_leaves_a_final_status(tmp_path):
    """A bug raised on rank 1 only, while rank 0 waits in a collective call: the abort kills rank
    0 before it can write, so rank 1 marks rank 0's summary.json itself (it stayed 'running')."""
    script = tmp_path / "bug.py"
    script.write_text(RANK_1_BUG.format(tests=os.path.dirname(os.path.dirname(__file__)), configs=CONFIGS))
    p = subprocess.run(["mpirun", "--oversubscribe", "-n", "2", sys.executable, str(script),
                        str(tmp_path / "out")], capture_output=True, text=True, cwd=ROOT,
                       timeout=TIMEOUT, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode != 0 and "simulated bug on one rank" in p.stderr, p.stdout + p.stderr
    s = read_summary(tmp_path / "out")
    assert (s["status"], s["reason_code"]) == ("failed", "INTERNAL_ERROR"), s["status"]
    assert s["message"] == "rank 1: RuntimeError: simulated bug on one rank"
    assert len(s["steps"]) >= 1                          # the converged levels are kept


@pytest.mark.mpi
def test_config_file_is_binary_or_a_directory(tmp_path):
    binary = tmp_path / "model.yaml"
    binary.write_bytes(b"name: x\n" + bytes(range(128, 256)))
    p = solve_cli(str(binary), timeout=TIMEOUT)
    assert_one_line(p, 2, str(binary), "not a text (UTF-8) YAML file")
    p = solve_cli(str(tmp_path), ranks=2, timeout=TIMEOUT)
    assert_one_line(p, 2, str(tmp_path), "is a directory, not a config file")


# ------------------------------------------------------------------------------ command line
def test_command_line_edges(tmp_path):
    cfg = write_config(tiny(), tmp_path / "c.yaml")
    p = solve_cli(cfg, extra=["--outputdir", str(tmp_path / "o")], timeout=TIMEOUT)
    assert_one_line(p, 2, "unknown option --outputdir; did you mean --output-dir?")
    assert not (tmp_path / "o").exists()
    p = solve_cli(cfg, extra=["-snes_max_it", "10.0"], timeout=TIMEOUT)
    assert_one_line(p, 2, "-snes_max_it 10.0: expected an integer")
    p = solve_cli(cfg, extra=["-snes_rtol", "1"], timeout=TIMEOUT)     # was a traceback after a level
    assert_one_line(p, 2, "-snes_rtol 1: a relative tolerance must be below 1")
    p = solve_cli(cfg, extra=["-snes_max_it=3"], timeout=TIMEOUT)     # was run at 15, 'never used' after
    assert_one_line(p, 2, "-snes_max_it=3: PETSc takes an option's value after a space, not '=': write -snes_max_it 3")
    p = solve_cli(cfg, extra=["--version"], timeout=TIMEOUT)
    from ancf_petsc import __version__
    assert p.returncode == 0 and p.stdout.startswith(f"ancf-solve {__version__}")
    if os.path.exists(os.path.join(ROOT, ".git")):
        assert "(git " in p.stdout
    p = solve_cli("-help", timeout=TIMEOUT)             # our usage (no model to show PETSc's)
    assert p.returncode == 0 and "usage: ancf-solve" in p.stdout and "ancf-solve CONFIG.yaml -help" in p.stdout


@pytest.mark.parametrize("flag", ["-help", "--help", "--version"])
def test_usage_and_version_into_a_closed_pipe(flag):
    """`ancf-solve -help | head`: a reader gone before the text is written is no traceback."""
    r, w = os.pipe()
    os.close(r)                                       # like `| head -0`
    p = subprocess.run([os.path.join(VENV_BIN, "ancf-solve"), flag], stdout=w, stderr=subprocess.PIPE,
                       text=True, timeout=TIMEOUT, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    os.close(w)
    assert (p.returncode, p.stderr) == (0, "")


def test_help_goes_to_petsc_and_version_is_recorded(tmp_path):
    raw = tiny()
    raw["steps"] = [1.0]
    p = run_cfg(tmp_path, raw, extra=["-help"])
    assert p.returncode == 0, p.stderr
    # PETSc's own help: its banner and the SNES options it read while setting up
    assert "Options for all PETSc programs" in p.stdout and "-snes_rtol" in p.stdout
    s = read_summary(tmp_path / "out")
    from ancf_petsc.version import version_info
    here = version_info()                # the tree may turn -dirty while tests run: compare the commit
    assert s["version"]["version"] == here["version"] and s["status"] == "completed"
    assert (s["version"]["git"] or "").split("-")[0] == (here["git"] or "").split("-")[0]
    with h5py.File(tmp_path / "out" / "results.h5") as h5:
        assert h5.attrs["ancf_version"] == s["version"]["version"]
        assert h5.attrs["ancf_git"] == (s["version"]["git"] or "")
        assert h5.attrs["status"] == "completed"


@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_unused_options_are_reported(tmp_path, ranks):
    raw = tiny(petsc={"snes_linesearch_typo": "bt", "ksp_converged_reason": None})
    p = run_cfg(tmp_path, raw, ranks, extra=["-snes_lnesearch_type", "bt", "-snes_rtol", "1e-9",
                                             "-mat_type", "aij"])
    assert p.returncode == 0, p.stderr
    lines = solver_lines(p.stderr)
    assert sorted(lines) == sorted([
        "ancf-solve: warning: PETSc option -mat_type was never used: the Jacobian's format is "
        "solver.matrix in the config (auto, aij, sbaij)",
        "ancf-solve: warning: PETSc option -snes_linesearch_typo (config) was never used: misspelt, "
        "or not read by the solver in use",
        "ancf-solve: warning: PETSc option -snes_lnesearch_type was never used: misspelt, or not "
        "read by the solver in use"]), p.stderr
    # a config option read at every solve works for the whole run (and so is used)
    assert "Linear solve converged" in p.stdout
    assert read_summary(tmp_path / "out")["unused_petsc_options"] == \
        ["petsc.snes_linesearch_typo", "-mat_type", "-snes_lnesearch_type"]
    p = run_cfg(tmp_path, raw, ranks, extra=["-options_left", "0"])
    assert p.returncode == 0 and not solver_lines(p.stderr), p.stderr


def test_ancf_study_reports_a_misspelt_option_once(tmp_path):
    """``ancf-study S.yaml -snes_maxit 3`` said nothing: copying the solver options under each
    solve's prefix read the originals (PETSc counts a read as a use), and the study printed no
    report; each run's summary listed -snes_maxit, -study1_snes_maxit and the used
    -snes_linesearch_type.  Now one line, as ancf-solve's, and only -snes_maxit in the summaries."""
    study = {"kind": "pareto", "name": "tiny", "base": os.path.join(CONFIGS, "bending_neohookean.yaml"),
             "probe": "tip", "component": "z",
             "grid": {"element": ["3363"], "axial_points": [2], "cubature_degree": [2], "elements": [1, 2]},
             "reference": {"element": "3363", "axial_points": 2, "cubature_degree": 2, "elements": 4},
             "output": str(tmp_path / "st")}
    f = write_config(study, tmp_path / "st.yaml")
    run = [os.path.join(VENV_BIN, "ancf-study"), f, "-snes_maxit", "3", "-snes_linesearch_type", "bt"]
    p = subprocess.run(run, capture_output=True, text=True, timeout=TIMEOUT, cwd=tmp_path,
                       env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode == 0, p.stderr
    assert [ln for ln in p.stderr.splitlines() if ln.startswith("ancf-")] == [
        "ancf-study: warning: PETSc option -snes_maxit was never used: misspelt, or not read by "
        "the solver in use"], p.stderr
    for run_dir in ("run_000", "run_001", "reference_4"):
        assert read_summary(tmp_path / "st" / run_dir)["unused_petsc_options"] == ["-snes_maxit"]
    p = subprocess.run(run + ["-options_left", "0"], capture_output=True, text=True, timeout=TIMEOUT,
                       cwd=tmp_path, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode == 0 and "ancf-study:" not in p.stderr, p.stderr


def test_ancf_fit_reports_a_misspelt_option_once(tmp_path):
    """``ancf-fit F.yaml -snes_maxit 3`` said nothing (as ancf-study); now one line when samples
    were solved, none when every sample came from the log (no solve could read an option)."""
    fit = bar_twin_fit(tmp_path / "fit")
    run = [os.path.join(VENV_BIN, "ancf-fit"), write_config(fit, tmp_path / "fit.yaml"), "--quiet",
           "-snes_maxit", "3", "-snes_linesearch_type", "bt"]
    lines = []
    for _ in range(2):                   # solved, then resumed from the log
        p = subprocess.run(run, capture_output=True, text=True, timeout=TIMEOUT, cwd=tmp_path,
                           env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
        assert p.returncode == 0, p.stderr
        lines.append([ln for ln in p.stderr.splitlines() if ln.startswith("ancf-")])
    assert lines == [["ancf-fit: warning: PETSc option -snes_maxit was never used: misspelt, or not "
                      "read by the solver in use"], []], lines


# ------------------------------------------------------------------------------ PETSc solvers
def _tip(tmp_path, out):
    return np.array(read_summary(tmp_path / out)["steps"][-1]["probes"]["tip"]["displacement"])


RUNS = {   # options that must run and give the default solver's answer
    1: ["-ksp_type gmres -pc_type ilu", "-ksp_type cg -pc_type icc", "-ksp_type gmres -pc_type gamg",
        "-ksp_type gmres -pc_type bjacobi", "-pc_type lu -pc_factor_mat_solver_type petsc",
        "-pc_type cholesky -pc_factor_mat_solver_type petsc", "-ksp_type minres -pc_type jacobi",
        "-ksp_type gmres -pc_type hypre"],
    2: ["-ksp_type gmres -pc_type bjacobi", "-ksp_type gmres -pc_type asm", "-pc_type lu",
        "-pc_type lu -pc_factor_mat_solver_type superlu_dist", "-ksp_type gmres -pc_type hypre"],
}
#: GMRES + GAMG on the two-element bar runs with 3 axial Gauss points but breaks down
#: (DIVERGED_BREAKDOWN at the first step) with the 2-point default: it may end in the failure line
MAY_DIVERGE = {"-ksp_type gmres -pc_type gamg"}
REFUSED = {   # options PETSc cannot run here: exit 2, one line with the options and what works
    1: [("-pc_type ilu -pc_factor_mat_solver_type mumps", "mumps does not support factorization type ILU")],
    2: [("-ksp_type gmres -pc_type ilu", "on 2 ranks use -pc_type bjacobi or asm"),
        ("-pc_type lu -pc_factor_mat_solver_type petsc", "-pc_factor_mat_solver_type petsc is sequential"),
        ("-pc_type cholesky -pc_factor_mat_solver_type petsc", "is sequential: on 2 ranks use")],
}

# one process (one mpirun) tries every option set in turn, as the command line would give them
DRIVER = """
import json, sys
from mpi4py import MPI
import petsc4py
petsc4py.init([])
from petsc4py import PETSc
from ancf_petsc.config.parse import ConfigError, load_config
from ancf_petsc.linalg.option_syntax import command_line_options
from ancf_petsc.solving.run import run_model
cfg, out, sets = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
results = []
for k, opts in enumerate(sets):
    pairs = command_line_options(opts.split())
    for name, value in pairs:
        PETSc.Options().setValue(name, value or "")
    spec = load_config(cfg)
    spec.output.dir = f"{out}/{k}"
    try:
        res = run_model(spec, PETSc.COMM_WORLD, lambda *_: None)
        steps = res.summary["steps"] if res.summary else []
        tip = steps[-1]["probes"]["tip"]["displacement"] if steps else None
        results.append({"status": res.status, "tip": tip, "message": res.message})
    except ConfigError as exc:
        results.append({"status": "refused", "message": str(exc)})
    for name, _ in pairs:
        PETSc.Options().delValue(name)
if MPI.COMM_WORLD.rank == 0:
    print("RESULTS " + json.dumps(results))
"""


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_standard_solver_options_run_or_say_what_works(tmp_path, ranks):
    petsc_init()
    from petsc4py import PETSc
    has_hypre = PETSc.Sys.hasExternalPackage("hypre")
    runs = [o for o in RUNS[ranks] if has_hypre or "hypre" not in o]
    refused = [o for o, _ in REFUSED[ranks]] + ([] if has_hypre else ["-ksp_type gmres -pc_type hypre"])
    raw = tiny()
    raw["output"]["dir"] = str(tmp_path / "unused")
    cfg = write_config(raw, tmp_path / "c.yaml")
    (tmp_path / "driver.py").write_text(DRIVER)
    cmd = [sys.executable, str(tmp_path / "driver.py"), cfg, str(tmp_path / "o"),
           json.dumps([""] + runs + refused)]
    if ranks > 1:
        cmd = ["mpirun", "--oversubscribe", "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT,
                       env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    results = json.loads(next(ln for ln in p.stdout.splitlines() if ln.startswith("RESULTS "))[8:])
    ref = np.array(results[0]["tip"])
    for opts, res in zip(runs, results[1:1 + len(runs)]):
        if opts in MAY_DIVERGE and res["status"] == "failed":
            # a Krylov method that breaks down ends in one line naming it and what works
            assert "DIVERGED_LINEAR_SOLVE (the linear solver " + opts in res["message"], res
            assert "use the default direct solver" in res["message"] and "\n" not in res["message"]
            continue
        assert res["status"] == "completed", (opts, res)
        assert np.abs(np.array(res["tip"]) - ref).max() <= 1e-7 * np.abs(ref).max(), opts
    whys = dict(REFUSED[ranks], **{"-ksp_type gmres -pc_type hypre": "no hypre"})
    for opts, res in zip(refused, results[1 + len(runs):]):
        assert res["status"] == "refused", (opts, res)
        msg = res["message"]
        assert msg.startswith("PETSc refused the solver options -ksp_type ") and \
            f"on {ranks} rank(s): " in msg, msg
        assert all(f"-{pair}" in msg for pair in opts.lstrip("-").split(" -")), msg
        assert whys[opts] in msg and "\n" not in msg, msg
    # and on the command line: exit 2, one line, nothing written
    opts, why = REFUSED[ranks][0]
    p = run_cfg(tmp_path, tiny(), ranks, extra=opts.split(), out="refused")
    assert_one_line(p, 2, "ancf-solve: PETSc refused the solver options", f"on {ranks} rank(s)", why,
                    *(f"-{pair}" for pair in opts.lstrip("-").split(" -")))
    assert not (tmp_path / "refused" / "results.h5").exists()     # refused before any level


def test_a_diverging_linear_solver_says_what_works(tmp_path):
    p = run_cfg(tmp_path, tiny(), 1, extra=["-ksp_type", "gmres", "-pc_type", "jacobi",
                                            "-ksp_max_it", "3"])
    line = assert_one_line(p, 3, "DIVERGED_LINEAR_SOLVE", "-ksp_type gmres -pc_type jacobi stopped with "
                                                          "DIVERGED_MAX_IT", "use the default direct solver")
    s = read_summary(tmp_path / "out")
    assert s["status"] == "failed" and s["reason_code"] == "DIVERGED_LINEAR_SOLVE" and line
    # failed linear solves let through (-snes_max_linear_solve_fail 5): it said only 'with
    # STALLED_ABOVE_TOLERANCE', failure_cause stalled_above_tolerance
    elastica = dict(load_raw("elastica_svk.yaml"), steps=[0.2], output={"vtk": False})
    p = run_cfg(tmp_path, elastica, 1, extra=["-ksp_type", "gmres", "-pc_type", "jacobi", "-ksp_max_it", "3",
                                              "-snes_max_linear_solve_fail", "5"], out="through")
    assert_one_line(p, 3, "-ksp_type gmres -pc_type jacobi stopped with DIVERGED_MAX_IT", "use the default direct")
    assert read_summary(tmp_path / "through")["failure_cause"] == "linear_solver"


def test_option_tables_match_petsc():
    """The type names and value parsing config.py checks against are PETSc's own."""
    petsc_init()
    from petsc4py import PETSc

    from ancf_petsc.linalg import option_syntax as po
    from ancf_petsc.linalg.diagnostics import petsc_library
    names = lambda cls: sorted({getattr(cls, k) for k in dir(cls) if not k.startswith("_")
                                and isinstance(getattr(cls, k), str)})
    assert sorted(po.KSP_TYPES) == names(PETSc.KSP.Type)
    assert sorted(po.PC_TYPES) == names(PETSc.PC.Type)
    assert sorted(po.SNES_TYPES) == names(PETSc.SNES.Type)
    assert sorted(po.SOLVER_TYPES) == names(PETSc.Mat.SolverType)
    assert set(names(PETSc.Mat.OrderingType)) <= set(po.ORDERING_TYPES)
    lib = petsc_library()

    def enum(symbol, pointer):
        arr = ctypes.POINTER(ctypes.c_char_p).in_dll(lib, symbol) if pointer else \
            (ctypes.c_char_p * 16).in_dll(lib, symbol)
        out = []
        while arr[len(out)] is not None:
            out.append(arr[len(out)].decode())
        return [x.lower() for x in out[:-2]]             # the last two: type name and prefix

    assert enum("MatFactorShiftTypes", False) == list(po.ENUMS["pc_factor_shift_type"])
    assert enum("KSPNormTypes", True) == list(po.ENUMS["ksp_norm_type"])
    assert sorted(enum("PCASMTypes", False)) == sorted(po.ENUMS["pc_asm_type"])
    assert enum("PCSides", True) == list(po.ENUMS["pc_side"])
    PETSc.Sys.pushErrorHandler("ignore")
    try:
        real, integer, flag = ctypes.c_double(), ctypes.c_int32() if np.dtype(PETSc.IntType).itemsize == 4 \
            else ctypes.c_int64(), ctypes.c_int()
        for text in ("1e-3", "abc", " 1", "1 ", "0x1p3", "-0X.8P1", "inf", "-Infinity", "nan", "NAN(12)",
                     "DEFAULT", "decide", "1e", ".5", "5.", "+-1", "1_000", "1e+", "2E-2", "", "e5"):
            ok = lib.PetscOptionsStringToReal(text.encode(), ctypes.byref(real)) == 0 if text else False
            mine = po.parse_real(text)
            assert (mine is not None) == ok, text
            if ok and text.lower() not in ("default", "decide") and np.isfinite(real.value):
                assert mine == real.value, text
        for text in ("10", "1e2", "10.0", " 5", "-3", "decide", "mouse", "0x10", "+7", "7 ", "--7"):
            ok = lib.PetscOptionsStringToInt(text.encode(), ctypes.byref(integer)) == 0
            assert (po.parse_int(text) is not None) == ok, text
            if ok:
                assert po.parse_int(text) == integer.value, text
        for text in ("", "yes", "On", "maybe", "0", "FALSE", "tru", "no", "OFF", "1"):
            ok = lib.PetscOptionsStringToBool(text.encode(), ctypes.byref(flag)) == 0
            assert (po.parse_bool(text) is not None) == ok, text
            if ok:
                assert po.parse_bool(text) == bool(flag.value), text
    finally:
        PETSc.Sys.popErrorHandler()


# ------------------------------------------------------------------------------ file system
def _readonly_dir(tmp_path):
    """A directory this process cannot write in (as root: a read-only bind mount), or None."""
    d = tmp_path / "ro"
    d.mkdir()
    if os.geteuid() != 0:
        d.chmod(0o555)
        return str(d), None
    return None, str(d)


def _in_namespace(script: str, timeout=TIMEOUT) -> subprocess.CompletedProcess | None:
    """Run ``script`` (sh) in a private mount namespace (unshare -rm), or None if not possible."""
    if shutil.which("unshare") is None:
        return None
    probe = subprocess.run(["unshare", "-rm", "true"], capture_output=True)
    if probe.returncode != 0:
        return None
    return subprocess.run(["unshare", "-rm", "sh", "-c", script], capture_output=True, text=True,
                          timeout=timeout, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))


OUTPUT_CASES = {
    "in /proc": (lambda t: "/proc/nope", "/proc/nope: cannot create the output directory"),
    "a file": (lambda t: str(t / "f"), "exists and is not a directory"),
    "under a file": (lambda t: str(t / "f" / "sub"), "cannot create the output directory: a file is in the way"),
}


@pytest.mark.mpi
@pytest.mark.parametrize("case,ranks", [("in /proc", 1), ("a file", 2), ("under a file", 1)])
def test_output_dir_problems(tmp_path, case, ranks):
    (tmp_path / "f").write_text("a file")
    where, message = OUTPUT_CASES[case]
    cfg = write_config(tiny(), tmp_path / "c.yaml")
    p = solve_cli(cfg, ranks=ranks, extra=["--output-dir", where(tmp_path), "--quiet"], timeout=TIMEOUT)
    assert_one_line(p, 2, "output error: ", message)


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_unwritable_output_dir(tmp_path, ranks):
    cfg = write_config(tiny(), tmp_path / "c.yaml")
    plain_dir, mount_point = _readonly_dir(tmp_path)
    exe = os.path.join(VENV_BIN, "ancf-solve")
    if plain_dir:
        p = solve_cli(cfg, ranks=ranks, extra=["--output-dir", plain_dir, "--quiet"], timeout=TIMEOUT)
    else:
        launch = f"mpirun --oversubscribe -n {ranks} {exe}"
        p = _in_namespace(f"mount -t tmpfs -o ro tmpfs {mount_point} && "
                          f"{launch} {cfg} --output-dir {mount_point}/out --quiet")
        if p is None:
            pytest.skip("root without user namespaces: no read-only directory to test with")
    assert_one_line(p, 2, "output error: ", "Read-only file system" if mount_point else "Permission denied")


def _check_agreement(out_dir, n_levels=None):
    """summary.json and results.h5 list the same converged levels; the summary is final."""
    s = read_summary(out_dir)
    with h5py.File(os.path.join(out_dir, "results.h5")) as h5:
        names = sorted(h5["steps"])
        h5_levels = [float(h5["steps"][n].attrs["load_factor"]) for n in names]
        assert all(n.startswith("step_") and not n.endswith(".partial") for n in names), names
        assert h5["steps"].attrs["converged"] == len(names)
    assert [st["load_factor"] for st in s["steps"]] == h5_levels
    assert s["status"] in ("completed", "failed", "interrupted", "unstable")
    if h5_levels:
        assert s["last_converged"] == {"step": len(h5_levels), "load_factor": h5_levels[-1]}
    if n_levels is not None:
        assert len(h5_levels) == n_levels
    assert not [f for f in os.listdir(out_dir) if f.endswith(".tmp") or f.startswith(".ancf")]
    return s


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_full_disk_on_a_small_tmpfs(tmp_path, ranks):
    """A 300 KB file system: the run stops before the level that would not fit, exit 2, one line
    naming the directory, and both result files agree on what converged."""
    mnt = tmp_path / "mnt"
    mnt.mkdir()
    raw = copy.deepcopy(UNIAXIAL)
    raw["output"] = {"dir": str(mnt / "out")}
    cfg = write_config(raw, tmp_path / "c.yaml")
    exe = os.path.join(VENV_BIN, "ancf-solve")
    keep = tmp_path / "kept"
    p = _in_namespace(f"mount -t tmpfs -o size=300k tmpfs {mnt} && "
                      f"mpirun --oversubscribe -n {ranks} {exe} {cfg} --quiet; rc=$?; "
                      f"cp -r {mnt}/out {keep}; exit $rc")
    if p is None:
        pytest.skip("no private mount namespace (unshare -rm) here; test_disk_full_* cover ENOSPC")
    line = assert_one_line(p, 2, "output error: ", f"{mnt}/out", "no space left on device for level")
    s = _check_agreement(keep)
    assert s["status"] == "failed" and s["reason_code"] == "OUTPUT_ERROR" and line in \
        "ancf-solve: " + s["message"] + f"; converged steps are in {mnt}/out"
    assert 0 < len(s["steps"]) < 10


class _Fault:
    """Makes one writer fail with ENOSPC at load level ``level`` (in-process, 1 rank)."""

    def __init__(self, monkeypatch, target: str, level: int):
        import ancf_petsc.io.results as out
        import ancf_petsc.io.vtk as vtk
        self.calls = 0
        if target == "vtu":
            real = vtk.write_vtu

            def write(path, *a, **k):
                if path.endswith(f"surface_{level:04d}.vtu"):
                    with open(path, "wb") as fh:
                        fh.write(b"<VTKFile trunc")          # a truncated file, then the error
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path)
                return real(path, *a, **k)
            monkeypatch.setattr(vtk, "write_vtu", write)
        elif target == "h5":
            real_file = h5py.File

            def file(path, mode="r", *a, **k):
                if mode == "a" and str(path).endswith("results.h5"):
                    self.calls += 1
                    if self.calls == level:
                        raise OSError(errno.ENOSPC, "Unable to open file (No space left on device)")
                return real_file(path, mode, *a, **k)
            monkeypatch.setattr(h5py, "File", file)
        elif target == "summary":
            real_atomic = out.atomic_write

            def atomic(path, text):
                doc = json.loads(text) if path.endswith("summary.json") else {}
                if doc.get("status") == "running" and len(doc["steps"]) >= level:
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path + ".tmp")
                return real_atomic(path, text)
            monkeypatch.setattr(out, "atomic_write", atomic)
            monkeypatch.setattr(out, "SUMMARY_SHARE", math.inf)   # rewritten at every level, as it may be
        monkeypatch.setattr(out.ResultsWriter, "_check_space", lambda self, k, q: None)


@pytest.mark.parametrize("target,level,kept", [("vtu", 2, 1), ("h5", 3, 2), ("summary", 2, 2)])
def test_disk_full_while_writing(tmp_path, monkeypatch, target, level, kept):
    """ENOSPC from each writer: the run ends 'failed' with OUTPUT_ERROR naming the file, no
    truncated VTU is left, and results.h5 and summary.json agree on the converged levels."""
    _Fault(monkeypatch, target, level)
    raw = copy.deepcopy(UNIAXIAL)
    raw["steps"] = [0.25, 0.5, 0.75, 1.0]
    s = run_inline(raw, tmp_path / "out")
    assert s["status"] == "failed" and s["reason_code"] == "OUTPUT_ERROR"
    name = {"vtu": f"surface_{level:04d}.vtu", "h5": "results.h5", "summary": "summary.json"}[target]
    assert name in s["message"] and "No space left on device" in s["message"]
    s = _check_agreement(tmp_path / "out", kept)
    vtus = {"vtu": [0, 1], "h5": [0, 1, 2], "summary": [0, 1, 2]}[target]   # none truncated
    assert sorted(f for f in os.listdir(tmp_path / "out") if f.endswith(".vtu")) == \
        [f"surface_{k:04d}.vtu" for k in vtus]


# ------------------------------------------------------------------------------ status, signals
def buckled_bar(allow=None) -> dict:
    """A bar compressed ~100x past its Euler load: straight, but a saddle (negative eigenvalues)."""
    raw = tiny()
    raw["beams"][0]["elements"] = 4
    raw["loads"][0]["traction_force"] = [-20.0, 0.0, 0.0]
    raw["steps"] = [0.01, 1.0]
    if allow is not None:
        raw["solver"] = {"allow_unstable": allow}
    return raw


@pytest.mark.slow
@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_unstable_levels_end_in_status_unstable(tmp_path, ranks):
    p = run_cfg(tmp_path, buckled_bar(), ranks)        # --quiet: the warning is printed anyway
    line = assert_one_line(p, 4, "ancf-solve: unstable: 1 of 2 levels are unstable equilibria",
                           "load factor 1)", "solver.allow_unstable: true")
    s = _check_agreement(tmp_path / "out", 2)
    assert s["status"] == "unstable" and s["reason_code"] == "NEGATIVE_EIGENVALUES"
    assert s["unstable_levels"] == [1.0] and s["stability_checked"] and line
    assert [st["negative_eigenvalues"] > 0 for st in s["steps"]] == [False, True]
    p = run_cfg(tmp_path, buckled_bar(allow=True), ranks, out="allowed")
    assert p.returncode == 0 and not solver_lines(p.stderr), p.stderr
    s = read_summary(tmp_path / "allowed")
    assert s["status"] == "completed" and s["unstable_levels"] == [1.0] and s["allow_unstable"]


def slow_model() -> dict:
    """Forty small levels of the bending cantilever: a few seconds, interrupted midway."""
    raw = load_raw("bending_neohookean.yaml")
    raw["steps"] = [round(0.05 * k, 2) for k in range(1, 41)]
    raw["solver"] = {"max_increment": 0.002}
    raw["output"] = {"vtk": False}
    return raw


def _interrupt(tmp_path, ranks: int, sig: int, to_ranks: bool):
    """Start a slow run, send ``sig`` after its first converged level (to mpirun or to one rank)."""
    raw = slow_model()
    out = tmp_path / f"out{ranks}{sig}"
    raw["output"]["dir"] = str(out)
    cfg = write_config(raw, tmp_path / "slow.yaml")
    cmd = [os.path.join(VENV_BIN, "ancf-solve"), cfg, "--quiet"]
    if ranks > 1:
        cmd = ["mpirun", "--oversubscribe", "-n", str(ranks)] + cmd
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    t0 = time.monotonic()
    try:
        while time.monotonic() - t0 < TIMEOUT:
            try:
                if len(read_summary(out)["steps"]) >= 1:
                    break
            except (OSError, ValueError, KeyError):
                pass
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.05)
        if to_ranks and ranks > 1:
            kids = subprocess.run(["ps", "-o", "pid=", "--ppid", str(proc.pid)], capture_output=True,
                                  text=True).stdout.split()
            os.kill(int(kids[-1]), sig)                 # one rank only, as srun/slurmstepd would
        else:
            proc.send_signal(sig)
        stdout, stderr = proc.communicate(timeout=TIMEOUT)
    finally:
        if proc.poll() is None:
            proc.kill()
    return subprocess.CompletedProcess(cmd, proc.returncode, stdout, stderr), out, raw["steps"]


@pytest.mark.slow
@pytest.mark.parametrize("ranks,sig,to_ranks", [
    (1, signal.SIGTERM, False), (1, signal.SIGINT, False),
    pytest.param(2, signal.SIGTERM, True, marks=pytest.mark.mpi),
    pytest.param(2, signal.SIGINT, False, marks=pytest.mark.mpi)])
def test_signals_stop_cleanly(tmp_path, ranks, sig, to_ranks):
    p, out, levels = _interrupt(tmp_path, ranks, sig, to_ranks)
    # mpirun forwards a signal it receives as SIGTERM and then exits 1 itself (Open MPI)
    code = 1 if ranks > 1 and not to_ranks else 128 + sig
    name = "SIGTERM" if ranks > 1 and not to_ranks else signal.Signals(sig).name
    line = assert_one_line(p, code, f"interrupted by {name}", "converged level(s) kept in")
    assert "KeyboardInterrupt" not in p.stderr
    s = _check_agreement(out)
    assert s["status"] == "interrupted" and s["reason_code"] == name and line
    k = len(s["steps"])
    assert 1 <= k < len(levels) and [st["load_factor"] for st in s["steps"]] == levels[:k]


@pytest.mark.parametrize("ranks", [1, pytest.param(2, marks=pytest.mark.mpi)])
def test_a_signal_inside_a_long_newton_solve_stops_it_cleanly(tmp_path, ranks):
    """SIGTERM while one Newton solve runs for long (here one that never converges: tolerances
    0): the run stops within an iteration, interrupted with SIGTERM.  The stepper asked only
    between solves, and Open MPI's mpirun sends SIGKILL 1 s after the SIGTERM it forwards: a
    friction column whose solves take seconds was killed, its summary.json left 'running'."""
    raw = tiny()
    raw["output"]["dir"] = str(tmp_path / "out")
    raw["petsc"] = {"snes_atol": 0.0, "snes_rtol": 0.0, "snes_stol": 0.0, "snes_max_it": 10000000}
    cmd = [os.path.join(VENV_BIN, "ancf-solve"), write_config(raw, tmp_path / "c.yaml"), "--quiet"]
    if ranks > 1:
        cmd = ["mpirun", "--oversubscribe", "-n", str(ranks)] + cmd
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    try:
        t0 = time.monotonic()
        while not os.path.exists(tmp_path / "out" / "summary.json") and time.monotonic() - t0 < TIMEOUT:
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.05)
        time.sleep(1.0)                                  # well inside the first Newton solve
        proc.send_signal(signal.SIGTERM)
        stdout, stderr = proc.communicate(timeout=TIMEOUT)
    finally:
        if proc.poll() is None:
            proc.kill()
    p = subprocess.CompletedProcess(cmd, proc.returncode, stdout, stderr)
    assert_one_line(p, 1 if ranks > 1 else 128 + signal.SIGTERM, "interrupted by SIGTERM in the Newton solve at "
                    "load factor")
    s = _check_agreement(tmp_path / "out")
    assert (s["status"], s["reason_code"], len(s["steps"])) == ("interrupted", "SIGTERM", 0)


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_closed_stdout_pipe_does_not_stop_the_solve(tmp_path, ranks):
    """`ancf-solve ... | head -1`: one rank stops printing and solves on.  Under mpirun the
    launcher itself aborts the job after ten writes to the closed pipe (hard-wired in Open MPI;
    docs/running.md): the ranks then get SIGTERM and stop cleanly, their levels kept."""
    raw = tiny()
    raw["steps"] = [0.25, 0.5, 0.75, 1.0]
    raw["output"]["dir"] = str(tmp_path / "out")
    cfg = write_config(raw, tmp_path / "c.yaml")
    cmd = [os.path.join(VENV_BIN, "ancf-solve"), cfg, "-snes_monitor"]
    if ranks > 1:
        cmd = ["mpirun", "--oversubscribe", "-n", str(ranks)] + cmd
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    first = proc.stdout.readline()                    # like `| head -1`
    proc.stdout.close()
    try:
        _, stderr = proc.communicate(timeout=TIMEOUT)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert first.startswith(b"[ancf]")
    assert b"Traceback" not in stderr and b"PETSC ERROR" not in stderr, stderr.decode()
    s = _check_agreement(tmp_path / "out")
    if ranks == 1:
        assert proc.returncode == 0 and s["status"] == "completed" and len(s["steps"]) == 4
    else:
        assert (s["status"], s["reason_code"]) in (("completed", "COMPLETED"), ("interrupted", "SIGTERM"))


def test_a_singular_tangent_is_reported_as_unstable(tmp_path):
    """The same singular model with the default null-pivot detection: Newton leaves the
    mechanism alone and converges, and the zero eigenvalues make every level unstable."""
    petsc_init()
    from petsc4py import PETSc

    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    raw = tiny()
    raw["output"]["dir"] = str(tmp_path / "out")
    spec = parse_config(raw, base_dir=CONFIGS)
    spec.beams[0].axial_points = 1
    res = run_model(spec, PETSc.COMM_WORLD, lambda *_: None)
    assert (res.status, res.exit_code) == ("unstable", 4)
    assert all(r.negative_eigenvalues > 0 for r in res.records)


def test_a_second_run_into_the_same_output_directory_is_refused(tmp_path):
    """Two runs into one directory mixed their results (issue 25): the second is refused up
    front naming the holder's pid and host (exit 2), the first completes and releases the lock;
    a lock left by a process that is gone is detected and taken over."""
    out = tmp_path / "shared"
    env = dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT)
    exe = os.path.join(VENV_BIN, "ancf-solve")
    first = subprocess.Popen([exe, os.path.join(CONFIGS, "achilles_type3_psi45.yaml"),
                              "--output-dir", str(out), "--quiet"], cwd=ROOT, env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        t0 = time.time()
        while not (out / ".ancf-lock").exists() and time.time() - t0 < 60:
            time.sleep(0.02)
        assert (out / ".ancf-lock").exists()
        p = solve_cli(write_config(tiny(), tmp_path / "b.yaml"), extra=["--output-dir", str(out)])
        lines = solver_lines(p.stderr)
        assert p.returncode == 2 and len(lines) == 1, p.stderr
        assert f"pid {first.pid} on " in lines[0] and "in use by another run" in lines[0]
    finally:
        first.communicate(timeout=TIMEOUT)
    assert first.returncode == 0 and not (out / ".ancf-lock").exists()
    assert read_summary(out)["name"] == "achilles_type3_psi45"
    # a stale lock: its process no longer runs
    (out / ".ancf-lock").write_text(json.dumps({"pid": 2 ** 22 + 17, "host": os.uname().nodename,
                                                "start": None, "since": "earlier"}))
    p = solve_cli(write_config(tiny(), tmp_path / "c.yaml"), extra=["--output-dir", str(out)])
    assert p.returncode == 0 and "removed the stale lock of pid" in p.stdout
    assert not (out / ".ancf-lock").exists()


def test_own_options_with_one_dash_are_refused_before_anything_is_written(tmp_path):
    """``-restart DIR`` went to PETSc and a fresh run overwrote the interrupted one (issue 25)."""
    cfg = write_config(tiny(), tmp_path / "t.yaml")
    for args in (["-restart", str(tmp_path / "r")], ["-output-dir", str(tmp_path / "o")], ["-quiet"],
                 ["-output_dir", str(tmp_path / "o")]):
        p = solve_cli(cfg, extra=args, cwd=str(tmp_path))
        lines = solver_lines(p.stderr)
        assert p.returncode == 2 and len(lines) == 1 and "take two dashes" in lines[0], p.stderr
    assert not os.path.exists(tmp_path / "results")      # nothing written


def test_a_level_is_accepted_only_at_the_stated_tolerance(tmp_path):
    """``-snes_linesearch_type bt`` ended levels of the pretwisted bar on the step-length test
    with |F| up to 420 × the printed tolerance, reported converged: now such a stop is cut back
    and every reported level has |F| at the tolerance."""
    raw = load_raw("pretwisted_bar.yaml")
    raw["output"] = {"dir": str(tmp_path / "bt"), "vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "bt.yaml"), extra=["-snes_linesearch_type", "bt"])
    assert p.returncode == 0, p.stderr
    s = read_summary(tmp_path / "bt")
    atol = float(re.search(r"atol ([0-9.e+-]+)", p.stdout).group(1))
    assert all(st["reason"].startswith("CONVERGED_FNORM") for st in s["steps"])
    assert all(st["residual_norm"] <= atol for st in s["steps"] if st["reason"] == "CONVERGED_FNORM_ABS")


def test_ancf_study_stopped_by_ctrl_c_says_so_in_one_line(tmp_path):
    """Ctrl-C during ``ancf-study S.yaml`` ended in a KeyboardInterrupt traceback from inside the
    Newton solve (exit by SIGINT); ancf-sweep, ancf-fit and ancf-solve say one line.  Now
    'ancf-study: interrupted ...', exit 130."""
    import yaml
    study = {"kind": "pareto", "name": "long", "base": os.path.join(CONFIGS, "bending_neohookean.yaml"),
             "probe": "tip", "component": "z", "grid": {"elements": [1, 2, 4, 8, 16, 32, 64]},
             "reference": {"elements": 128}, "repeats": 20, "output": str(tmp_path / "st")}
    f = str(tmp_path / "st.yaml")
    with open(f, "w") as fh:
        yaml.safe_dump(study, fh)
    p = subprocess.Popen([os.path.join(VENV_BIN, "ancf-study"), f], stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=dict(os.environ, **MPI_ENV),
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 120
    while not os.path.isdir(tmp_path / "st" / "run_000") and time.time() < deadline:
        time.sleep(0.1)
    p.send_signal(signal.SIGINT)
    err = p.communicate(timeout=120)[1]
    assert p.returncode == 130 and "Traceback" not in err, err
    assert err.strip().splitlines() == ["ancf-study: interrupted (Ctrl-C); no study.csv written: run the "
                                        "same command to start it again"], err
