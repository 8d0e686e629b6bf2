#!/usr/bin/env python3
"""Behaviour snapshot for refactors: the paper's columns, Table 2 models and bundles, to full precision.

A command line over ``ancf_verify.demos.snapshot_results`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.demos.snapshot_results import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
