#!/usr/bin/env python3
"""Memory of many solves in one process (issue 15): a study must not grow with the models it solves.

A command line over ``ancf_verify.bench.memory`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.bench.memory import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
