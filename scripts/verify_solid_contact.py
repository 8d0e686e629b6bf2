#!/usr/bin/env python3
"""Three-subtendon Achilles tendon as a 3D solid with frictionless contact: a reference for ANCF.

A command line over ``ancf_verify.cli.contact`` (its docstring: the method, the usage, what it writes);
``--help`` lists the options."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run("contact", "verify_solid_contact"))
