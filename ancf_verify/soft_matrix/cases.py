"""The soft-matrix bar (nearly incompressible matrix, stiff fibres): constants and cases."""
from __future__ import annotations

import copy

from ancf_verify.bars.cases import Case
from ancf_verify.fibres.cases import ANCF, ANCF_MIXED, LENGTH, SECTION, STEPS, TWIST


CSV_NAME = "solid_soft_matrix.csv"

BLOCK = "solid_soft_matrix"

WRITER = "scripts/verify_solid_soft_matrix.py"

MU = 107.2e3

BULK_RATIO = 49.67

MATERIAL = {"model": "goh", "mu": MU, "bulk_modulus": BULK_RATIO * MU, "k1": 75.351e6, "k2": 23.926,
            "kappa": 0.0, "fibres": {"follow": "twist"}}


#: total end force [N]: the largest Ē of the 8-element traction beam in the bar's middle half is
#: 3.2 % (``--beam-only --force F``: 2.4 % at 100 N, 4.0 % at 300 N)
FORCE = 200.0

ELEMENTS = (4, 8)

H = (2.83e-3, 2e-3, 1.41e-3, 1e-3)     # solid mesh sizes [m]; the finest alone takes ~20 min

LOADS = {"traction_force": "end traction", "force": "point force on r"}

LOCKINGS = {ANCF: "none", ANCF_MIXED: "mixed"}

MIDDLE = (0.25, 0.75)              # the bar's middle half, fractions of L

EXTRA = ["fibre_strain_min", "fibre_strain_max", "ux_mean_m", "ux_fit0_m", "ux_span_m"]


def make_case(force: float = FORCE) -> Case:
    """The soft-matrix bar at total end force ``force``."""
    return Case("goh_soft_alex", "GOH alex set, helical fibres", copy.deepcopy(SECTION),
                   copy.deepcopy(MATERIAL), (force, 0.0, 0.0), h=H, h_quick=H, length=LENGTH,
                   twist_deg=TWIST, twist_axis=(0.0, 0.0), steps=STEPS)


def model_name(locking: str, load: str) -> str:
    return f"ANCF, {LOADS[load]}, locking: {locking}"
