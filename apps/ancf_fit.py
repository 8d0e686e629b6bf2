"""ancf-fit FIT.yaml [--fresh] [--out DIR] [--quiet] [--task K | --slurm [--ranks N] | --collect]
        [PETSc options ...]

Fits config values of a model (any key path: material parameters, ...) to measured data and says
what the data determine: the optimum, standard errors, correlations, profiles and a verdict per
parameter (docs/calibration.md).  Every sample is solved in this process (the model built once,
warm-started from nearby solved parameter sets) and logged in <output>/samples.jsonl; a stopped
calibration started again resumes from that log.  Under ``mpirun -n N`` the samples are spread
over the ranks (the same answer as one rank).

  --task K    run start K of a multi-start fit only (optimizer.starts), into <output>/starts/K
  --slurm     write <output>/fit.slurm: a SLURM job array with one task per start
  --collect   after the array: take every start's log, pick the best, analyse and report

Exit codes: 0 done, 1 a bug (traceback), 2 bad fit file or option (one line naming the key and
the fix), 130/143 stopped by SIGINT/SIGTERM (every sample so far is in the log: run again to go on).
"""
from __future__ import annotations

import argparse
import os
import sys

from apps.cli import Parser, at_least, path, positive, printer, report_unused_options, say_stderr, start_petsc

PROG = "ancf-fit"


#: --task: a non-negative integer
_count = at_least(0)


def _args(argv: list[str]):
    ap = Parser(prog=PROG, allow_abbrev=False, description=__doc__,
                formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("fit", type=path, help="fit file (YAML)")
    ap.add_argument("--out", type=path, help="output directory (default: the fit file's output)")
    ap.add_argument("--fresh", action="store_true", help="start over: ignore (and replace) the log")
    ap.add_argument("--quiet", action="store_true", help="no progress lines")
    what = ap.add_mutually_exclusive_group()
    what.add_argument("--task", type=_count, help="one start of a multi-start fit (a SLURM array task)")
    what.add_argument("--slurm", action="store_true", help="write <output>/fit.slurm and stop")
    what.add_argument("--collect", action="store_true", help="gather the starts' logs, then analyse")
    ap.add_argument("--ranks", type=positive, help="MPI ranks per array task (with --slurm)")
    args, petsc = ap.parse_with_petsc(argv)
    if args.ranks is not None and not args.slurm:    # else a fit on one rank, --ranks unread
        ap.error(f"--ranks {args.ranks}: sets the ranks of --slurm's array tasks; to solve here "
                 f"on {args.ranks} ranks, run mpirun -n {args.ranks} {PROG} {args.fit}")
    if args.fresh and (args.slurm or args.collect):   # else unread by the tasks, or the merged logs dropped
        ap.error("--fresh: " + ("the array's tasks go on from their logs, <output>/starts/K: remove those "
                                "to start over" if args.slurm else "--collect would drop the logs it "
                                "gathers and solve the fit here again: leave it out"))
    args.ranks = args.ranks or 1
    return args, petsc


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    try:
        args, petsc_args = _args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    start_petsc(petsc_args)
    from ancf_petsc.solving import interrupt
    from ancf_petsc.solving.spread import world
    from ancf_petsc.errors import InputError
    from ancf_petsc.io.files import OutputError, prepare_output_dir
    from ancf_petsc.workflows.calibration import CalibrationInterrupted, load_fit

    interrupt.install()
    rank = world()[0]
    say = printer(quiet=args.quiet or rank != 0)     # ancf-fit ... | head: no BrokenPipeError
    log_path = "samples.jsonl"
    try:
        spec = load_fit(args.fit)
        if args.out:
            spec.output = os.path.abspath(args.out)
        log_path = os.path.join(spec.output, "samples.jsonl")
        prepare_output_dir(spec.output, "output / --out")   # every rank: a file in the way fails them all alike
        return _run(spec, args, say)
    except InputError as exc:
        if rank == 0:
            say_stderr(f"{PROG}: {args.fit}: {exc}")
        return 2
    except OutputError as exc:
        if rank == 0:
            say_stderr(f"{PROG}: output error: {exc}")
        return 2
    except CalibrationInterrupted as exc:
        if rank == 0:
            say_stderr(f"{PROG}: interrupted (signal {exc.signum}); every sample so far is in "
                       f"{log_path}: run the same command to go on")
        return 128 + exc.signum
    finally:
        interrupt.uninstall()            # back to the caller's handlers (main() called in-process)


def _run(spec, args, say) -> int:
    from ancf_petsc.workflows.calibration.calibrate import run_calibration
    from ancf_petsc.workflows.calibration.errors import expect
    from ancf_petsc.workflows.calibration.report import write_report
    from ancf_petsc.workflows.calibration.slurm import merge_starts, write_slurm

    starts = spec.optimizer.starts
    if args.slurm:
        script = write_slurm(spec, args.fit, args.ranks)
        say(f"[fit] wrote {script}: submit with cd {spec.output} && sbatch fit.slurm, "
            f"then {PROG} {args.fit} --collect")
        return 0
    if args.task is not None:
        expect(0 <= args.task < starts, "optimizer.starts",
               f"--task {args.task} is not a start of this fit (starts: {starts}, tasks 0-{starts - 1})")
    if args.collect:
        from ancf_petsc.solving.spread import agree, world
        added = agree(merge_starts(spec) if world()[0] == 0 else None)
        say(f"[fit] {added} sample(s) taken from the starts' logs")
    res = run_calibration(spec, fresh=args.fresh, task=args.task, say=say, write=write_report)
    for p in res.parameters:
        say(f"[fit] {p.name} = {p.value:.6g} ± {p.se:.3g} (95 %: [{p.interval[0]:.4g}, "
            f"{p.interval[1]:.4g}]): {p.verdict} ({p.reason})")
    tp = res.throughput
    rate = 60.0 * tp["solved_now"] / tp["solve_time"] if tp["solve_time"] > 0 else 0.0
    say(f"[fit] {tp['samples']} samples ({tp['resumed']} from the log, {tp['solved_now']} solved: "
        f"{rate:.0f} per minute of solving); {res.wall_time:.1f} s; results in {res.output}")
    report_unused_options(PROG, solved=tp["solved_now"] > 0)    # none solved: none could read them
    return 0


def cli() -> None:
    sys.exit(main())


if __name__ == "__main__":
    cli()
