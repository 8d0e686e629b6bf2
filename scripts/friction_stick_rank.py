#!/usr/bin/env python3
"""Why large mu is hard on the tendon (issue 27): exact stick repeats the supports at the roots.

A command line over ``ancf_verify.studies.friction_stick_rank`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.studies.friction_stick_rank import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
