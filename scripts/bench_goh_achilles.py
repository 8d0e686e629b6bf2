#!/usr/bin/env python3
"""The Achilles psi = 45 deg column with GOH against neo-Hookean (issue 26): cut-backs, Newton

A command line over ``ancf_verify.bench.goh_achilles`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.bench.goh_achilles import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
