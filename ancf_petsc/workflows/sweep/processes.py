"""The child processes of a local sweep: started only while the sweep is not being stopped, and
stopped together (signal to each run's process group, a grace period, then SIGKILL) so that no
``ancf-solve`` outlives an interrupted sweep.

Each run starts in its own session (a Ctrl-C at the terminal reaches only ``ancf-sweep``, which
forwards it): ``ancf-solve`` stops at its next safe point with its converged levels on disk and
``summary.json`` saying ``interrupted``; ``mpiexec`` passes the signal on to its ranks.
"""
from __future__ import annotations

import signal
import subprocess
import threading
import time

#: seconds a run may take to stop at its next safe point before it is killed
STOP_GRACE = 20.0
KILL_GRACE = 10.0


def _signal_group(proc: subprocess.Popen, sig: int) -> None:
    import os
    try:
        os.killpg(proc.pid, sig)
    except (ProcessLookupError, PermissionError):
        pass


def stop_processes(procs: list[subprocess.Popen], sig: int = signal.SIGTERM,
                   grace: float = STOP_GRACE) -> None:
    """Send ``sig`` to every process group, wait up to ``grace`` seconds for all of them together,
    SIGKILL the groups still running and reap them."""
    for p in procs:
        if p.poll() is None:
            _signal_group(p, sig)
    for final, wait in ((False, grace), (True, KILL_GRACE)):
        deadline = time.monotonic() + wait
        for p in procs:
            try:
                p.wait(timeout=max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                pass
        alive = [p for p in procs if p.poll() is None]
        if not alive or final:
            return
        for p in alive:
            _signal_group(p, signal.SIGKILL)


class Interrupted(KeyboardInterrupt):
    """A signal that stops the sweep (``signum``: forwarded to the runs)."""

    def __init__(self, signum: int = signal.SIGINT) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def raise_interrupted(signum: int, frame: object) -> None:
    """Signal handler: SIGTERM (kill, a job scheduler) stops the sweep like Ctrl-C."""
    raise Interrupted(signum)


class shielded:
    """While the runs are being stopped, a second Ctrl-C or SIGTERM is ignored instead of
    abandoning them half-stopped (main thread only; elsewhere a no-op)."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.previous: dict = {}

    def __enter__(self) -> "shielded":
        if threading.current_thread() is threading.main_thread():
            self.previous = {s: signal.signal(s, signal.SIG_IGN) for s in self.SIGNALS}
        return self

    def __exit__(self, *exc) -> None:
        for s, handler in self.previous.items():
            signal.signal(s, handler)


class Active:
    """The runs' processes, so that an interrupt stops every one of them; once cancelled, no
    new process starts (``start`` and ``cancel`` take the same lock)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.procs: set[subprocess.Popen] = set()
        self.cancelled = threading.Event()

    def start(self, cmd: list[str], **popen) -> subprocess.Popen | None:
        """``subprocess.Popen(cmd, start_new_session=True, **popen)``, or None once cancelled."""
        with self.lock:
            if self.cancelled.is_set():
                return None
            proc = subprocess.Popen(cmd, start_new_session=True, **popen)
            self.procs.add(proc)
            return proc

    def finished(self, proc: subprocess.Popen) -> None:
        with self.lock:
            self.procs.discard(proc)

    def cancel(self, sig: int = signal.SIGTERM, grace: float = STOP_GRACE) -> None:
        """Start no more runs; stop the running ones (``sig``, then SIGKILL after ``grace``)."""
        with self.lock:
            self.cancelled.set()
            procs = list(self.procs)
        stop_processes(procs, sig, grace)
