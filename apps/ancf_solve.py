"""ancf-solve CONFIG.yaml [--output-dir DIR] [PETSc options ...]

Exit codes: 0 solved, 2 config error (one line, no traceback), 3 a load level was not reached
(every converged level is already on disk).
"""
from __future__ import annotations

import argparse
import os
import sys


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(
        prog="ancf-solve", allow_abbrev=False,
        description="Solve an ANCF continuum-beam model described by a YAML config. "
                    "Unrecognised options (-snes_*, -ksp_*, -pc_*, -log_view, ...) go to PETSc.")
    parser.add_argument("config", help="YAML model description")
    parser.add_argument("--output-dir", help="override output.dir of the config")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    args, petsc_args = parser.parse_known_args(argv)
    from ancf_petsc.launch import prepare_environment
    prepare_environment()

    from mpi4py import MPI  # noqa: F401  (MPI before PETSc)
    import petsc4py
    petsc4py.init([sys.argv[0]] + petsc_args)
    from petsc4py import PETSc

    from ancf_petsc.config import ConfigError, load_config
    from ancf_petsc.run import solve

    comm = PETSc.COMM_WORLD
    log = (lambda *_: None) if args.quiet else (lambda msg: print(msg, flush=True))
    try:
        spec = load_config(args.config)
        if args.output_dir:
            spec.output.dir = args.output_dir
        result = solve(spec, comm, log)
    except ConfigError as exc:
        if comm.rank == 0:
            print(f"ancf-solve: config error: {exc}", file=sys.stderr, flush=True)
        return 2
    except Exception:
        # a bug, not a user error: show it, and never leave the other ranks waiting
        import traceback
        traceback.print_exc()
        sys.stderr.flush()
        if comm.size > 1:
            comm.tompi4py().Abort(1)
        return 1
    if result.status != "completed":
        if comm.rank == 0:
            print(f"ancf-solve: {result.message}; converged steps are in {spec.output.dir}",
                  file=sys.stderr, flush=True)
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
