"""ancf-report: the paper's Tables 1 and 2 beside ours, the contact study and the figures.

    ancf-report                         # Table 1, Table 2 and figures into results/achilles_report
    ancf-report --table1 --ranks 2      # one study, each run on 2 MPI ranks
    ancf-report --contact --fit-bulk-modulus
    ancf-report --existing results/achilles_type3_psi45   # report on finished runs, no solving

Runs are sweeps (see ancf-sweep): finished runs are reused, so re-running is cheap.
Exit codes: 0 done, 2 bad option, configs or run directory (one line), 130 interrupted (Ctrl-C
or SIGTERM: the runs stop at their next safe point, no report is written; the same command
goes on, reusing the finished runs).
"""
from __future__ import annotations

import argparse
import os
import signal
import sys

from apps.cli import Parser, launch_status, path, positive, printer, say_stderr, started_by_mpirun

#: the configs shipped beside the command lines (a checkout or an editable install)
CONFIGS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "configs")
#: the options that choose what to solve and how: none of them applies to --existing
SOLVING = ("table1", "table2", "contact", "fit_bulk_modulus", "figures", "ranks", "jobs")


def main(argv: list[str] | None = None) -> int:
    """The ``ancf-report`` command; Ctrl-C or SIGTERM stops its runs and exits 130 (one line)."""
    from ancf_petsc.workflows.sweep.processes import raise_interrupted
    previous = signal.signal(signal.SIGTERM, raise_interrupted)   # the runs would outlive a kill
    try:
        return _main(argv)
    except KeyboardInterrupt:
        say_stderr("ancf-report: interrupted; no report written (the finished runs are kept: "
                   "run the same command to go on)")
        return 130
    finally:
        signal.signal(signal.SIGTERM, previous)


def _main(argv: list[str] | None) -> int:
    ap = Parser(prog="ancf-report", allow_abbrev=False, description=__doc__,
                formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=path, default="results/achilles_report", help="output directory")
    ap.add_argument("--ranks", type=positive, help="MPI ranks per run (default 1)")
    ap.add_argument("--jobs", type=positive, help="runs at the same time (default 1)")
    ap.add_argument("--table1", action="store_true")
    ap.add_argument("--table2", action="store_true")
    ap.add_argument("--contact", action="store_true",
                    help="contact study: Table 1 for both laws, k_s scaling (psi = 45)")
    ap.add_argument("--fit-bulk-modulus", action="store_true")
    ap.add_argument("--figures", action="store_true")
    ap.add_argument("--configs", type=path, default=CONFIGS, metavar="DIR",
                    help="the Achilles configs and data/paper_table*.csv (default: this checkout's configs/)")
    ap.add_argument("--existing", type=path, nargs="+", metavar="RUN_DIR",
                    help="finished ancf-solve output directories to report on (no solving)")
    args = ap.parse_args(argv)
    solving = [f"--{k.replace('_', '-')}" for k in SOLVING if getattr(args, k)]
    if args.existing and solving:        # they were ignored, or solved runs beside the given ones
        ap.error(f"--existing reports on finished runs and solves nothing (their figures are drawn "
                 f"anyway): leave out {', '.join(solving)}; got --existing with {', '.join(solving)}")
    args.ranks, args.jobs = args.ranks or 1, args.jobs or 1
    if started_by_mpirun("ancf-report", "it is one process that starts its runs itself (--ranks: ranks per run)"):
        return launch_status(2)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    from ancf_petsc import paper as rp
    from ancf_petsc.errors import InputError

    chosen = args.table1 or args.table2 or args.contact or args.fit_bulk_modulus or args.figures
    if not chosen and not args.existing:
        args.table1 = args.table2 = args.figures = True
    try:
        inputs = rp.PaperInputs(os.path.abspath(args.configs)).check()
        if args.existing:                # every run read before anything is written
            from ancf_petsc.paper import existing
            runs = existing.read_existing(args.existing, inputs)
    except InputError as exc:
        say_stderr(f"ancf-report: {exc}")
        return 2
    out = os.path.abspath(args.out)
    from ancf_petsc.io.files import OutputError, prepare_output_dir
    try:
        prepare_output_dir(out, "--out")
    except OutputError as exc:
        say_stderr(f"ancf-report: output error: {exc}")
        return 2
    sections = []
    heading = "Type III Achilles tendon: reproduction of Obrezkov et al. (2022)"
    log = printer()                       # ancf-report ... | head: no BrokenPipeError
    try:
        t1 = t2 = None
        drawn = []
        if args.existing:
            heading = existing.title(runs)
            sections.append(("The runs", existing.runs_markdown(runs)))
            drawn = existing.other_figures(runs, out)
            if drawn:
                sections.append(("Figures of the other runs", "\n\n".join(
                    f"![{os.path.basename(f)}]({os.path.basename(f)})" for f in drawn)))
            found = existing.paper_summaries(runs)
            left = existing.shadowed(runs)
            if left:
                sections.append(("Runs not in Table 1 (a later one has the same pretwist)", left))
            if found:
                t1 = rp.table1_from(inputs, found)
                missing = existing.levels_missing(t1, found)
                if missing:
                    sections.append(("Levels of Table 1 not reached or not asked", missing))
            args.figures = bool(found)
        if args.table1:
            t1 = rp.table1(inputs, out, args.ranks, args.jobs, log)
        if t1 is not None:
            sections.append(("Table 1: soleus elongation [mm], paper vs ours", t1.markdown()))
            sections.append(("Run time per column [s]", rp.timing_markdown(t1)))
        if args.table2:
            t2 = rp.table2(inputs, out, ranks=args.ranks, jobs=args.jobs, log=log)
            sections.append(("Table 2: soleus elongation at 400 N [mm] vs elements per subtendon",
                             rp.table2_markdown(inputs, t2)))
        if args.contact:
            t1s = t1 if t1 is not None else rp.table1(inputs, out, args.ranks, args.jobs, log)
            t1u = rp.table1(inputs, out, args.ranks, args.jobs, log, mode="unilateral")
            sections.append(("Table 1 for both contact laws", rp.laws_markdown(t1s, t1u)))
            rows = rp.scaling_study(inputs, out, ranks=args.ranks, jobs=args.jobs, log=log)
            sections.append(("No penalty in the answer: the multipliers' unit k_s over two decades",
                             rp.scaling_markdown(rows)))
        if args.fit_bulk_modulus:
            fit = rp.fit_bulk_modulus(inputs, out, jobs=args.jobs, log=log)
            sections.append(("Bulk modulus fitted to Table 1, psi = 0", rp.fit_markdown(fit)))
        if args.figures and t1 is not None:
            drawn += rp.figures(inputs, t1, out, t2, log)
        text = "\n\n".join(f"## {title}\n\n{body}" for title, body in sections)
        with open(os.path.join(out, "report.md"), "w") as fh:
            fh.write(f"# {heading}\n\n" + text + "\n")
        rp.keep_only(out, drawn, others=not args.existing)   # another run's figures are not this report's
    except InputError as exc:
        say_stderr(f"ancf-report: {exc}")
        return 2
    except OSError as exc:               # a figure or report.md not writable, a full disk
        from ancf_petsc.io.files import os_reason
        say_stderr(f"ancf-report: output error: {exc.filename or out}: {os_reason(exc)}")
        return 2
    log(text)
    log(f"\n[report] {os.path.join(out, 'report.md')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
