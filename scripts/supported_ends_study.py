#!/usr/bin/env python3
"""The pressure functions at clamped ends kept or folded (``contact.projection.supported_ends``),.

A command line over ``ancf_verify.cli.supported_ends`` (its docstring: the method, the usage, what it writes);
``--help`` lists the options."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run("supported_ends", "supported_ends_study"))
