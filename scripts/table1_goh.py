#!/usr/bin/env python3
"""Table 1 with neo-Hookean and with GOH side by side, and the untwist of the soleus (issue 26).

A command line over ``ancf_verify.studies.table1_goh`` (its docstring: what it does and how).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from ancf_verify.studies.table1_goh import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
