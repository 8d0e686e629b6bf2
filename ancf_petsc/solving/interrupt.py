"""Clean stops on SIGTERM / SIGINT, and output that survives a closed pipe.

A signal handler only records the signal.  The load stepper asks ``stop_requested`` between
Newton solves, and the SNES monitor at every Newton iteration (snes_solver.py: mpirun kills 1 s
after forwarding a SIGTERM); it reduces the record over all ranks (an allreduce), so every rank
stops at the same safe point even when only one of them got the signal.  A second signal of either kind ends
the process at once (converged levels are on disk already; summary.json then still says running).

SIGPIPE (``ancf-solve ... | head``) is ignored: a write to the closed pipe fails with EPIPE,
``SafePrinter`` then stops printing for the rest of the run and the solve goes on; so it does when
stdout is a terminal that went away (EIO: the closed terminal or ssh session of a detached run;
the ranks of a killed mpirun, whose stdout is its pseudo-terminal, no longer end 'failed' with
INTERNAL_ERROR but as killed processes do: summary.json 'running', --restart goes on).
"""
from __future__ import annotations

import errno
import os
import signal
import sys

_pending = 0                    # the signal number received (0: none)

#: write errors that mean stdout's reader is gone for good: a closed pipe, a closed terminal
GONE = (errno.EPIPE, errno.EIO)


class RunInterrupted(Exception):
    """Raised identically on every rank when a stop was requested; ``signum`` is the signal."""

    def __init__(self, signum: int, where: str):
        self.signum = signum
        try:
            self.name = signal.Signals(signum).name
        except ValueError:
            self.name = f"signal {signum}"
        super().__init__(f"interrupted by {self.name} {where}")


def _handler(signum, frame) -> None:
    global _pending
    if _pending:
        # a second signal: the user (or scheduler) insists; stop now without cleaning up
        try:
            os.write(2, f"ancf-solve: second {signal.Signals(signum).name}: stopping at once\n".encode())
        finally:
            os._exit(128 + signum)
    _pending = signum


_previous: dict = {}


def install() -> None:
    """Handlers for SIGTERM and SIGINT (record, stop at the next safe point); SIGPIPE ignored.
    Call (again) after petsc4py.init: PETSc installs its own SIGPIPE handler, replaced here."""
    for sig, handler in ((signal.SIGTERM, _handler), (signal.SIGINT, _handler),
                         (signal.SIGPIPE, signal.SIG_IGN)):
        previous = signal.signal(sig, handler)
        _previous.setdefault(sig, previous)


def uninstall() -> None:
    """Restore the handlers found by the first ``install`` and forget any recorded signal."""
    for sig, handler in _previous.items():
        signal.signal(sig, handler if handler is not None else signal.SIG_DFL)
    _previous.clear()
    reset()


def pending() -> int:
    """This rank's recorded signal (0: none); not collective."""
    return _pending


def reset() -> None:
    global _pending
    _pending = 0


def stop_requested(comm) -> int:
    """The signal any rank received (0: none); collective over ``comm`` (a PETSc Comm)."""
    from mpi4py import MPI
    mpi = comm.tompi4py()
    if mpi.Get_size() == 1:
        return _pending
    return int(mpi.allreduce(_pending, op=MPI.MAX))


class SafePrinter:
    """``print`` to stdout that stops quietly once stdout is a closed pipe or terminal (``GONE``):
    the file descriptor is pointed at /dev/null, so PETSc's own printing (-snes_monitor) goes
    there too."""

    def __init__(self, quiet: bool = False):
        self.quiet = quiet
        self.closed = False

    def __call__(self, msg: str) -> None:
        if self.quiet or self.closed:
            return
        try:
            print(msg, flush=True)
        except OSError as exc:
            if exc.errno in GONE:
                self.close_stdout()
            else:
                raise

    def close_stdout(self) -> None:
        self.closed = True
        _to_devnull(sys.stdout)


def say_stderr(line: str) -> None:
    """One line on stderr, flushed; once stderr is a closed pipe or terminal (``GONE``:
    ``ancf-solve C.yaml 2>&1 | head -1``, a closed ssh session) it is pointed at /dev/null, so
    the run's last lines cannot turn its exit code into a bug's (1)."""
    try:
        print(line, file=sys.stderr, flush=True)
    except OSError as exc:
        if exc.errno not in GONE:
            raise
        _to_devnull(sys.stderr)


def hold_standard_streams() -> None:
    """A standard stream closed at start (``ancf-solve C.yaml >&-``, ``2>&-``): its descriptor
    pointed at /dev/null and ``sys.stdout`` / ``sys.stderr`` made a writer on it, so that lines go
    nowhere and keep the exit code, and no file the run opens takes descriptor 1 or 2 (PETSc's
    printing would go into it)."""
    for fd, name in ((1, "stdout"), (2, "stderr")):
        try:
            os.fstat(fd)
        except OSError:
            devnull = os.open(os.devnull, os.O_WRONLY)
            if devnull != fd:
                os.dup2(devnull, fd)
                os.close(devnull)
        if getattr(sys, name) is None:
            setattr(sys, name, open(fd, "w", closefd=False))


def _to_devnull(stream) -> None:
    """Point ``stream``'s file descriptor at /dev/null (what is buffered goes there too)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, stream.fileno())
        os.close(devnull)
    except OSError:
        pass
