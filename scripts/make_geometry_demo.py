#!/usr/bin/env python3
"""Make the worked example of docs/geometry.md: a small labelled mask of a three-subtendon tendon

A command line over ``ancf_verify.demos.make_geometry_demo`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.demos.make_geometry_demo import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
