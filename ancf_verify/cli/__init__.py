"""The verification's command lines, one module per command, each with ``main(argv) -> int``;
``scripts/`` holds only the thin files that call ``run``."""
from __future__ import annotations

import importlib
import os
import sys

# the solids and beams run serially: one BLAS thread (set before numpy is first imported)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

__all__ = ["run", "study_parts"]


def run(command: str, name: str, argv: list[str] | None = None) -> int:
    """``main(argv)`` of ``ancf_verify.cli.<command>``; a failure is one line on stderr (prefixed
    with ``name``, the script's name) and exit status 1; bad options exit 2 (argparse)."""
    from ..stack import SolidError
    try:
        return importlib.import_module(f"{__name__}.{command}").main(argv)
    except SolidError as exc:
        print(f"{name}: {exc}", file=sys.stderr)
    except Exception as exc:   # a failed solve deep in dolfinx or PETSc: one line, no traceback
        print(f"{name}: {type(exc).__name__}: {exc}", file=sys.stderr)
    return 1


def study_parts(prog: str, doc: str, names, argv: list[str] | None, more: str = "") -> list[str]:
    """The parts named on a study's command line (``[]``: all of them); ``--help`` prints ``doc``
    and the parts, bad options exit 2 (argparse)."""
    import argparse
    ap = argparse.ArgumentParser(prog=prog, description=doc, allow_abbrev=False,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("parts", nargs="*", help=f"some of {', '.join(names)} (default: all){more}")
    return ap.parse_args(argv).parts
