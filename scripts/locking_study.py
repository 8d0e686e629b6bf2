#!/usr/bin/env python3
"""``locking: mixed`` measured (issue 26): the numbers of docs/locking.md.

A command line over ``ancf_verify.studies.locking_study`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.studies.locking_study import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
