#!/usr/bin/env python3
"""A soft-matrix GOH bar against the 3D solid: end traction and point force on r (issue 26).

A command line over ``ancf_verify.cli.soft_matrix`` (its docstring: the method, the usage, what it writes);
``--help`` lists the options."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run("soft_matrix", "verify_solid_soft_matrix"))
