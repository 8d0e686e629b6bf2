#!/usr/bin/env python3
"""ANCF 3363 beams against 3D solid elements: accuracy and wall time (``make verify-solid``).

A command line over ``ancf_verify.cli.bars`` (its docstring: the method, the usage, what it writes);
``--help`` lists the options."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run("bars", "verify_solid"))
