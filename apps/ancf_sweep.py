"""ancf-sweep SWEEP.yaml [--dry-run] [--slurm] [--collect] [--jobs N] [--ranks N] [--force]
                  [--throttle N] [--cpus-per-task N] [--mem M] [--time T] [--partition P]
                  [--account A] [--venv DIR] [--logs append|numbered]

Runs a parameter sweep over a base config (format: ancf_petsc/workflows/sweep/__init__.py), locally with N
concurrent ancf-solve processes, or writes a SLURM job-array script (resources from the sweep
file's ``slurm:`` or the options above; docs/running.md). Completed runs are skipped.
Exit codes (docs/running.md, "Sweeps run locally"): 0 all runs completed, 1 some did not (or a
file-system error of the sweep), 2 bad sweep file or option (one line, no traceback), 130
interrupted (the runs are stopped at their next safe point and recorded as interrupted).
"""
from __future__ import annotations

import os
import shlex
import signal
import sys

from apps.cli import Parser, launch_status, path, positive, printer, say_stderr, started_by_mpirun

#: the options of --slurm's script (the sweep file's slurm: keys)
SLURM_OPTIONS = ("throttle", "cpus_per_task", "mem", "time", "partition", "account", "venv", "logs")


def main(argv: list[str] | None = None) -> int:
    """The ``ancf-sweep`` command; a Ctrl-C at any point (also while importing) exits 130."""
    try:
        return _main(sys.argv[1:] if argv is None else argv)
    except KeyboardInterrupt:
        say_stderr("ancf-sweep: interrupted")
        return 130


def _main(argv: list[str]) -> int:
    parser = Parser(
        prog="ancf-sweep", allow_abbrev=False,
        epilog="Exit codes: 0 all runs completed, 1 some did not, 2 bad sweep file or option, "
               "130 interrupted. See docs/running.md.",
        description="Run ancf-solve over a grid or list of parameter values of a base config, "
                    "then collect every run into <output>/results.csv and <output>/failed.txt.")
    parser.add_argument("sweep", type=path, help="sweep file (YAML: base, parameters, mode, run, output, name)")
    what = parser.add_mutually_exclusive_group()
    what.add_argument("--dry-run", action="store_true",
                      help="list the runs (and which are already done); write nothing")
    what.add_argument("--slurm", action="store_true",
                      help="prepare the run directories and write <output>/sweep.slurm "
                           "(a job array) and runs.txt instead of running")
    what.add_argument("--collect", action="store_true",
                      help="only collect results.csv and failed.txt (also of a partial sweep)")
    parser.add_argument("--jobs", type=positive, help="concurrent runs (overrides run.jobs)")
    parser.add_argument("--ranks", type=positive, help="MPI ranks per run (overrides run.ranks)")
    parser.add_argument("--force", action="store_true", help="rerun runs that already completed")
    slurm = parser.add_argument_group("SLURM (with --slurm; override the sweep file's slurm:)")
    slurm.add_argument("--throttle", type=positive,
                       help="most array tasks running at once (--array=0-N%%T; not run.jobs)")
    slurm.add_argument("--cpus-per-task", type=positive, help="#SBATCH --cpus-per-task")
    slurm.add_argument("--mem", help="#SBATCH --mem (e.g. 4G)")
    slurm.add_argument("--time", help="#SBATCH --time (e.g. 02:00:00; default run.timeout + 2 min)")
    slurm.add_argument("--partition", help="#SBATCH --partition")
    slurm.add_argument("--account", help="#SBATCH --account")
    slurm.add_argument("--venv", help="environment with ancf-solve on the compute nodes "
                                      "(default: the one running ancf-sweep; ANCF_VENV at submission wins)")
    slurm.add_argument("--logs", choices=("append", "numbered"),
                       help="log.txt of a resubmitted task: appended (default) or log.N.txt")
    args, extra = parser.parse_known_args(argv)
    petsc = [a for a in extra if a.startswith("-") and not a.startswith("--")]
    if petsc:                             # the runs' PETSc options come from the sweep file
        parser.error(f"{petsc[0]}: PETSc options of the runs go in the sweep file's run.petsc, "
                     f'e.g. run: {{petsc: ["-snes_max_it", "30"]}}')
    if extra:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    if started_by_mpirun("ancf-sweep", "it is one process that starts its runs itself (run.ranks: ranks per run)"):
        return launch_status(2)
    unread = [k for k in ("jobs", "ranks", "force") if args.collect and getattr(args, k)]
    if unread or (args.slurm and args.jobs):   # else ignored: --collect runs nothing
        parser.error(f"--{(unread or ['jobs'])[0]}: " + ("--collect only reads the runs' outputs: leave it out"
                     if unread else "the local runs at once; the array's tasks at once are --throttle"))
    given = [k for k in SLURM_OPTIONS if getattr(args, k) is not None]
    if given and not args.slurm:          # else unread: a local run, --dry-run or --collect
        parser.error(f"--{given[0].replace('_', '-')}: a SLURM option, for the script of --slurm; "
                     + ("the runs at once here are --jobs" if given[0] == "throttle" else
                        "add --slurm, or leave it out"))

    from ancf_petsc.workflows.sweep import (FAILED_STATUSES, SweepError, check_values, collect, expand, is_done,
        load_sweep, run_sweep, slurm_spec, write_slurm)

    say = printer()                       # ancf-sweep ... --dry-run | head: no BrokenPipeError

    try:
        overrides = {}
        for key in SLURM_OPTIONS:
            value = getattr(args, key)
            if value is not None:
                try:
                    overrides[key] = getattr(slurm_spec({key: value}, os.getcwd()), key)
                except SweepError as exc:
                    raise SweepError("--" + key.replace("_", "-"), exc.message) from None
        sweep = load_sweep(args.sweep).with_overrides(jobs=args.jobs, ranks=args.ranks, **overrides)
        runs = expand(sweep)
        if not args.collect:              # a sweep already run is collected as it ran
            check_values(sweep, runs)
    except SweepError as exc:
        say_stderr(f"ancf-sweep: {args.sweep}: {exc}")
        return 2
    say(f"[sweep] {sweep.name}: {len(runs)} runs ({sweep.shape()}) of {sweep.base}; "
        f"{sweep.ranks} rank(s) per run, {sweep.jobs} at a time; output {sweep.output}")

    try:
        if args.dry_run:
            width = max(len(r.run_id) for r in runs)
            n_done = 0
            for r in runs:
                done = is_done(sweep, r)
                n_done += done
                values = "  ".join(f"{k}={v!r}" for k, v in r.params.items())
                say(f"  {r.run_id:<{width}}  {'done' if done else 'todo'}  {values}")
            say(f"[sweep] dry run: {len(runs) - n_done} to run, {n_done} already done")
            return 0
        if args.collect:
            col = collect(sweep)
            say(f"[sweep] {col.summary_line()}")
            say(f"[sweep] results: {col.csv_path}")
            if any(s.status in FAILED_STATUSES + ("missing",) for s in col.states):
                say(f"[sweep] failed or missing runs and reasons: {col.failed_path}")
            return 0 if col.all_completed() else 1
        if args.slurm:
            script, runs_txt = write_slurm(sweep, force=args.force)
            say(f"[sweep] wrote {script} (array 0-{len(runs) - 1}) and {runs_txt}")
            q = shlex.quote               # commands to paste: a directory may hold a blank
            say(f"[sweep] submit: cd {q(os.path.dirname(script))} && sbatch sweep.slurm "
                "(every path in it is relative to that directory)")
            say(f"[sweep] afterwards: ancf-sweep {q(args.sweep)} --collect")
            return 0

        # SIGTERM (kill, a job scheduler) stops the runs like Ctrl-C: they run in their own
        # sessions and would otherwise outlive the sweep; the signal is forwarded to them
        from ancf_petsc.workflows.sweep.processes import raise_interrupted
        previous = signal.signal(signal.SIGTERM, raise_interrupted)
        try:
            report = run_sweep(sweep, force=args.force, log=say)
        finally:
            signal.signal(signal.SIGTERM, previous)
        col = collect(sweep)
        if report.interrupted:
            say(f"[sweep] interrupted: {report.summary_line()}")
        else:
            say(f"[sweep] {report.summary_line()}")
        say(f"[sweep] results: {col.csv_path}")
        if any(s.status in FAILED_STATUSES for s in col.states):
            say(f"[sweep] failed runs and reasons: {col.failed_path}")
        if report.interrupted:
            return 130
        return 0 if report.ok() and col.all_completed() else 1
    except OSError as exc:
        where = f": {exc.filename}" if exc.filename else ""
        say_stderr(f"ancf-sweep: {exc.strerror or exc}{where}")
        return 1
    except KeyboardInterrupt:
        say_stderr("ancf-sweep: interrupted")
        return 130


if __name__ == "__main__":
    sys.exit(main())
