#!/usr/bin/env python3
"""The GOH parameter sets of the paper's authors' public code in this model (issue 26): why the

A command line over ``ancf_verify.studies.goh_published_sets`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.studies.goh_published_sets import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
