#!/usr/bin/env python3
"""What limits the ANCF sliding columns against the 3D solid with contact (issue 24, point 3):.

A command line over ``ancf_verify.cli.contact_variants`` (its docstring: the method, the usage, what it writes);
``--help`` lists the options."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run("contact_variants", "solid_contact_variants"))
