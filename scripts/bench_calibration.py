#!/usr/bin/env python3
"""Calibration throughput (issue 28): solves of the Achilles column per minute, and the twin.

A command line over ``ancf_verify.bench.calibration`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.bench.calibration import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
