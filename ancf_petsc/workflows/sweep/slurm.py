"""SLURM job arrays for a sweep: one array task per run (a script that runs and records it,
and continues an interrupted run with --restart), with the settings of the sweep file's ``slurm:``."""
from __future__ import annotations

import os
import shlex
import sys

from ...io.files import atomic_write, remove_quietly
from .execute import ATTEMPT_HEADER, solver_command
from .expand import expand, prepare_run
from .spec import Sweep


# ----------------------------------------------------------------------------------- SLURM
#: the script's first lines: the sweep directory (holding runs.txt and the run directories) is
#: ANCF_SWEEP_DIR, else the submission directory, else the script's own (``bash sweep.slurm``);
#: under sbatch the script runs as a copy in SLURM's spool directory, so $0 alone says nothing
_FIND_SWEEP = [
    'SWEEP_OUTPUT=""',
    'for D in "${ANCF_SWEEP_DIR:-}" "${SLURM_SUBMIT_DIR:-}" "$(dirname "$0")"; do',
    '  if [ -n "$D" ] && [ -f "$D/runs.txt" ] && [ -f "$D/sweep.slurm" ]; then',
    '    SWEEP_OUTPUT=$(cd "$D" && pwd); break',
    "  fi",
    "done",
    'if [ -z "$SWEEP_OUTPUT" ]; then',
    '  echo "ancf-sweep: no runs.txt here: submit from the sweep directory (cd DIR && sbatch '
    'sweep.slurm) or set ANCF_SWEEP_DIR=DIR" >&2',
    "  exit 2",
    "fi",
]


def _slurm_time(sweep: Sweep) -> str | None:
    """``--time``: slurm.time, else the run's timeout plus a start-up margin, else none."""
    if sweep.slurm.time is not None:
        return sweep.slurm.time
    if sweep.timeout is None:
        return None
    minutes = int(sweep.timeout // 60) + 2
    return f"{minutes // 60:02d}:{minutes % 60:02d}:00"


def default_venv() -> str | None:
    """The virtual environment running this program, if it has ancf-solve."""
    prefix = sys.prefix
    if prefix != getattr(sys, "base_prefix", prefix) and \
            os.path.isfile(os.path.join(prefix, "bin", "ancf-solve")):
        return prefix
    return None


def write_slurm(sweep: Sweep, force: bool = False) -> tuple[str, str]:
    """Prepare every run directory and write ``sweep.slurm`` + ``runs.txt``; returns their paths.

    Array task i runs line i+1 of runs.txt; ``tasks/<i>`` links to that run directory so that
    SLURM's ``--output`` lands in the run directory itself.  Resources come from ``sweep.slurm``;
    the environment is ``$ANCF_VENV`` at submission, else slurm.venv, else the one running this."""
    runs = expand(sweep)
    os.makedirs(sweep.output, exist_ok=True)
    for run in runs:
        prepare_run(sweep, run)
        if force:
            remove_quietly(os.path.join(run.dir, "summary.json"), os.path.join(run.dir, "run.json"))
    # runs.txt and every path in the script are relative to the sweep directory, found at run
    # time (``_FIND_SWEEP``): a sweep prepared on one machine runs on another
    runs_txt = os.path.join(sweep.output, "runs.txt")
    atomic_write(runs_txt, "".join(r.run_id + "\n" for r in runs))
    tasks = os.path.join(sweep.output, "tasks")
    os.makedirs(tasks, exist_ok=True)
    for old in os.listdir(tasks):
        if os.path.islink(os.path.join(tasks, old)):
            os.remove(os.path.join(tasks, old))
    for r in runs:
        os.symlink(os.path.join("..", r.run_id), os.path.join(tasks, str(r.index)))

    q = shlex.quote
    n = len(runs)
    sl = sweep.slurm
    throttle = f"%{sl.throttle}" if sl.throttle is not None and sl.throttle < n else ""
    venv = sl.venv or default_venv()
    if venv is not None and os.path.commonpath([venv, sweep.output]) != os.sep:
        # relative to the sweep directory when both share a tree (a project's .venv and its
        # sweeps/): the same layout elsewhere finds its own environment; else as it is
        venv = "$SWEEP_OUTPUT/" + os.path.relpath(venv, sweep.output)
    petsc = (" " + shlex.join(sweep.petsc)) if sweep.petsc else ""
    sweep_cmd = f"ancf-sweep {q(sweep.file)} --collect"
    record = ("import sys; from ancf_petsc.workflows.sweep import finish_slurm_task as f; "
              "o = f(sys.argv[1], int(sys.argv[2]), float(sys.argv[4]) - float(sys.argv[3]), "
              f"{sweep.timeout!r}, sys.argv[5]); print(vars(o))")
    # summary.json as the attempt starts: one it leaves unchanged is an earlier attempt's
    mark = ("import sys; from ancf_petsc.workflows.sweep.execute import summary_mark; "
            "print(summary_mark(sys.argv[1]))")
    begin = ("import os, sys; from ancf_petsc.workflows.sweep.execute import begin_attempt; "
             'begin_attempt(sys.argv[1], sys.argv[2] == "--restart", {"slurm_job": '
             'os.environ.get("SLURM_ARRAY_JOB_ID"), "slurm_task": os.environ.get("SLURM_ARRAY_TASK_ID")})')
    refresh = ("import sys; from ancf_petsc.workflows.sweep.expand import refresh_inputs; "
               "f = refresh_inputs(sys.argv[1]); "
               'f and print("ancf-sweep: " + sys.argv[1] + ": " + f + " was edited since it ran; solving it again")')
    lines = [
        "#!/bin/bash",
        f"#SBATCH --job-name={sweep.name}",
        f"#SBATCH --array=0-{n - 1}{throttle}",
        f"#SBATCH --ntasks={sweep.ranks}",
        # relative to the submission directory: submit from the sweep directory
        "#SBATCH --output=tasks/%a/slurm-%A_%a.out",
    ]
    time_limit = _slurm_time(sweep)
    for option, value in (("time", time_limit), ("cpus-per-task", sl.cpus_per_task), ("mem", sl.mem),
                          ("partition", sl.partition), ("account", sl.account)):
        if value is not None:
            lines.append(f"#SBATCH --{option}={value}")
    lines += [
        f"# Sweep {sweep.name}: {n} runs ({sweep.shape()}) of {sweep.base}",
        f"# generated by ancf-sweep from {sweep.file}",
        "#",
        f"# Submit:   cd {q(sweep.output)} && sbatch sweep.slurm",
        "#           (from the sweep directory: SLURM's output goes to tasks/<i>/; the directory",
        "#           may be moved or copied to another machine, every path here is relative to it)",
        "#           (ANCF_VENV=/path/to/venv sbatch ... runs another environment's ancf-solve)",
        f"# Collect:  {sweep_cmd}",
        "#           (results.csv and failed.txt in the output directory; works while tasks still run)",
        "# Array task i runs the directory on line i+1 of runs.txt and skips it if its",
        "# summary.json already says completed (or unstable), so resubmitting only redoes what is",
        "# missing; log.txt " + ("gets one more section per attempt" if sl.logs == "append" else
                                 "is a link to log.N.txt, N counting the attempts") + ".",
        "set -u",
        "# at the time limit SLURM signals the tasks and this shell: the shell waits for ancf-solve",
        "# (which stops at its next safe point, status interrupted) and then records the outcome",
        "trap 'echo \"ancf-sweep: task signalled; waiting for ancf-solve to stop cleanly\" >&2' TERM INT",
    ] + _FIND_SWEEP
    if venv is not None:
        lines += [f'VENV="${{ANCF_VENV:-{venv}}}"',
                  'PYTHON="$VENV/bin/python"',
                  'ANCF_SOLVE=("$VENV/bin/ancf-solve")']
    else:
        lines += ['VENV="${ANCF_VENV:-}"',
                  f'if [ -n "$VENV" ]; then PYTHON="$VENV/bin/python"; ANCF_SOLVE=("$VENV/bin/ancf-solve"); '
                  f"else PYTHON={q(sys.executable)}; ANCF_SOLVE=({shlex.join(solver_command())}); fi"]
    lines += [
        f"RANKS={sweep.ranks}",
        'TASK="${SLURM_ARRAY_TASK_ID:?not running as a SLURM array task}"',
        'RUN_ID=$(sed -n "$((TASK + 1))p" "$SWEEP_OUTPUT/runs.txt")',
        'RUN_DIR="$SWEEP_OUTPUT/$RUN_ID"',
        'if [ -z "$RUN_ID" ] || [ ! -f "$RUN_DIR/config.yaml" ]; then',
        '  echo "ancf-sweep: array task $TASK has no run directory in $SWEEP_OUTPUT/runs.txt" >&2',
        "  exit 1",
        "fi",
        'if [ ! -x "${ANCF_SOLVE[0]}" ] && ! command -v "${ANCF_SOLVE[0]}" >/dev/null 2>&1; then',
        '  echo "ancf-sweep: no ancf-solve at ${ANCF_SOLVE[0]} (set ANCF_VENV or slurm.venv)" >&2',
        "  exit 1",
        "fi",
        # a data file edited since the run was solved: its result is cleared and solved again
        f'"$PYTHON" -c {q(refresh)} "$RUN_DIR" 2>/dev/null',
        "if \"$PYTHON\" -c 'import json, sys; sys.exit(json.load(open(sys.argv[1])).get(\"status\") "
        "not in (\"completed\", \"unstable\"))' \"$RUN_DIR/summary.json\" 2>/dev/null; then",
        '  echo "ancf-sweep: $RUN_DIR already done; skipping"',
        "  exit 0",
        "fi",
        'if command -v srun >/dev/null 2>&1; then LAUNCH=(srun --ntasks="${SLURM_NTASKS:-$RANKS}")',
        'else LAUNCH=(mpirun -n "$RANKS"); fi',
    ]
    if sweep.timeout is not None:
        lines.append(f"LAUNCH=(timeout --signal=TERM --kill-after=30 {sweep.timeout:g} "
                     '"${LAUNCH[@]}")')
    if sl.logs == "numbered":
        lines += ['N=1; while [ -e "$RUN_DIR/log.$N.txt" ]; do N=$((N + 1)); done',
                  'LOG="$RUN_DIR/log.$N.txt"; : > "$LOG"; ln -sfn "log.$N.txt" "$RUN_DIR/log.txt"']
    else:
        lines += ['LOG="$RUN_DIR/log.txt"']
    lines += [
        'export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"',
        'export OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"',
        'echo "ancf-sweep: task $TASK: $RUN_DIR on $(hostname), $RANKS rank(s)"',
        f'echo "{ATTEMPT_HEADER}: job ${{SLURM_ARRAY_JOB_ID:-?}}_$TASK on $(hostname) at '
        '$(date +%Y-%m-%dT%H:%M:%S) ===" >> "$LOG"',
        f'BEFORE=$("$PYTHON" -c {q(mark)} "$RUN_DIR" 2>/dev/null)',
        # a task killed at the time limit (interrupted) or with its node (running) goes on from
        # its last converged level when the array is submitted again
        'WHERE=(--output-dir "$RUN_DIR")',
        "if \"$PYTHON\" -c 'import json, os, sys; s = json.load(open(sys.argv[1])); "
        "sys.exit(not (s.get(\"status\") in (\"interrupted\", \"running\") and s.get(\"steps\") "
        "and os.path.exists(sys.argv[2])))' \"$RUN_DIR/summary.json\" \"$RUN_DIR/results.h5\" 2>/dev/null; then",
        '  WHERE=(--restart "$RUN_DIR"); echo "ancf-sweep: continuing $RUN_DIR from its last converged level"',
        "fi",
        # run.json says running (with a restart: the wall time of the attempts it continues)
        f'"$PYTHON" -c {q(begin)} "$RUN_DIR" "${{WHERE[0]}}" 2>/dev/null || rm -f "$RUN_DIR/run.json"',
        "START=$(date +%s.%N)",
        '"${LAUNCH[@]}" "${ANCF_SOLVE[@]}" "$RUN_DIR/config.yaml" "${WHERE[@]}"'
        f'{petsc} >> "$LOG" 2>&1',
        "RC=$?",
        "END=$(date +%s.%N)",
        f"\"$PYTHON\" -c {q(record)} \"$RUN_DIR\" \"$RC\" \"$START\" \"$END\" \"$BEFORE\"",
        'exit "$RC"',
    ]
    script = os.path.join(sweep.output, "sweep.slurm")
    atomic_write(script, "\n".join(lines) + "\n")
    os.chmod(script, 0o755)
    return script, runs_txt
