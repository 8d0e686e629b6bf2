#!/usr/bin/env python3
"""Projection of the fascicle-parallel solver to 64 ranks and a 1000-fascicle scene (issue 16).

A command line over ``ancf_verify.bench.project_scaling`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.bench.project_scaling import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
