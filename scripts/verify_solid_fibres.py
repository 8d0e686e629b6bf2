#!/usr/bin/env python3
"""A pretwisted bar with helical GOH fibres: ANCF 3363 against a 3D solid (issue 26, ``make verify-solid``).

A command line over ``ancf_verify.cli.fibres`` (its docstring: the method, the usage, what it writes);
``--help`` lists the options."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run("fibres", "verify_solid_fibres"))
