#!/usr/bin/env python3
"""Build the package's Cython modules in place (run by scripts/setup.sh; quick when current).

A command line over ``ancf_petsc.native.build`` (its docstring: what is built, when and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_petsc.native import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
