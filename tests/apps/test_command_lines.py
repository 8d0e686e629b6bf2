"""Every command line (apps/cli.py): help and progress lines into a pipe whose reader is gone
(``ancf-sweep S.yaml --dry-run | head -1``) end quietly with the work's own exit code."""
from __future__ import annotations

import os
import subprocess

import pytest
import yaml

from helpers import CONFIGS, MPI_ENV, ROOT, VENV_BIN, solve_cli

TIMEOUT = 300
PROGRAMS = ("ancf-solve", "ancf-report", "ancf-study", "ancf-sweep", "ancf-fit")


def into_closed_pipe(args: list[str], cwd=ROOT) -> subprocess.CompletedProcess:
    """Run a command line with stdout a pipe already closed by its reader (``| head -0``)."""
    r, w = os.pipe()
    os.close(r)
    try:
        return subprocess.run([os.path.join(VENV_BIN, args[0])] + args[1:], stdout=w, stderr=subprocess.PIPE,
                              text=True, timeout=TIMEOUT, cwd=cwd, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    finally:
        os.close(w)


def _write(path, doc: dict) -> str:
    with open(path, "w") as fh:
        yaml.safe_dump(doc, fh, sort_keys=False)
    return str(path)


def _work(program: str, tmp) -> tuple[list[str], str]:
    """A small piece of work for ``program`` and the file it writes when done."""
    uniaxial = os.path.join(CONFIGS, "uniaxial_neohookean.yaml")
    if program == "ancf-sweep":
        sweep = {"base": uniaxial, "parameters": {"beams[0].elements": [1, 2]}, "output": str(tmp / "sw")}
        return [_write(tmp / "sw.yaml", sweep), "--slurm"], str(tmp / "sw" / "sweep.slurm")
    if program == "ancf-study":
        study = {"kind": "pareto", "name": "tiny", "base": os.path.join(CONFIGS, "bending_neohookean.yaml"),
                 "probe": "tip", "component": "z",
                 "grid": {"element": ["3363"], "axial_points": [2], "cubature_degree": [2], "elements": [1, 2]},
                 "reference": {"element": "3363", "axial_points": 2, "cubature_degree": 2, "elements": 4},
                 "output": str(tmp / "st")}
        return [_write(tmp / "st.yaml", study)], str(tmp / "st" / "study.csv")
    if program == "ancf-fit":
        with open(os.path.join(CONFIGS, "fits", "bar_twin.yaml")) as fh:
            fit = yaml.safe_load(fh)
        fit["model"] = os.path.join(CONFIGS, "calibration_bar.yaml")
        for d in fit["data"]:
            d["file"] = os.path.join(CONFIGS, "data", os.path.basename(d["file"]))
        fit["output"] = str(tmp / "fit")
        return [_write(tmp / "fit.yaml", fit)], str(tmp / "fit" / "fit.json")
    if program == "ancf-report":
        run = tmp / "run"
        assert solve_cli(uniaxial, extra=["--output-dir", str(run), "--quiet"]).returncode == 0
        return ["--existing", str(run), "--out", str(tmp / "rep")], str(tmp / "rep" / "report.md")
    raw = yaml.safe_load(open(uniaxial))
    raw["output"] = {"dir": str(tmp / "out"), "vtk": False}
    return [_write(tmp / "c.yaml", raw)], str(tmp / "out" / "summary.json")


@pytest.mark.parametrize("program", PROGRAMS)
def test_help_into_a_closed_pipe(program):
    """``ancf-sweep --help | head -0`` was a BrokenPipeError traceback and exit 1."""
    p = into_closed_pipe([program, "--help"])
    assert (p.returncode, p.stderr) == (0, "")


@pytest.mark.parametrize("program", PROGRAMS)
def test_progress_lines_into_a_closed_pipe(program, tmp_path):
    """The work is done and the exit code is its own: ancf-sweep --slurm, ancf-fit and ancf-report
    stopped at their first line with a BrokenPipeError (exit 1), ancf-study's first line after
    PETSc started was PETSc's SIGPIPE abort (exit 59)."""
    args, written = _work(program, tmp_path)
    p = into_closed_pipe([program] + args, cwd=tmp_path)
    assert (p.returncode, p.stderr) == (0, "")
    assert os.path.isfile(written)


@pytest.mark.parametrize("args,words", [
    (["ancf-solve"], "the following arguments are required: config"),
    (["ancf-report", "--ranks", "x"], "argument --ranks"),
    (["ancf-study"], "the following arguments are required: study"),
    (["ancf-sweep", "s.yaml", "--jobs", "x"], "argument --jobs: expected a positive integer; got 'x'"),
    (["ancf-fit", "f.yaml", "--task", "x"], "argument --task: expected an integer; got 'x'"),
])
def test_an_option_error_is_one_line(args, words):
    """argparse's usage block (five lines for ancf-sweep) before its error line is left out."""
    p = subprocess.run([os.path.join(VENV_BIN, args[0])] + args[1:], capture_output=True, text=True,
                       timeout=TIMEOUT, cwd=ROOT, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert p.stderr == f"{args[0]}: {p.stderr.split(': ', 1)[1]}" and p.stderr.count("\n") == 1, p.stderr
    assert words in p.stderr and p.stderr.endswith(f"(see {args[0]} --help)\n"), p.stderr
