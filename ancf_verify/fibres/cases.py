"""The helical-fibre bar (GOH) compared with the solid: constants, laws and cases."""
from __future__ import annotations

from dataclasses import dataclass
import copy
import os

from ancf_verify.bars.cases import Case
from ancf_verify.paths import ROOT


CSV_NAME = "solid_fibres.csv"

DOC = os.path.join(ROOT, "docs", "fibres.md")

FIGURE = os.path.join("figures", "solid_fibres.png")

BLOCK = "solid_fibres"

SECTION = {"shape": "ellipse", "semi_axes": [0.006, 0.004], "cubature_degree": 6}

MU = 1.0e6

FIBRES = {"k1": 2.0e6, "k2": 5.0, "kappa": 0.0}

LENGTH, TWIST, FORCE = 0.05, 180.0, 20.0

STEPS = (0.25, 0.5, 0.75, 1.0)

ELEMENTS = (4, 8, 16)

STATIONS = 8                       # rotation along x at x = k L / 8 (nodes of every ANCF mesh)

OUTSIDE_TOL = 0.03                 # largest violation of a point's reference coordinates accepted

SAMPLE_SCALE = 0.95                # solid sections sampled at the section rule's points x 0.95

H = (2.83e-3, 2e-3, 1.41e-3)       # solid mesh sizes [m], coarse to fine

H_INCOMPRESSIBLE = (1e-3,)         # one more at the largest K/mu (P2 tets converge slowly there)

H_QUICK = (4e-3, 2.83e-3, 2e-3)


#: matrix bulk modulus over mu: the tests' nearly incompressible matrix (nu = 0.49), the Achilles
#: columns' (0.86 GPa / 103.1 MPa, nu = 0.44) and a compressible one (nu = 0.3)
BULK_RATIOS = (50.0, 8.34, 2.1667)


#: section rule degree of the volumetric term in the locking diagnosis (``BeamSpec.volumetric_degree``)
VOLUMETRIC_DEGREE = 2

ANCF, ANCF_VOL = "ANCF", f"ANCF, K/2 (J-1)^2 on a degree-{VOLUMETRIC_DEGREE} section rule"


#: the remedy: ``locking: mixed`` (ancf_petsc/physics/mixed.py)
ANCF_MIXED = "ANCF, locking: mixed"

ANCF_MODELS = (ANCF, ANCF_VOL, ANCF_MIXED)


@dataclass
class Law:
    """One material of the study: its key, label and the ANCF material dict (matrix K/mu aside)."""
    key: str
    label: str
    material: dict

LAWS = [Law("goh_twist", "GOH, helical fibres (along the pretwist's material lines)",
            {"model": "goh", "mu": MU, **FIBRES, "fibres": {"follow": "twist"}}),
        Law("goh_axis", "GOH, fibres along x (control)",
            {"model": "goh", "mu": MU, **FIBRES, "fibres": {"follow": "axis"}}),
        Law("neo_hookean", "neo-Hookean matrix alone (control)", {"model": "neo-hookean", "mu": MU})]


def case_key(law: str, ratio: float) -> str:
    return f"{law}_K{ratio:g}"


def make_case(law: Law, ratio: float, quick: bool = False) -> Case:
    """The bar of ``law`` with bulk modulus ratio * mu as a verify_solid Case (section centred
    on the twist axis, fibres with the matrix)."""
    mat = {**copy.deepcopy(law.material), "bulk_modulus": ratio * MU}
    h = H_QUICK if quick else (H + H_INCOMPRESSIBLE if ratio == max(BULK_RATIOS) else H)
    return Case(case_key(law.key, ratio), law.label, copy.deepcopy(SECTION), mat, (FORCE, 0.0, 0.0),
                   h=h, h_quick=H_QUICK, length=LENGTH, twist_deg=TWIST,
                   twist_axis=(0.0, 0.0), steps=STEPS)
