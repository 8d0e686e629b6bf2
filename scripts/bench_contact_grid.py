#!/usr/bin/env python3
"""Unilateral contact wherever a user takes it (issue 24): Newton iterations / cut-backs of the

A command line over ``ancf_verify.bench.contact_grid`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.bench.contact_grid import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
