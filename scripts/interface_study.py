#!/usr/bin/env python3
"""Between sliding and bonded (issue 27): the paper's tendon (psi = 45 deg, Table 1's levels) with

A command line over ``ancf_verify.studies.interface_study`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.studies.interface_study import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
