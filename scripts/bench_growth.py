#!/usr/bin/env python3
"""How the cost of a run grows with the scene (issue 16, target 1): one rank, twisted hexagonal

A command line over ``ancf_verify.bench.growth`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.bench.growth import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
