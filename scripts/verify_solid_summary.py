#!/usr/bin/env python3
"""Every 3D-solid reference in one table, after re-solving each on its coarsest mesh (``make verify-solid``).

A command line over ``ancf_verify.cli.summary`` (its docstring: the method, the usage, what it writes);
``--help`` lists the options."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run("summary", "verify_solid_summary"))
