"""Every command line (apps/cli.py): help and progress lines into a pipe whose reader is gone
(``ancf-sweep S.yaml --dry-run | head -1``) end quietly with the work's own exit code."""
from __future__ import annotations

import os
import subprocess

import pytest
import yaml

from helpers import CONFIGS, MPI_ENV, ONE_AND_TWO_RANKS, ROOT, VENV_BIN, bar_twin_fit, solve_cli

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
        return [_write(tmp / "fit.yaml", bar_twin_fit(tmp / "fit"))], str(tmp / "fit" / "fit.json")
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


def into_gone_terminal(args: list[str], cwd=ROOT, stderr_too: bool = False) -> subprocess.CompletedProcess:
    """Run a command line with stdout (and stderr) a terminal that went away (a pseudo-terminal
    whose other end is closed: the closed ssh session of a detached run, a killed mpirun): every
    write to it fails with EIO."""
    master, slave = os.openpty()
    os.close(master)
    try:
        return subprocess.run([os.path.join(VENV_BIN, args[0])] + args[1:], stdout=slave,
                              stderr=slave if stderr_too else subprocess.PIPE, text=True,
                              timeout=TIMEOUT, cwd=cwd,
                              start_new_session=True, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    finally:
        os.close(slave)


@pytest.mark.parametrize("program", ["ancf-solve", "ancf-sweep"])
def test_progress_lines_into_a_terminal_that_went_away(program, tmp_path):
    """The work goes on as into a closed pipe: ancf-solve ended 'failed', INTERNAL_ERROR
    'OSError: [Errno 5] Input/output error', exit 1 with a traceback, at its first line (the gait
    stride whose terminal closed after frame 3: 4 of 100 frames solved)."""
    args, written = _work(program, tmp_path)
    p = into_gone_terminal([program] + args, cwd=tmp_path)
    assert (p.returncode, p.stderr) == (0, "")
    assert os.path.isfile(written)


def into_gone_stderr(args: list[str], into: str, cwd) -> subprocess.CompletedProcess:
    """Run a command line with stdout and stderr a pipe closed by its reader (``2>&1 | head -0``,
    ``into`` "pipe") or a terminal that went away ("terminal")."""
    if into == "terminal":
        return into_gone_terminal(args, cwd=cwd, stderr_too=True)
    r, w = os.pipe()
    os.close(r)
    try:
        return subprocess.run([os.path.join(VENV_BIN, args[0])] + args[1:], stdout=w, stderr=w,
                              timeout=TIMEOUT, cwd=cwd, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    finally:
        os.close(w)


@pytest.mark.parametrize("into", ["pipe", "terminal"])
@pytest.mark.parametrize("extra, code", [(["-snes_maxit", "3"], 0), (["-snes_max_it", "1"], 3)])
def test_the_last_lines_on_a_gone_stderr_keep_the_runs_exit_code(into, extra, code, tmp_path):
    """``ancf-solve C.yaml 2>&1 | head -0`` (or a closed terminal): the line on stderr after the
    run (an unused option's warning, the failure) raised BrokenPipeError / EIO out of main, exit
    1 (a bug's code) for a run that completed (exit 0) or could not reach a level (exit 3)."""
    args, written = _work("ancf-solve", tmp_path)
    args = ["ancf-solve"] + args + extra
    p = into_gone_stderr(args, into, tmp_path)
    assert p.returncode == code
    assert os.path.isfile(written)


#: one-line errors of every command line (exit 2): the last is apps/cli.py's Parser
GONE_STDERR_ERRORS = [["ancf-solve"], ["ancf-report", "--existing", "nosuch"], ["ancf-study", "nosuch.yaml"],
                      ["ancf-sweep", "nosuch.yaml"], ["ancf-fit", "nosuch.yaml"],
                      ["ancf-sweep", "s.yaml", "--jobs", "x"]]


@pytest.mark.parametrize("into", ["pipe", "terminal"])
@pytest.mark.parametrize("args", GONE_STDERR_ERRORS)
def test_an_error_line_on_a_gone_stderr_keeps_exit_2(into, args, tmp_path):
    """``ancf-study NOSUCH.yaml 2>&1 | head -0``: the one-line error raised BrokenPipeError, exit 1
    (a bug's code) instead of 2, for every command but ancf-solve's config errors."""
    p = into_gone_stderr(args, into, tmp_path)
    assert p.returncode == 2


#: (command line, words of its one error line); the last ones were accepted: an empty --out or
#: --configs for the default directory (ancf-report --out= wrote report.md into the working
#: directory), a misspelt or one-dash option given to PETSc and left unread (ancf-study S.yaml
#: --output DIR wrote into the study's own output; ancf-fit F.yaml -fresh resumed the log), or
#: refused late, naming another key (ancf-report --jobs -3: "run.jobs")
OPTION_ERRORS = [
    (["ancf-solve"], "the following arguments are required: config"),
    (["ancf-report", "--ranks", "x"], "argument --ranks"),
    (["ancf-study"], "the following arguments are required: study"),
    (["ancf-sweep", "s.yaml", "--jobs", "x"], "argument --jobs: expected a positive integer; got 'x'"),
    (["ancf-fit", "f.yaml", "--task", "x"], "argument --task: expected an integer; got 'x'"),
    (["ancf-solve", ""], "argument config: expected a path; got ''"),
    (["ancf-study", ""], "argument study: expected a path; got ''"),
    (["ancf-sweep", "", "--dry-run"], "argument sweep: expected a path; got ''"),
    (["ancf-fit", ""], "argument fit: expected a path; got ''"),
    (["ancf-study", "s.yaml", "--out="], "argument --out: expected a path; got ''"),
    (["ancf-fit", "f.yaml", "--out="], "argument --out: expected a path; got ''"),
    (["ancf-report", "--out=", "--existing", "run"], "argument --out: expected a path; got ''"),
    (["ancf-report", "--configs", "", "--table1"], "argument --configs: expected a path; got ''"),
    (["ancf-report", "--existing="], "argument --existing: expected a path; got ''"),
    (["ancf-report", "--jobs", "-3", "--table1"], "argument --jobs: expected a positive integer; got -3"),
    (["ancf-report", "--ranks", "0", "--table1"], "argument --ranks: expected a positive integer; got 0"),
    # solving options beside --existing were ignored (--ranks, --figures) or solved the paper's
    # columns into --out beside the given runs (--table1, --fit-bulk-modulus), exit 0
    (["ancf-report", "--existing", "run", "--ranks", "2"], "solves nothing (their figures are drawn "
                                                           "anyway): leave out --ranks; got --existing with --ranks"),
    (["ancf-report", "--existing", "run", "--table1", "--jobs", "2"], "leave out --table1, --jobs"),
    (["ancf-study", "s.yaml", "--output", "o"], "unknown option --output (did you mean --out?)"),
    (["ancf-study", "s.yaml", "--bogus"], "unknown option --bogus (PETSc options take one dash)"),
    (["ancf-study", "s.yaml", "-out", "o"], "-out: ancf-study's own options take two dashes (--out)"),
    (["ancf-fit", "f.yaml", "--outdir=o"], "unknown option --outdir (did you mean --out?)"),
    (["ancf-fit", "f.yaml", "-fresh"], "-fresh: ancf-fit's own options take two dashes (--fresh)"),
    (["ancf-fit", "f.yaml", "--ranks", "4"], "--ranks 4: sets the ranks of --slurm's array tasks; to solve "
                                             "here on 4 ranks, run mpirun -n 4 ancf-fit f.yaml"),
    (["ancf-fit", "f.yaml", "--slurm", "--ranks", "0"], "argument --ranks: expected a positive integer; got 0"),
    # --fresh was unread by the array's tasks, and after --collect's merge dropped the starts' samples
    (["ancf-fit", "f.yaml", "--slurm", "--fresh"], "--fresh: the array's tasks go on from their logs"),
    (["ancf-fit", "f.yaml", "--collect", "--fresh"], "--fresh: --collect would drop the logs it gathers"),
    (["ancf-sweep", "s.yaml", "--throttle", "2"], "--throttle: a SLURM option, for the script of --slurm; "
                                                  "the runs at once here are --jobs"),
    (["ancf-sweep", "s.yaml", "--dry-run", "--mem", "4G"], "--mem: a SLURM option, for the script of --slurm; "
                                                           "add --slurm, or leave it out"),
    # run options that nothing reads were ignored: --collect runs nothing, --slurm's array has --throttle
    (["ancf-sweep", "s.yaml", "--collect", "--ranks", "2"], "--ranks: --collect only reads the runs' outputs: leave it out"),
    (["ancf-sweep", "s.yaml", "--collect", "--force"], "--force: --collect only reads the runs' outputs"),
    (["ancf-sweep", "s.yaml", "--slurm", "--jobs", "4"], "--jobs: the local runs at once; the array's tasks at "
                                                         "once are --throttle"),
]


@pytest.mark.parametrize("args,words", OPTION_ERRORS)
def test_an_option_error_is_one_line(args, words, tmp_path):
    """One line naming the option and what to give, exit 2, nothing written; argparse's usage
    block (five lines for ancf-sweep) before its error line is left out."""
    p = subprocess.run([os.path.join(VENV_BIN, args[0])] + args[1:], capture_output=True, text=True,
                       timeout=TIMEOUT, cwd=tmp_path, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert p.stderr.startswith(f"{args[0]}: ") and p.stderr.count("\n") == 1, p.stderr
    assert words in p.stderr and p.stderr.endswith(f"(see {args[0]} --help)\n"), p.stderr
    assert os.listdir(tmp_path) == []


#: a file argument that is not a model/study/sweep/fit file: (how to make it, words of the line)
BAD_FILES = {
    "missing": (lambda p: None, "no such"),
    "a directory": (lambda p: os.mkdir(p), "is a directory, not a"),
    "empty": (lambda p: open(p, "w").close(), "empty"),
    "a list": (lambda p: open(p, "w").write("- a\n"), "list ['a']"),
    "broken YAML": (lambda p: open(p, "w").write("a: [1,\n"), "YAML syntax error at line 2, column 1"),
    "binary": (lambda p: open(p, "wb").write(b"\xff\xfe\x00bin"), "not a text (UTF-8) YAML file"),
}


@pytest.mark.parametrize("program", ["ancf-solve", "ancf-study", "ancf-sweep", "ancf-fit"])
@pytest.mark.parametrize("case", list(BAD_FILES))
def test_a_bad_file_argument_is_one_line(program, case, tmp_path):
    """ancf-fit DIR said 'is a directory, not a sweep file'; ancf-study EMPTY.yaml said
    'EMPTY.yaml: EMPTY.yaml: expected a mapping' (neither the keys nor what it got)."""
    make, words = BAD_FILES[case]
    f = str(tmp_path / "f.yaml")
    make(f)
    p = subprocess.run([os.path.join(VENV_BIN, program), f], capture_output=True, text=True,
                       timeout=TIMEOUT, cwd=tmp_path, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert p.stderr.startswith(f"{program}: ") and p.stderr.count("\n") == 1, p.stderr
    assert words in p.stderr and "sweep file" not in p.stderr, p.stderr
    if program != "ancf-solve":           # ancf-solve's config error of a list names no file
        assert p.stderr.count("f.yaml") == 1, p.stderr
        if case in ("empty", "a list"):
            assert "expected a mapping with keys " in p.stderr, p.stderr


EXISTING = {
    "no such directory": (lambda d: None, "no such directory (give ancf-solve output directories)"),
    "a file": (lambda d: open(d, "w").close(), "not a directory (give ancf-solve output directories)"),
    "no run": (lambda d: os.mkdir(d), "summary.json: no summary.json (run ancf-solve first)"),
    "an unreadable summary": (lambda d: os.makedirs(os.path.join(d, "summary.json")),
                              "summary.json: cannot read: Is a directory"),
    # a sweep's top directory said only 'no summary.json (run ancf-solve first)'
    "a sweep's top directory": (lambda d: [os.makedirs(os.path.join(d, "out", r)) or open(
        os.path.join(d, "out", r, "summary.json"), "w").close() for r in ("run_0000", "run_0001")],
                                "no summary.json (it holds 2 run directories, e.g. out/run_0000: give those, "
                                "e.g. --existing run/out/*)"),
}


@pytest.mark.parametrize("case", list(EXISTING))
def test_existing_runs_that_are_none_are_refused_before_anything_is_written(case, tmp_path):
    """ancf-report --existing FILE said 'FILE/summary.json: no summary.json', an unreadable
    summary '[Errno 21] Is a directory: ...', each after creating results/achilles_report."""
    make, words = EXISTING[case]
    run = str(tmp_path / "run")
    make(run)
    p = subprocess.run([os.path.join(VENV_BIN, "ancf-report"), "--existing", "run"], capture_output=True,
                       text=True, timeout=TIMEOUT, cwd=tmp_path, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode == 2 and p.stderr.count("\n") == 1, p.stderr
    assert p.stderr.startswith("ancf-report: --existing: run") and words in p.stderr, p.stderr
    assert sorted(os.listdir(tmp_path)) == (["run"] if case != "no such directory" else [])


@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
@pytest.mark.parametrize("case", ["no such directory", "not a directory"])
def test_a_restart_directory_that_is_none_is_refused_and_not_created(case, ranks, tmp_path):
    """ancf-solve C --restart TYPO created TYPO empty, then said 'TYPO/results.h5: no such file';
    --restart FILE said 'exists and is not a directory (choose another output.dir / --output-dir)'."""
    where = tmp_path / "typo"
    if case == "not a directory":
        where.write_text("")
    p = solve_cli(os.path.join(CONFIGS, "uniaxial_neohookean.yaml"), ranks=ranks,
                  extra=["--restart", str(where), "--quiet"], cwd=str(tmp_path), timeout=TIMEOUT)
    lines = [ln for ln in p.stderr.splitlines() if ln.startswith("ancf-solve:")]
    assert p.returncode == 2 and len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    assert lines[0] == (f"ancf-solve: config error: --restart: {where}: {case} "
                        "(restart from a run's output directory)"), lines[0]
    assert os.listdir(tmp_path) == ([] if case == "no such directory" else ["typo"])


def with_closed(fd: int, args: list[str], cwd) -> subprocess.CompletedProcess:
    """Run a command line with stdout (``fd`` 1: ``>&-``) or stderr (2: ``2>&-``) closed, the
    other captured."""
    return subprocess.run([os.path.join(VENV_BIN, args[0])] + args[1:], capture_output=True, text=True,
                          timeout=TIMEOUT, cwd=cwd, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT),
                          preexec_fn=lambda: os.close(fd))


@pytest.mark.parametrize("fd", [1, 2])
def test_a_closed_stream_keeps_a_completed_runs_exit_0(fd, tmp_path):
    """``ancf-solve C.yaml >&-`` (or ``2>&-``) completed its run and exited 1 (AttributeError on
    sys.stdout None, a traceback; with stderr closed a silent 1)."""
    args, written = _work("ancf-solve", tmp_path)
    p = with_closed(fd, ["ancf-solve"] + args + ["-snes_maxit", "3"], tmp_path)
    assert p.returncode == 0
    assert os.path.isfile(written)
    assert "Traceback" not in p.stdout + p.stderr


@pytest.mark.parametrize("args", GONE_STDERR_ERRORS)
def test_an_error_line_on_a_closed_stderr_keeps_exit_2_and_stays_off_stdout(args, tmp_path):
    """``ancf-study NOSUCH.yaml 2>&-``: the one-line error went to stdout (print to a stderr of
    None), and ancf-solve exited 1."""
    p = with_closed(2, args, tmp_path)
    assert (p.returncode, p.stdout) == (2, "")


@pytest.mark.mpi
@pytest.mark.parametrize("program", ["ancf-sweep", "ancf-study", "ancf-report"])
def test_a_program_that_starts_its_own_runs_refuses_mpirun(program, tmp_path):
    """``mpirun -n 2 ancf-sweep S.yaml``: both copies ran the sweep into the same directory and
    the second run of each crashed (its ancf-solve inherited the launcher's variables: orte_init
    failed, 'crashed: exit code 1'); ``mpirun -n 2 ancf-study``: the second copy stopped on the
    first one's lock.  Now one line from rank 0, exit 2, nothing written."""
    args, written = _work(program, tmp_path)
    if program == "ancf-sweep":
        args = args[:-1]                                    # run it, not --slurm
    cmd = ["mpirun", "--oversubscribe", "-n", "2", os.path.join(VENV_BIN, program)] + args
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, cwd=str(tmp_path),
                       env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    lines = [ln for ln in p.stderr.splitlines() if ln.startswith(f"{program}:")]
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert len(lines) == 1 and lines[0].startswith(f"{program}: started by mpirun (2 processes): "), lines
    assert lines[0].endswith("; run it without mpirun") and not os.path.exists(os.path.dirname(written))


@pytest.mark.mpi
@pytest.mark.parametrize("args,start", [
    (["ancf-solve", "--version"], "ancf-solve "),
    (["ancf-solve", "--help"], "usage: ancf-solve"),
    (["ancf-solve", "-help"], "usage: ancf-solve"),
    (["ancf-fit", "--help"], "usage: ancf-fit"),
    (["ancf-report", "--bogus"], "ancf-report: unrecognized arguments: --bogus"),
    (["ancf-sweep"], "ancf-sweep: the following arguments are required: sweep")],
    ids=["solve --version", "solve --help", "solve -help", "fit --help", "report bad option",
         "sweep no file"])
def test_help_version_and_usage_errors_print_once_under_mpirun(args, start, tmp_path):
    """``mpirun -n 3 ancf-solve --version`` printed its line three times, ``--help`` its usage
    three times, and the other programs' option errors came once per rank: rank 0 alone now."""
    cmd = ["mpirun", "--oversubscribe", "-n", "3", os.path.join(VENV_BIN, args[0])] + args[1:]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, cwd=str(tmp_path),
                       env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    lines = [ln for ln in (p.stdout + p.stderr).splitlines() if ln.startswith(start)]
    assert len(lines) == 1 and "Traceback" not in p.stderr, p.stdout + p.stderr
    assert p.returncode == (2 if "arguments" in start else 0), p.returncode


@pytest.mark.parametrize("rank,code", [("0", 2), ("2", 0)])
def test_a_usage_error_under_mpirun_exits_2_on_rank_0_alone(rank, code, monkeypatch, capsys):
    """CI: ``mpirun -n 3 ancf-report --bogus`` printed nothing: rank 2 left first with exit 2
    and mpirun killed rank 0 before it had printed its line.  The other ranks now leave with 0,
    quiet; rank 0 prints and gives the job its 2."""
    from apps.cli import Parser, launch_status
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "3")
    monkeypatch.setenv("OMPI_COMM_WORLD_RANK", rank)
    with pytest.raises(SystemExit) as stop:
        Parser(prog="ancf-report").parse_args(["--bogus"])
    assert stop.value.code == code == launch_status(2)
    assert ("unrecognized arguments: --bogus" in capsys.readouterr().err) == (rank == "0")
