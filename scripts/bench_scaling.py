#!/usr/bin/env python3
"""Strong scaling and linear solvers on the 37-fascicle bundle (issues 4 and 16).

A command line over ``ancf_verify.bench.scaling`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.bench.scaling import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
