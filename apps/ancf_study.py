"""ancf-study: speed–accuracy studies and stability maps of a model.

    ancf-study configs/studies/bending_pareto.yaml       # wall time vs error, Pareto chart
    ancf-study configs/studies/bending_stability.yaml    # converged/failed map, stability chart
    ancf-study STUDY.yaml --out DIR                       # results elsewhere

The study file's ``kind`` (pareto | stability) chooses the study; see ancf_petsc/workflows/study.py and
ancf_petsc/workflows/stability.py for the keys.  Runs are solved in this process, one after another, on
one core.  Exit codes: 0 done, 2 study-file error, 130 interrupted by Ctrl-C (one line; the
run being solved is kept as interrupted, the study's CSV and chart are not written).
"""
from __future__ import annotations

import argparse
import os
import sys

from apps.cli import (Parser, launch_status, path, printer, report_unused_options, say_stderr,
                      start_petsc, started_by_mpirun)


def main(argv: list[str] | None = None) -> int:
    ap = Parser(prog="ancf-study", allow_abbrev=False, description=__doc__,
                formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", type=path, help="study file (YAML)")
    ap.add_argument("--out", type=path, help="output directory (default: the study file's 'output')")
    args, petsc_args = ap.parse_with_petsc(argv)
    if started_by_mpirun("ancf-study", "it is one process that solves its runs one after another"):
        return launch_status(2)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    start_petsc(petsc_args)

    from ancf_petsc.io.files import OutputError
    from ancf_petsc.workflows.study import StudyError, read_yaml
    log = printer()                       # ancf-study ... | head: no BrokenPipeError
    try:
        doc = read_yaml(args.study)
        kind = doc.get("kind", "pareto") if isinstance(doc, dict) else "pareto"
        if kind == "pareto":
            from ancf_petsc.workflows.study import load_study, run_study
            spec = load_study(args.study)
            if args.out:
                spec.output = os.path.abspath(args.out)
            run_study(spec, log)
        elif kind == "stability":
            from ancf_petsc.workflows.stability import load_stability, run_stability
            spec = load_stability(args.study)
            if args.out:
                spec.output = os.path.abspath(args.out)
            run_stability(spec, log)
        else:
            raise StudyError("kind", f"must be pareto or stability; got {kind!r}")
    except StudyError as exc:
        say_stderr(f"ancf-study: {args.study}: {exc}")
        return 2
    except OutputError as exc:
        say_stderr(f"ancf-study: output error: {exc}")
        return 2
    except KeyboardInterrupt:
        say_stderr("ancf-study: interrupted (Ctrl-C); no study.csv written: run the same command "
                   "to start it again")
        return 130
    report_unused_options("ancf-study")
    return 0


if __name__ == "__main__":
    sys.exit(main())
