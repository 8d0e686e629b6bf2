#!/usr/bin/env python3
"""Set-up cost of the support check (``ancf_petsc/solving/supports.py``) against the scene size:

A command line over ``ancf_verify.bench.support_check`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.bench.support_check import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
