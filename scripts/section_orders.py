#!/usr/bin/env python3
"""The section order as a rung (issue 42): 3363, 33103 and 33153 measured against beam theory,
the committed 3D solids and each other.

A command line over ``ancf_verify.cli.section_orders`` (its docstring: the parts, the usage);
``--help`` lists the options."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run("section_orders", "section_orders"))
