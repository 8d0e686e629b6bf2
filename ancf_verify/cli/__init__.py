"""The verification's command lines, one module per command, each with ``main(argv) -> int``;
``scripts/`` holds only the thin files that call ``run``."""
from __future__ import annotations

import argparse
import importlib
import math
import os
import sys

# the solids and beams run serially: one BLAS thread (set before numpy is first imported)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

__all__ = ["Parser", "count", "counts", "numbers", "out_dir", "run", "size", "sizes", "study_parts"]


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


class Parser(argparse.ArgumentParser):
    """argparse whose errors are one line naming the option (no usage block), exit 2."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: {message} (see {self.prog} --help)\n")


def size(text: str) -> float:
    """One mesh size > 0 (gmsh aborts the whole process on a size <= 0)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a mesh size > 0, e.g. 2e-3; got {text!r}") from None
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"mesh sizes must be > 0; got {text!r}")
    return value


def sizes(text: str) -> list[float]:
    """Comma-separated mesh sizes, each > 0 (``--h 2e-3,1.4e-3``)."""
    out = [size(x) for x in text.split(",") if x.strip()]
    if not out:
        raise argparse.ArgumentTypeError(f"expected mesh sizes > 0 separated by commas, e.g. 2e-3,1.4e-3; got {text!r}")
    return out


def count(text: str) -> int:
    """A count >= 1 (``--ancf-repeats``, ``--quad-degree``)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer; got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer; got {value}")
    return value


def numbers(text: str) -> list[float]:
    """Comma-separated numbers (``--psi 0,45``, ``--loads 10,20``); '' is none."""
    try:
        return [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected numbers separated by commas, e.g. 10,20; got {text!r}") from None


def counts(text: str) -> list[int]:
    """Comma-separated counts >= 1 (``--elements 4,8,16``)."""
    out = [count(x) for x in text.split(",") if x.strip()]
    if not out:
        raise argparse.ArgumentTypeError(f"expected positive integers separated by commas, e.g. 4,8; got {text!r}")
    return out


def out_dir(out: str | None, quick: bool, name: str) -> str:
    """Where a command writes: ``out`` if given, else docs/; a ``--quick`` smoke run without
    ``--out`` writes to results/<name>_quick/ (git ignores it), not over the committed references."""
    from ..paths import DOCS, ROOT
    if out:
        return out
    return os.path.join(ROOT, "results", f"{name}_quick") if quick else DOCS


def study_parts(prog: str, doc: str, names, argv: list[str] | None, more: str = "") -> list[str]:
    """The parts named on a study's command line (``[]``: all of them); ``--help`` prints ``doc``
    and the parts, bad options exit 2 (argparse)."""
    ap = argparse.ArgumentParser(prog=prog, description=doc, allow_abbrev=False,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("parts", nargs="*", help=f"some of {', '.join(names)} (default: all){more}")
    return ap.parse_args(argv).parts
