#!/usr/bin/env python3
"""Verification report: runs the core verification problems and prints Markdown tables.

A command line over ``ancf_verify.demos.verification_report`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.demos.verification_report import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
