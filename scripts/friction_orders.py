#!/usr/bin/env python3
"""The section orders against the friction solid (issue 42): tables and the inf-sup study.

A command line over ``ancf_verify.cli.friction_orders`` (its docstring: what it reads, measures
and writes); ``--help`` lists the options."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run("friction_orders", "friction_orders"))
