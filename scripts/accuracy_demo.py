#!/usr/bin/env python3
"""``accuracy: {probe, rtol}`` on three scenes: is the tolerance met, at less cost than a fixed fine model?

A command line over ``ancf_verify.demos.accuracy_demo`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.demos.accuracy_demo import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
