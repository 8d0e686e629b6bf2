#!/usr/bin/env python3
"""Contact benchmark (issue 13): Newton iterations, cut-backs and wall time of the Table 1 columns.

A command line over ``ancf_verify.bench.contact`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.bench.contact import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
