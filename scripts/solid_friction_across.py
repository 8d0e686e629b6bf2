#!/usr/bin/env python3
"""The contact pressure ACROSS each interface, 3D solid against beams (issue 27, the friction gap).

A command line over ``ancf_verify.cli.friction_across`` (its docstring: the method, the usage, what it writes);
``--help`` lists the options."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run("friction_across", "solid_friction_across"))
