"""The soft-matrix bar of docs/fibres.md as a 3D solid on the CSV's coarsest mesh: today's solid
gives the committed end displacement, rotation and section-mean u_x (SoftProbe)."""
import os

import numpy as np
import pytest

from ancf_verify.fibres.report import read_csv
from ancf_verify.soft_matrix.cases import H, make_case
from ancf_verify.soft_matrix.solid import SoftProbe, evaluate
from helpers import ROOT


def test_the_coarsest_soft_matrix_solid_is_the_committed_one(solid_stack):
    from ancf_verify.bars.cases import ancf_section
    from ancf_verify.fibres.solid import run_solid
    case = make_case()
    want = next(r for r in evaluate(read_csv(os.path.join(ROOT, "docs", "solid_soft_matrix.csv")))["solid"]
                if r["res"] == f"h {H[0] * 1e3:.2f} mm")
    got = run_solid(case, ancf_section(case), H[0], 2, probe=SoftProbe)
    assert np.linalg.norm(got["u"] - want["u"]) <= 1e-6 * np.linalg.norm(want["u"]), (got["u"], want["u"])
    assert got["rot"] == pytest.approx(want["rot"], rel=1e-6)
    assert got["u_mean"][0] == pytest.approx(want["ux_mean"], rel=1e-6)
