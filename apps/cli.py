"""What the command lines share: option errors in one line, and stdout that may be a closed pipe.

``Parser`` is argparse with the project's errors (``ancf-sweep: argument --jobs: expected a
positive integer; got 'x' (see ancf-sweep --help)``, exit 2, no usage block) and a help that
survives a reader gone before it is written (``ancf-fit --help | head -0``).  Progress lines go
through ``printer`` (``interrupt.SafePrinter``): once stdout is a closed pipe (``ancf-sweep S.yaml
--dry-run | head -1``) they stop quietly, the work goes on and its exit code is unchanged;
``start_petsc`` keeps PETSc's SIGPIPE handler from aborting the process meanwhile.  One-line
errors and warnings go through ``say_stderr`` (``interrupt.say_stderr``): on a stderr that is gone
(``ancf-study S.yaml 2>&1 | head -0``) the exit code stays the error's (2), not a bug's (1).
``path`` and ``positive`` are option types whose errors say what to give."""
from __future__ import annotations

import argparse
import difflib
import signal
import sys

from ancf_petsc.solving.interrupt import SafePrinter, say_stderr

__all__ = ["Parser", "at_least", "first_rank", "launch_status", "path", "positive", "printer",
           "report_unused_options", "say_stderr", "start_petsc", "started_by_mpirun"]


def printer(quiet: bool = False) -> SafePrinter:
    """``print`` to stdout, flushed, that stops quietly once stdout is a closed pipe."""
    return SafePrinter(quiet=quiet)


def first_rank() -> bool:
    """Whether this process prints what a command line says before MPI starts (help, version,
    usage errors): every process without a launcher, rank 0 alone under mpirun (``mpirun -n 3
    ancf-solve --version`` printed its line three times)."""
    from ancf_petsc.parallel.launch import launch_rank
    return launch_rank() == 0


def launch_status(status: int) -> int:
    """The exit code of a process that stops before MPI starts (a usage error, a program
    refusing mpirun): ``status`` on rank 0, which printed why, 0 on the other ranks.  Under
    mpirun a rank leaving first with 2 made mpirun kill rank 0 before it had printed its line
    (``mpirun -n 3 ancf-report --bogus``: no message, in CI); the job's code is rank 0's."""
    return status if first_rank() else 0


def path(text: str) -> str:
    """A file or directory option: an empty one is refused (``--out=`` was taken for no ``--out``)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"expected a path; got {text!r}")
    return text


def at_least(lo: int):
    """The type of an integer option >= ``lo``: counts (``--jobs``, ``--ranks``) take 1
    (``positive``), ancf-fit's ``--task`` 0."""
    what = "a positive integer" if lo == 1 else "an integer"
    bound = what if lo == 1 else f"an integer >= {lo}"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what}; got {text!r}") from None
        if value < lo:
            raise argparse.ArgumentTypeError(f"expected {bound}; got {value}")
        return value
    return parse


positive = at_least(1)


def started_by_mpirun(prog: str, how: str) -> bool:
    """Whether ``prog``, a program that starts or solves its runs itself (``how``), was started
    by mpirun/mpiexec; rank 0 then says so in one line.  Its copies ran the
    same runs into the same directories: ``mpirun -n 2 ancf-sweep`` crashed half of them, and
    the runs' own mpirun failed in the children of any launched copy.  The caller then exits
    with ``launch_status(2)``."""
    from ancf_petsc.parallel.launch import launch_rank, launch_size
    n = launch_size()
    if n and launch_rank() == 0:
        say_stderr(f"{prog}: started by mpirun ({n} process{'es' if n > 1 else ''}): {how}; "
                   "run it without mpirun")
    return n > 0


def start_petsc(petsc_args: list[str]) -> None:
    """MPI, then PETSc with these options; a write into a closed pipe is then EPIPE (which
    ``printer`` takes) instead of PETSc's SIGPIPE handler aborting the process (exit 59)."""
    from mpi4py import MPI  # noqa: F401  (before petsc4py)
    import petsc4py
    petsc4py.init([sys.argv[0]] + petsc_args)
    from petsc4py import PETSc  # noqa: F401  (PetscInitialize installs PETSc's signal handlers)
    signal.signal(signal.SIGPIPE, signal.SIG_IGN)


def report_unused_options(prog: str, solved: bool = True) -> None:
    """After in-process solves (ancf-study, ancf-fit): a PETSc option none of them read
    (misspelt: ``-snes_maxit``), one line each from rank 0 if it ``solved``, as ancf-solve
    reports it; PETSc reports instead when given -options_left.  Collective."""
    from petsc4py import PETSc

    from ancf_petsc.linalg.database import option
    from ancf_petsc.linalg.diagnostics import unused_command_line_options, unused_line
    unused = unused_command_line_options(PETSc.COMM_WORLD)
    if solved and PETSc.COMM_WORLD.rank == 0 and option("options_left") is None:
        for name in unused:
            say_stderr(unused_line(name, prog=prog))


class Parser(argparse.ArgumentParser):
    """argparse whose errors are one line and exit 2, and whose help survives a closed pipe."""

    def error(self, message: str):
        """One line naming the option (argparse prints the usage too), exit 2."""
        self.exit(2, f"{self.prog}: {message} (see {self.prog} --help)\n")

    def exit(self, status: int = 0, message: str | None = None):
        """``message`` through ``say_stderr`` (a gone stderr keeps ``status``; under mpirun from
        rank 0 alone), then exit with ``launch_status(status)``."""
        if message and first_rank():
            say_stderr(message.rstrip("\n"))
        sys.exit(launch_status(status))

    def print_help(self, file=None) -> None:
        """The help on stdout through ``printer`` (``--help | head``: no BrokenPipeError); under
        mpirun from rank 0 alone."""
        if file is not None and file is not sys.stdout:
            super().print_help(file)
            return
        if first_rank():
            printer()(self.format_help().rstrip("\n"))

    def parse_with_petsc(self, argv: list[str] | None) -> tuple[argparse.Namespace, list[str]]:
        """(our options, PETSc's): an unknown option with two dashes (``--output`` for ``--out``),
        one of ours with one dash (``-out``), a stray word or a value PETSc would refuse is an
        error (one line, exit 2), not a PETSc option left unread or blamed on a solve."""
        args, petsc = self.parse_known_args(argv)
        ours = [s for a in self._actions for s in a.option_strings if s.startswith("--")]
        for arg in petsc:
            name = arg.split("=", 1)[0]
            if name.startswith("--") and len(name) > 2:
                near = difflib.get_close_matches(name, ours, n=1, cutoff=0.7)
                hint = f"did you mean {near[0]}?" if near else "PETSc options take one dash"
                self.error(f"unknown option {name} ({hint})")
            if name.startswith("-") and "-" + name in ours and name != "-help":
                self.error(f"{name}: {self.prog}'s own options take two dashes (-{name}); "
                           "one dash is for PETSc options such as -snes_monitor")
        from ancf_petsc.config.options_files import check_all_options
        problem = check_all_options(petsc, tuple(ours))   # stray words, values, options files
        if problem:
            self.exit(2, f"{self.prog}: {problem}\n")
        return args, petsc
