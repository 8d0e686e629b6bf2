"""Frames per second of the walking stride (issue 38) by elements, contact law and material, and
against a commit without load histories (--before OTHER/.venv/bin/ancf-solve): apps/stride_bench.py.

    python scripts/bench_stride.py --before /work/base38/.venv/bin/ancf-solve --repeats 2
"""
import sys

from apps.stride_bench import main

if __name__ == "__main__":
    sys.exit(main())
