#!/usr/bin/env python3
"""Three-subtendon Achilles tendon with Coulomb friction: 3D solid reference against ANCF (issue 27).

A command line over ``ancf_verify.cli.friction`` (its docstring: the method, the usage, what it writes);
``--help`` lists the options."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run("friction", "verify_solid_friction"))
