"""Running a sweep locally: runs in parallel jobs with progress lines, stopped cleanly on a signal."""
from __future__ import annotations

import os
import signal
import threading
import time
from dataclasses import dataclass
from typing import Callable

from .base import FINAL_STATUSES
from .execute import Outcome, execute_run
from .processes import Active, shielded
from .expand import expand, prepare_run
from .spec import RunSpec, Sweep


# --------------------------------------------------------------------------- running a sweep
@dataclass
class SweepReport:
    """What one local execution did."""
    runs: list[RunSpec]
    outcomes: dict[str, Outcome]    # run id -> outcome, for the runs executed now
    skipped: list[str]              # run ids already completed
    interrupted: bool = False

    def counts(self) -> dict[str, int]:
        c = {s: 0 for s in FINAL_STATUSES}
        for o in self.outcomes.values():
            c[o.status] = c.get(o.status, 0) + 1
        return c

    def ok(self) -> bool:
        return not self.interrupted and all(o.status == "completed" for o in self.outcomes.values())

    def summary_line(self) -> str:
        """``12 runs: 10 completed, 1 failed, 1 skipped (already done)``."""
        c = self.counts()
        parts = [f"{c['completed']} completed"]
        parts += [f"{n} {s}" for s, n in c.items() if s != "completed" and n]
        if self.skipped:
            parts.append(f"{len(self.skipped)} skipped (already done)")
        not_run = len(self.runs) - len(self.outcomes) - len(self.skipped)
        if not_run:
            parts.append(f"{not_run} not run (interrupted)")
        return f"{len(self.runs)} runs: " + ", ".join(parts)


def progress_line(run: RunSpec, n: int, outcome: Outcome | None = None, event: str = "") -> str:
    """``[sweep] 3/12 run_0003__... completed in 4.2 s`` (or ``failed: <reason> (4.2 s)``)."""
    head = f"[sweep] {run.index + 1}/{n} {run.run_id}"
    if outcome is None:
        return f"{head} {event}"
    t = f"{outcome.wall_time:.1f} s" if outcome.wall_time is not None else "?"
    if outcome.status == "completed":
        return f"{head} completed in {t}"
    return f"{head} {outcome.status}: {outcome.reason or 'no reason given'} ({t})"


def run_sweep(sweep: Sweep, force: bool = False,
              log: Callable[[str], None] = print) -> SweepReport:
    """Run every run not already completed, ``sweep.jobs`` at a time; one line per start/end."""
    runs = expand(sweep)
    n = len(runs)
    report, todo = _skip_done(sweep, runs, force, log)
    lock = threading.Lock()
    queue = list(reversed(todo))
    active = Active()

    def say(line: str) -> None:
        with lock:
            log(line)

    def work() -> None:
        while not active.cancelled.is_set():
            with lock:
                if not queue:
                    return
                run = queue.pop()
            ranks = f" on {sweep.ranks} ranks" if sweep.ranks > 1 else ""
            say(progress_line(run, n, event=f"started{ranks}"))
            try:
                outcome = execute_run(sweep, run, active)
            except OSError as exc:
                outcome = Outcome("crashed", f"ancf-sweep: {exc}", None, None)
            if outcome is None:                 # not started: the sweep is being stopped
                return
            with lock:
                report.outcomes[run.run_id] = outcome
            say(progress_line(run, n, outcome))

    # the main thread polls an Event per worker instead of Thread.join: a Ctrl-C that interrupts
    # Thread.join can leave the thread marked as finished (CPython 3.11), and the sweep would
    # then exit before the interrupted runs are recorded
    finished = [threading.Event() for _ in range(max(1, min(sweep.jobs, len(todo))) if todo else 0)]

    def worker(done: threading.Event) -> None:
        try:
            work()
        finally:
            done.set()

    for done in finished:
        threading.Thread(target=worker, args=(done,), daemon=True).start()
    try:
        _wait_all(finished)
    except KeyboardInterrupt as exc:
        # forward the signal to every run and wait for them (no ancf-solve outlives the sweep)
        report.interrupted = True
        with shielded():
            with active.lock:
                n_running = len(active.procs)
            if n_running:
                say(f"[sweep] stopping {n_running} run(s) at their next safe point "
                    "(converged levels are kept)")
            active.cancel(getattr(exc, "signum", signal.SIGINT))
            _wait_all(finished, limit=60.0)
    return report


def _skip_done(sweep: Sweep, runs: list[RunSpec], force: bool,
               log: Callable[[str], None]) -> tuple[SweepReport, list[RunSpec]]:
    """Prepare every run's directory; the report (completed runs skipped) and the runs to do."""
    os.makedirs(sweep.output, exist_ok=True)
    todo: list[RunSpec] = []
    report = SweepReport(runs, {}, [])
    for run in runs:
        done = prepare_run(sweep, run)
        if done and not force:
            report.skipped.append(run.run_id)
            log(progress_line(run, len(runs), event="skipped (already done)"))
        else:
            todo.append(run)
    return report, todo


def _wait_all(events: list[threading.Event], limit: float | None = None) -> None:
    """Until every event is set (or ``limit`` seconds), by polling: a signal stays harmless."""
    t0 = time.monotonic()
    while not all(e.is_set() for e in events):
        if limit is not None and time.monotonic() - t0 > limit:
            return
        time.sleep(0.05)
