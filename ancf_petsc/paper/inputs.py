"""The reproduction's inputs: the Achilles configs and the paper's tables, in one directory
given by the caller (``ancf-report --configs``, default the repository's ``configs/``)."""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

TWISTS = (0, 15, 45)
PROBE = "soleus"
BEAMS = 3


@dataclass(frozen=True)
class PaperInputs:
    """``configs``: a directory with achilles_type3_psi45.yaml (and the section data it reads)
    and data/paper_table{1,2}_*.csv."""
    configs: str

    @property
    def base(self) -> str:
        """The Achilles config every study varies."""
        return os.path.join(self.configs, "achilles_type3_psi45.yaml")

    @property
    def table1_csv(self) -> str:
        return os.path.join(self.configs, "data", "paper_table1_elongation.csv")

    @property
    def table2_csv(self) -> str:
        return os.path.join(self.configs, "data", "paper_table2_convergence.csv")

    def check(self) -> "PaperInputs":
        """Raise an InputError naming the first missing file."""
        for path in (self.base, self.table1_csv, self.table2_csv):
            if not os.path.isfile(path):
                raise InputError("--configs", f"{path}: not found (give the directory with the "
                                              "Achilles configs and data/paper_table*.csv)")
        return self


def read_paper(path: str) -> dict[str, np.ndarray]:
    """A paper table CSV (``#`` comment lines) as columns."""
    with open(path) as fh:
        rows = [ln.strip().split(",") for ln in fh if ln.strip() and not ln.startswith("#")]
    head, body = rows[0], np.array(rows[1:], dtype=float)
    return {h: body[:, i] for i, h in enumerate(head)}
