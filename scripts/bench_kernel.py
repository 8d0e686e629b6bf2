#!/usr/bin/env python3
"""Element-kernel throughput, compiled beside numpy, and whole-run wall times (``make bench``).
A command line over ``ancf_petsc.workflows.kernel_bench`` (its docstring: what is measured).
Usage: OPENBLAS_NUM_THREADS=1 python scripts/bench_kernel.py [--elements 64] [--repeat 20]"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import apps  # noqa: E402,F401  (the programs' BLAS threads and kernels, before numpy: apps/__init__.py)
from ancf_petsc.workflows.kernel_bench import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
