#!/usr/bin/env python3
"""Build the package's Cython modules (``ancf_petsc/**/*.pyx``) in place; run by scripts/setup.sh.
A command line over ``ancf_petsc.native.build`` (only stale modules are rebuilt)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_petsc.native import build  # noqa: E402

if __name__ == "__main__":
    sys.exit(build())
