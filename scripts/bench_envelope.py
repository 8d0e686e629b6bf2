"""The gait envelope (issue 38): the three subtendons over twist x bias x law x material x mesh,
Newton iterations, cut-backs and failures per cell, against the targets (apps/envelope.py).

    python scripts/bench_envelope.py --grid core --jobs 2 [--before OTHER/.venv/bin/ancf-solve]
    python scripts/bench_envelope.py --grid strides --twists 0,90,180
"""
import sys

from apps.envelope import main

if __name__ == "__main__":
    sys.exit(main())
