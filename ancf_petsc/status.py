"""How a run ends: final status, machine-readable reason code and exit code, in one place.

summary.json's ``status`` is ``running`` while a run goes on and always ends in one of
``FINAL_STATUSES``; ``reason_code`` says why (a fixed upper-case word; ``message`` is the prose).
docs/running.md documents the table below for users.
"""
from __future__ import annotations

import signal

FINAL_STATUSES = ("completed", "failed", "interrupted", "unstable")

#: exit codes of ancf-solve
EXIT_OK = 0
EXIT_BUG = 1                 # a bug (Python traceback); please report it
EXIT_INPUT = 2               # config, command line, PETSc option or file-system error (one line)
EXIT_FAILED = 3              # a load level was not reached (the converged ones are on disk)
EXIT_UNSTABLE = 4            # every level converged, but some are unstable equilibria
#: interrupted by a signal: 128 + the signal number (130 SIGINT, 143 SIGTERM)

#: reason codes beside the SNES ones (DIVERGED_LINE_SEARCH, DIVERGED_MAX_IT, ...), which a failed
#: level reports as they are
COMPLETED = "COMPLETED"
NEGATIVE_EIGENVALUES = "NEGATIVE_EIGENVALUES"
#: completed, but some levels were accepted with their contact weights unsettled
WEIGHTS_UNSETTLED = "WEIGHTS_UNSETTLED"
#: completed, after switching to a stable branch at a bifurcation (solving/branch_switch.py)
BRANCH_SWITCHED = "BRANCH_SWITCHED"
#: completed, but no rung of the accuracy ladder met its rtol: the answer's error is not known to meet
#: it (workflows/accuracy.py)
ACCURACY_NOT_MET = "ACCURACY_NOT_MET"
#: completed, with levels inside a gap of the load path reported just past it (solving/step_over.py)
LEVELS_PASSED_OVER = "LEVELS_PASSED_OVER"
OUTPUT_ERROR = "OUTPUT_ERROR"
PETSC_ERROR = "PETSC_ERROR"
INTERNAL_ERROR = "INTERNAL_ERROR"         # a bug (exit code 1, with a traceback)
CONFIG_ERROR = "CONFIG_ERROR"             # an input error before any level (exit code 2; no summary)


def signal_reason(signum: int) -> str:
    """``SIGTERM`` / ``SIGINT`` (the reason code of an interrupted run)."""
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"SIGNAL_{signum}"


def crash_status(exc: BaseException, converged: list[float]) -> tuple[str, str, str]:
    """(reason code, message, status) of a run ended by an exception that is not the solver's
    (``converged``: the load factors reached): a Ctrl-C of a Python session (KeyboardInterrupt)
    is ``interrupted`` by SIGINT, anything else a bug (``failed``, INTERNAL_ERROR)."""
    if isinstance(exc, KeyboardInterrupt):
        return (signal_reason(signal.SIGINT), "interrupted by SIGINT (KeyboardInterrupt) after load "
                f"factor {converged[-1] if converged else 0.0:g}", "interrupted")
    return INTERNAL_ERROR, f"{type(exc).__name__}: {exc}", "failed"


def exit_code(status: str, reason_code: str = "", signum: int = 0) -> int:
    """The exit code of a run that ended with ``status`` (``signum`` for interrupted runs)."""
    if reason_code == OUTPUT_ERROR:
        return EXIT_INPUT             # a file-system problem, named in one line like a config error
    if status == "completed":
        return EXIT_OK
    if status == "unstable":
        return EXIT_UNSTABLE
    if status == "interrupted":
        return 128 + signum
    return EXIT_FAILED
