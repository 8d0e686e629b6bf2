#!/usr/bin/env python3
"""A Newton iteration of the paper's tendon, start-up, the column and the kernel against older
checkouts (issue 40; ``make bench-iteration``; docs/parallel.md).

A command line over ``ancf_petsc.workflows.iteration_bench`` (its docstring: what is measured).
Usage: OPENBLAS_NUM_THREADS=1 python scripts/bench_iteration.py [--rounds 7] \\
           [--baseline 38a07d3=/path/to/checkout ...] [--pin 1] [--json FILE]"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_petsc.workflows.iteration_bench import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
