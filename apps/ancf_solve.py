"""ancf-solve CONFIG.yaml [--output-dir DIR | --restart DIR] [--quiet] [PETSc options ...]
ancf-solve --check CONFIG.yaml [--output PNG]     (the model built and drawn, not solved)

Exit codes (docs/running.md): 0 completed; 2 config, command-line, PETSc-option or file-system
error (one line, no traceback); 3 a load level was not reached (every converged level is on
disk); 4 unstable (levels with negative tangent eigenvalues, see solver.allow_unstable);
130 / 143 stopped by SIGINT / SIGTERM at the next safe point (converged levels kept); 1 a bug.
"""
from __future__ import annotations

import argparse
import difflib
import os
import sys

from ancf_petsc.parallel.launch import launch_rank
from ancf_petsc.solving.interrupt import say_stderr
from apps.cli import Parser, first_rank, path

OPTIONS = ("--output-dir", "--restart", "--quiet", "--version", "--help", "--check", "--output")


def _split_argv(argv: list[str]) -> tuple[list[str], list[str], str | None]:
    """(ours, PETSc's, error): PETSc's ``-help`` goes to PETSc (argparse would take it for -h),
    and a double-dash option we do not know is an error, not a PETSc option (``--outputdir``)."""
    ours, petsc = [], []
    for arg in argv:
        if arg == "-help":
            petsc.append(arg)
            continue
        if arg.startswith("-") and not arg.startswith("--") and len(arg) > 1:
            # one of the program's own options written with one dash would go to PETSc, and a
            # restart meant for DIR would start afresh: refuse it before anything is written
            name = arg[1:].split("=", 1)[0].replace("_", "-")
            if "--" + name in OPTIONS:
                return [], [], (f"{arg.split('=', 1)[0]}: ancf-solve's own options take two dashes "
                                f"(--{name}); one dash is for PETSc options such as -snes_monitor")
        if arg.startswith("--") and len(arg) > 2:
            name = arg.split("=", 1)[0]
            if name not in OPTIONS and name != "--":
                near = difflib.get_close_matches(name, OPTIONS, n=1, cutoff=0.6)
                hint = f"; did you mean {near[0]}?" if near else f"; ancf-solve knows {', '.join(OPTIONS)}"
                return [], [], (f"unknown option {name}{hint} (PETSc options take one dash, "
                                "e.g. -snes_monitor)")
        ours.append(arg)
    return ours, petsc, None


def _parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="ancf-solve", allow_abbrev=False,
        description="Solve an ANCF continuum-beam model described by a YAML config. "
                    "Options with one dash (-snes_*, -ksp_*, -pc_*, -log_view, -help) go to PETSc.",
        epilog="Exit codes: 0 completed, 2 input or file-system error, 3 a load level not "
               "reached, 4 unstable levels, 130/143 interrupted (SIGINT/SIGTERM). See docs/running.md.")
    parser.add_argument("config", type=path, help="YAML model description")
    parser.add_argument("--output-dir", help="override output.dir of the config")
    parser.add_argument("--restart", metavar="DIR",
                        help="continue the run in DIR (its output directory) from its last "
                             "converged level; the config must describe the same model")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    parser.add_argument("--version", action="store_true", help="print the version and exit")
    parser.add_argument("--check", action="store_true",
                        help="build the model without solving: print each beam's area and centroid "
                             "and each shared border's length, draw the sections, borders, contact "
                             "interfaces and twist axis (docs/geometry.md)")
    parser.add_argument("--output", metavar="PNG",
                        help="with --check: the picture (default: OUTPUT_DIR/geometry.png)")
    return parser


def _error(line: str, rank: int | None = None) -> None:
    """One line on stderr from rank 0 (before MPI starts: the launcher's rank 0)."""
    if (launch_rank() if rank is None else rank) == 0:
        say_stderr(f"ancf-solve: {line}")


def main(argv: list[str] | None = None, hold_signals: bool = False) -> int:
    """``ancf-solve`` with ``argv``; the exit code.  ``hold_signals``: keep the SIGTERM/SIGINT
    handlers when it returns (``cli``: until the process is gone), else the caller's are back."""
    argv = sys.argv[1:] if argv is None else argv
    from ancf_petsc.solving import interrupt
    interrupt.install()                  # from the start: Ctrl-C is a clean stop, never a traceback
    try:
        code = _main(argv, interrupt)
    finally:
        if not hold_signals:
            interrupt.uninstall()        # back to the caller's handlers (main() called in-process)
    try:
        sys.stdout.flush()
    except OSError:                      # stdout was a pipe that closed (ancf-solve ... | head)
        interrupt.SafePrinter().close_stdout()
    return code


def _main(argv: list[str], interrupt) -> int:
    ours, petsc_help, problem = _split_argv(argv)
    if problem:
        _error(problem)
        return 2
    if "--version" in ours:
        from ancf_petsc.version import version_line
        interrupt.SafePrinter(quiet=not first_rank())(version_line())
        return 0
    parser = _parser()
    if petsc_help and not [a for a in ours if not a.startswith("-")]:
        say = interrupt.SafePrinter(quiet=not first_rank())   # -help | head: no BrokenPipeError
        say(parser.format_help() + "\nPETSc's own options are listed by running a model: "
                                    "ancf-solve CONFIG.yaml -help")
        return 0
    try:                                 # usage errors and --help from rank 0 only (Parser)
        args, petsc_args = parser.parse_known_args(ours)
    except SystemExit as exc:            # argparse already printed its one-line usage error
        return 2 if exc.code else 0
    for name in ("output_dir", "restart"):
        if getattr(args, name) == "":    # else silently the config's output.dir
            _error(f"--{name.replace('_', '-')}: an empty path; give a directory")
            return 2
    petsc_args = petsc_help + petsc_args
    from ancf_petsc.config.options_files import check_all_options
    problem = check_all_options(petsc_args, OPTIONS)   # command line, options files, PETSC_OPTIONS
    if problem:
        _error(problem)
        return 2
    if args.check or args.output:
        return _check(args, interrupt.SafePrinter(quiet=args.quiet))
    if petsc_help:
        # PETSc prints its help during PetscInitialize, under its own SIGPIPE handler (which
        # aborts): without PETSc's handlers, `ancf-solve CONFIG -help | head` ends quietly
        petsc_args.append("-no_signal_handler")
    from ancf_petsc.parallel.launch import prepare_environment
    prepare_environment()               # BLAS threads, Open MPI's layer for a singleton

    from mpi4py import MPI  # noqa: F401  (MPI before PETSc)
    import petsc4py
    try:
        petsc4py.init([sys.argv[0]] + petsc_args)
    except Exception:                    # PETSc printed its reason (a case the checks above miss)
        _error("PETSc did not start with these options (PETSc's reason is above)")
        return 2
    from petsc4py import PETSc

    from ancf_petsc.config.values import ConfigError
    from ancf_petsc.config.parse import load_config
    from ancf_petsc.io.files import OutputError
    from ancf_petsc.linalg.database import option
    from ancf_petsc.linalg.diagnostics import unused_line
    from ancf_petsc.api import solve
    from ancf_petsc.linalg.options import SolverOptionError
    from ancf_petsc.parallel.launch import freeze_imports
    freeze_imports()

    interrupt.install()                  # again: PETSc installed its own SIGPIPE handler
    comm = PETSc.COMM_WORLD
    rank = comm.rank
    printer = interrupt.SafePrinter(quiet=args.quiet)
    try:
        spec = load_config(args.config)
        if args.output_dir:
            spec.output.dir = args.output_dir
        if args.restart and args.output_dir and os.path.abspath(args.output_dir) != os.path.abspath(args.restart):
            _error("--restart DIR writes into DIR; leave out --output-dir", rank)
            return 2
        result = solve(spec, comm, printer, restart=args.restart)
    except SolverOptionError as exc:
        _error(str(exc), rank)
        return 2
    except ConfigError as exc:
        _error(f"config error: {exc}", rank)
        return 2
    except OutputError as exc:
        _error(f"output error: {exc}", rank)
        return 2
    except Exception:
        # a bug, not a user error: show it, and never leave the other ranks waiting
        import traceback
        traceback.print_exc()
        sys.stderr.flush()
        if comm.size > 1:
            comm.tompi4py().Abort(1)
        return 1
    if rank == 0:
        if option("options_left") is None:   # else PETSc reports (or was told not to)
            for name in result.unused_options:
                source = "config" if name.startswith("petsc.") else ""
                option = "-" + name[len("petsc."):] if source else name
                say_stderr(unused_line(option, source, prefix=spec.solver.options_prefix))
        for note in (result.summary or {}).get("warnings", []):   # e.g. a first level strained > 50 %
            say_stderr(f"ancf-solve: {note}")
        if result.status == "unstable":
            _error(f"unstable: {result.message}; results in {spec.output.dir}")
        elif result.status == "interrupted":
            n = len(result.records)
            _error(f"{result.message}; {n} converged level(s) kept in {spec.output.dir}")
        elif result.status != "completed":
            _error(f"{result.message}; converged steps are in {spec.output.dir}")
    return result.exit_code


def _check(args, say) -> int:
    """--check: the model built and drawn on rank 0, no PETSc and no solve; every rank exits
    with rank 0's code."""
    if not args.check:
        _error("--output PNG names the picture of --check; the results directory is --output-dir")
        return 2
    if args.restart:
        _error("--check builds the model only; leave out --restart")
        return 2
    if args.output is not None and not args.output.lower().endswith(".png"):
        _error(f"--output {args.output}: the picture is a PNG; give a file name ending in .png")
        return 2
    from ancf_petsc.parallel.launch import prepare_environment
    prepare_environment()
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    code = _check_model(args, say) if comm.rank == 0 else None
    return comm.bcast(code, root=0) if comm.size > 1 else code


def _check_model(args, say) -> int:
    from ancf_petsc.config.parse import load_config
    from ancf_petsc.errors import InputError
    from ancf_petsc.io.files import OutputError, os_reason, prepare_output_dir
    png = args.output
    try:
        spec = load_config(args.config)
        if args.output_dir:
            spec.output.dir = args.output_dir
        if png is None:
            prepare_output_dir(spec.output.dir)
            png = os.path.join(spec.output.dir, "geometry.png")
        from ancf_petsc.viz.geometry_check import check_geometry
        lines = check_geometry(spec, png)
    except InputError as exc:
        _error(f"config error: {exc}")
        return 2
    except OutputError as exc:
        _error(f"output error: {exc}")
        return 2
    except OSError as exc:
        _error(f"--output {png}: cannot write the picture: {os_reason(exc)}")
        return 2
    except Exception:                    # a bug: shown, and the other ranks not left waiting
        import traceback
        traceback.print_exc()
        sys.stderr.flush()
        from mpi4py import MPI
        if MPI.COMM_WORLD.size > 1:
            MPI.COMM_WORLD.Abort(1)
        return 1
    say(f"[ancf] check {spec.name}: {len(spec.beams)} beam(s), L = {spec.length:g} m, model built, "
        "not solved")
    for line in lines:
        say("[ancf]   " + line)
    say(f"[ancf] picture: {png}")
    return 0


def cli() -> None:
    """The ``ancf-solve`` command: ``main`` and a quick process exit (``launch.exit_process``);
    an exception ``main`` lets through (a bug) ends the ordinary way, with its traceback.  The
    signal handlers stay through PETSc's and MPI's finalize: a SIGTERM/SIGINT there (a time
    limit as the run ends) keeps the run's exit code; a second one ends the process at once."""
    code = main(hold_signals=True)
    from ancf_petsc.parallel.launch import exit_process
    exit_process(code)


if __name__ == "__main__":
    cli()
