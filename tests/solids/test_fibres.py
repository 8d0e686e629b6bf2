"""The helical-fibre (GOH) bar of docs/fibres.md as a 3D solid on the CSV's coarsest mesh: today's
solid (the UFL GOH law, the fibre field built from ancf_petsc's twist map, checked against it at
the quadrature points) gives the committed end displacement and rotation."""
import os

import numpy as np
import pytest

from ancf_verify.fibres.cases import BULK_RATIOS, H, LAWS, case_key, make_case
from ancf_verify.fibres.report import read_csv, runs_of
from helpers import ROOT


@pytest.mark.parametrize("law", [LAWS[0]], ids=lambda law: law.key)
def test_the_coarsest_fibre_solid_is_the_committed_one(solid_stack, law):
    from ancf_verify.bars.cases import ancf_section
    from ancf_verify.fibres.solid import run_solid
    ratio = BULK_RATIOS[0]
    case = make_case(law, ratio)
    want = next(r for r in runs_of(read_csv(os.path.join(ROOT, "docs", "solid_fibres.csv")))[case_key(law.key, ratio)]
                ["solid"] if r["res"] == f"h {H[0] * 1e3:.2f} mm")
    got = run_solid(case, ancf_section(case), H[0], 2)
    assert not got["field_err"] > 1e-10                 # nan for the isotropic law
    assert np.linalg.norm(got["u"] - want["u"]) <= 1e-6 * np.linalg.norm(want["u"]), (got["u"], want["u"])
    assert got["levels"][-1]["rot"] == pytest.approx(want["rot"], rel=1e-6, abs=1e-9)
