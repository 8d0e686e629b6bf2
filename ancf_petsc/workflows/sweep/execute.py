"""One run of a sweep as a child ancf-solve process: the command, its outcome classified from the exit
code and summary.json (never from its stderr, which goes to log.txt for people), kill on timeout
or cancel."""
from __future__ import annotations

import json
import os
import shlex
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass

from ...errors import InputError
from ...io.files import DirectoryLock, atomic_write, remove_quietly
from ...status import CONFIG_ERROR, EXIT_INPUT, EXIT_UNSTABLE
from .base import read_json
from .processes import Active, stop_processes
from .spec import RunSpec, Sweep


# ------------------------------------------------------------------------- running one run
@dataclass
class Outcome:
    """How one attempt ended."""
    status: str                     # one of FINAL_STATUSES, or running (by another process)
    reason: str = ""
    wall_time: float | None = None
    returncode: int | None = None


def solver_command() -> list[str]:
    """The ancf-solve command: beside this interpreter, else on PATH, else ``python -m``."""
    exe = os.path.join(os.path.dirname(sys.executable), "ancf-solve")
    if os.path.isfile(exe) and os.access(exe, os.X_OK):
        return [exe]
    import shutil
    found = shutil.which("ancf-solve")
    return [found] if found else [sys.executable, "-m", "apps.ancf_solve"]


#: statuses of an attempt that stopped early but kept its converged levels: continued with
#: ``ancf-solve --restart`` (a task killed at the time limit, or by the node)
RESTARTABLE = ("interrupted", "running")


def can_restart(run_dir: str) -> bool:
    """The run in ``run_dir`` stopped early with converged levels on disk (same config)."""
    summary = read_json(os.path.join(run_dir, "summary.json"))
    return (summary is not None and summary.get("status") in RESTARTABLE and bool(summary.get("steps"))
            and os.path.exists(os.path.join(run_dir, "results.h5")))


def summary_mark(run_dir: str) -> str:
    """summary.json as it is now (inode, mtime, size; '' when there is none): an attempt that
    leaves this mark wrote no summary, and the one on disk is an earlier attempt's."""
    try:
        st = os.stat(os.path.join(run_dir, "summary.json"))
    except OSError:
        return ""
    return f"{st.st_ino}:{st.st_mtime_ns}:{st.st_size}"


def solve_command(sweep: Sweep, run: RunSpec) -> list[str]:
    """Full command of one local run (``mpiexec -n ranks`` in front when ranks > 1); a run that
    stopped early is continued from its last converged level."""
    where = ["--restart", run.dir] if can_restart(run.dir) else ["--output-dir", run.dir]
    cmd = solver_command() + [os.path.join(run.dir, "config.yaml")] + where
    cmd += sweep.petsc
    if sweep.ranks > 1:
        cmd = sweep.mpiexec + ["-n", str(sweep.ranks)] + cmd
    return cmd


def _signal_name(returncode: int) -> str:
    try:
        return signal.Signals(-returncode).name
    except ValueError:
        return f"signal {-returncode}"


def input_problem(run_dir: str) -> str:
    """Why ancf-solve refused the run's config.yaml (exit code 2 before summary.json): the same
    checks run here, and the error's key path and message are read as data."""
    from ...config.parse import load_config
    from ...io.restart import read_restart
    from ...model.contact_setup import check_model
    try:
        check_model(load_config(os.path.join(run_dir, "config.yaml")))
        if can_restart(run_dir):                # the attempt was a restart: did it refuse?
            read_restart(run_dir)
    except InputError as exc:
        return f"config error: {exc.path}: {exc.message}" if exc.path else f"config error: {exc.message}"
    except Exception:               # noqa: BLE001 - any other failure: the log has it
        pass
    return f"input error (exit code {EXIT_INPUT}); see log.txt"


def classify(run_dir: str, returncode: int | None, timed_out: bool = False,
             timeout: float | None = None, before: str = "") -> tuple[str, str]:
    """(status, reason) of a finished attempt from summary.json's ``status`` and ``message`` and
    the exit code; stderr is never read.  An attempt without a final summary (none, or still
    ``before``'s, the ``summary_mark`` of an earlier attempt) is classified by its exit code
    alone (a config error's reason from ``input_problem``)."""
    summary = read_json(os.path.join(run_dir, "summary.json")) or {}
    if before and summary_mark(run_dir) == before:
        summary = {}
    sstat = summary.get("status")
    message = str(summary.get("message") or "")
    if timed_out and sstat == "completed":     # its last level was written as the time ran out
        return "completed", ""
    if timed_out:
        steps = summary.get("steps") or []
        last = f"; last converged load factor {steps[-1].get('load_factor'):g}" if steps else ""
        return "timeout", f"timed out after {timeout:g} s{last}" if timeout else "timed out" + last
    if returncode == 0 and sstat == "completed":
        return "completed", ""
    if returncode == EXIT_UNSTABLE and sstat == "unstable":
        return "unstable", message or "unstable"
    if sstat == "interrupted":
        return "interrupted", message or "interrupted"
    if sstat == "failed":
        return "failed", message or f"a load level was not reached (exit code {returncode})"
    if returncode in (128 + signal.SIGTERM, 128 + signal.SIGINT):
        return "interrupted", f"interrupted (exit code {returncode}) before summary.json said so"
    if returncode == EXIT_INPUT and sstat is None:
        return "config_error", input_problem(run_dir)
    if returncode is not None and returncode < 0:
        return "crashed", f"killed by {_signal_name(returncode)}"
    if returncode == 0:
        return "crashed", f"exit code 0 but summary.json says status {sstat!r}"
    return "crashed", f"exit code {returncode}" + (f"; summary.json says status {sstat!r}" if sstat else "")


#: reason codes of sweep statuses that ancf-solve does not report itself
SWEEP_CODES = {"config_error": CONFIG_ERROR, "timeout": "TIMEOUT", "crashed": "CRASHED"}


def reason_code(run_dir: str, status: str) -> str:
    """The machine-readable reason of an attempt: summary.json's ``reason_code`` (the SNES reason,
    NEWTON_BUDGET_EXCEEDED, OUTPUT_ERROR, SIGTERM, ...) or the sweep's own (``SWEEP_CODES``)."""
    if status in SWEEP_CODES:
        return SWEEP_CODES[status]
    summary = read_json(os.path.join(run_dir, "summary.json")) or {}
    return str(summary.get("reason_code") or ("COMPLETED" if status == "completed" else ""))


def record_outcome(run_dir: str, returncode: int | None, wall_time: float,
                   timed_out: bool = False, timeout: float | None = None, extra: dict | None = None,
                   verdict: tuple[str, str] | None = None, before: str = "") -> Outcome:
    """Classify a finished attempt (unless ``verdict`` gives (status, reason)) and write
    ``run.json``; ``before``: summary.json's mark as the attempt started (``classify``)."""
    if verdict is not None:
        status, reason = verdict
    else:
        status, reason = classify(run_dir, returncode, timed_out, timeout, before)
    record = read_json(os.path.join(run_dir, "run.json")) or {}
    record.update(extra or {})
    record.update({"status": status, "reason": reason, "reason_code": reason_code(run_dir, status),
                   "wall_time": wall_time,
                   "returncode": returncode, "finished": time.strftime("%Y-%m-%dT%H:%M:%S")})
    atomic_write(os.path.join(run_dir, "run.json"), json.dumps(record, indent=1) + "\n")
    return Outcome(status, reason, wall_time, returncode)


def begin_attempt(run_dir: str, restart: bool, extra: dict | None = None) -> dict | None:
    """run.json of an attempt that starts: status running, and with a restart the wall time of
    the attempts it continues (``earlier_wall_time``: results.csv gives the whole run's); returns
    the record it replaces (put back by an attempt that does not start)."""
    previous = read_json(os.path.join(run_dir, "run.json"))
    old = previous or {}
    earlier = float(old.get("earlier_wall_time") or 0.0) + float(old.get("wall_time") or 0.0)
    remove_quietly(os.path.join(run_dir, "run.json"))
    record = {"status": "running", "started": time.strftime("%Y-%m-%dT%H:%M:%S"),
              "host": socket.gethostname(), **(extra or {})}
    if restart and earlier:
        record["earlier_wall_time"] = earlier
    atomic_write(os.path.join(run_dir, "run.json"), json.dumps(record, indent=1) + "\n")
    return previous


#: first line of each attempt in an appended log.txt (SLURM resubmissions)
ATTEMPT_HEADER = "=== ancf-sweep attempt"


def finish_slurm_task(run_dir: str, returncode: int, wall_time: float,
                      timeout: float | None = None, before: str = "") -> Outcome:
    """Record a run executed by the SLURM script (exit code 124 of ``timeout`` = time limit;
    ``before``: summary.json's ``summary_mark`` as the task started ancf-solve)."""
    return record_outcome(run_dir, returncode, wall_time, before=before,
                          timed_out=timeout is not None and returncode == 124, timeout=timeout,
                          extra={"host": socket.gethostname(),
                                 "slurm_job": os.environ.get("SLURM_ARRAY_JOB_ID"),
                                 "slurm_task": os.environ.get("SLURM_ARRAY_TASK_ID")})


def _child_env() -> dict[str, str]:
    env = dict(os.environ)
    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
        env.setdefault(k, "1")      # ranks x jobs processes: BLAS threads would only contend
    env.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")   # jobs x ranks may exceed the cores
    return env


def _kill(proc: subprocess.Popen) -> None:
    """Terminate the run's process group (it was started in its own session), then kill it."""
    stop_processes([proc], signal.SIGTERM, grace=5.0)


def solved_elsewhere(run_dir: str) -> Outcome | None:
    """The outcome 'running' when a live process holds the run directory's lock, else None."""
    lock = DirectoryLock(run_dir)
    holder = lock.live_holder()
    if holder is None:
        return None
    return Outcome("running", f"being run by another process (pid {holder.get('pid')} on "
                              f"{holder.get('host')}, since {holder.get('since')}); not started "
                              f"here (remove {lock.path} if that run is gone)", 0.0)


def execute_run(sweep: Sweep, run: RunSpec, active: Active | None = None) -> Outcome | None:
    """Run one prepared run directory; writes log.txt and run.json, returns the outcome (None:
    not started, the sweep is being stopped)."""
    active = active or Active()
    if active.cancelled.is_set():
        return None
    busy = solved_elsewhere(run.dir)
    if busy is not None:                         # another ancf-sweep's: its files are left alone
        return busy
    cmd = solve_command(sweep, run)              # decides on a restart from summary.json
    if "--restart" not in cmd:
        remove_quietly(os.path.join(run.dir, "summary.json"))
    before = summary_mark(run.dir)               # a restart's: the stopped attempt's summary
    previous = begin_attempt(run.dir, "--restart" in cmd, {"sweep_pid": os.getpid(), "ranks": sweep.ranks,
                                                           "command": shlex.join(cmd)})
    t0 = time.monotonic()
    with open(os.path.join(run.dir, "log.txt"), "wb", buffering=0) as log:
        log.write(("$ " + shlex.join(cmd) + "\n").encode())
        try:
            proc = active.start(cmd, cwd=run.dir, env=_child_env(), stdin=subprocess.DEVNULL,
                                stdout=log, stderr=subprocess.PIPE)
        except OSError as exc:
            msg = f"cannot start {cmd[0]}: {exc.strerror}"
            log.write((msg + "\n").encode())
            return record_outcome(run.dir, None, time.monotonic() - t0, verdict=("crashed", msg))
        if proc is None:                         # stopped between the check above and now
            log.write(b"not started: ancf-sweep was interrupted\n")
            remove_quietly(os.path.join(run.dir, "run.json"))
            if previous is not None:             # the attempt before's record (its wall time)
                atomic_write(os.path.join(run.dir, "run.json"), json.dumps(previous, indent=1) + "\n")
            return None

        def pump() -> None:
            for raw in proc.stderr:             # type: ignore[union-attr]
                log.write(raw)

        reader = threading.Thread(target=pump, daemon=True)
        reader.start()
        timed_out = False
        try:
            rc = proc.wait(timeout=sweep.timeout)
        except subprocess.TimeoutExpired:
            timed_out = True
            _kill(proc)
            rc = proc.returncode
        finally:
            active.finished(proc)
        reader.join(timeout=10.0)
    wall = time.monotonic() - t0
    if active.cancelled.is_set() and not timed_out and rc != 0:
        # stopped by the sweep: at its next safe point (exit 130/143, converged levels kept) or,
        # past the grace period, killed; either way it is continued by the next ancf-sweep
        summary = read_json(os.path.join(run.dir, "summary.json")) or {}
        if summary.get("status") == "completed":      # done as the signal came (mpirun: exit 1)
            return record_outcome(run.dir, rc, wall, verdict=("completed", ""))
        how = "stopped at a safe point" if summary.get("status") == "interrupted" \
            else f"killed ({_signal_name(rc) if rc is not None and rc < 0 else f'exit code {rc}'})"
        return record_outcome(run.dir, rc, wall,
                              verdict=("interrupted", f"ancf-sweep was interrupted; the run {how}"))
    return record_outcome(run.dir, rc, wall, timed_out=timed_out, timeout=sweep.timeout, before=before)
