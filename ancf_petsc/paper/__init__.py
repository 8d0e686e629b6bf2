"""The reproduction of Obrezkov et al. (2022) for the Type III Achilles tendon, kept apart from
the library (nothing in ancf_petsc imports it): Tables 1 and 2 (tables.py), the contact study
(contact_study.py), the figures (figures.py), each a sweep over the Achilles config (runs.py) with
its inputs in one directory (inputs.py).  ``ancf-report`` is its command line."""
from .contact_study import BulkFit, fit_bulk_modulus, fit_markdown, laws_markdown, scaling_markdown, scaling_spread, scaling_study
from .figures import FIGURE5_VIEW, figures, keep_only, slip_figures
from .inputs import BEAMS, PROBE, TWISTS, PaperInputs, read_paper
from .runs import elongations, execute, make_sweep, summary_of
from .tables import (T2_ELEMENTS, T2_VARIANTS, Table1, table1, table1_from, table2, table2_markdown,
                     timing_markdown)

__all__ = ["BEAMS", "FIGURE5_VIEW", "PROBE", "T2_ELEMENTS", "T2_VARIANTS", "TWISTS", "PaperInputs", "Table1",
           "elongations", "execute", "figures", "fit_bulk_modulus", "keep_only", "fit_markdown", "BulkFit", "laws_markdown", "make_sweep", "read_paper",
           "scaling_markdown", "scaling_spread", "scaling_study", "slip_figures", "summary_of", "table1",
           "table1_from", "table2", "table2_markdown", "timing_markdown"]
