"""docs/fibres.md's 3D-solid check of the pretwisted bar with helical GOH fibres is what
scripts/verify_solid_fibres.py makes of the committed docs/solid_fibres.csv, and the CSV's ANCF
numbers are what today's code computes.  No dolfinx here: the solid runs only under
``make verify-solid``; the ANCF runs (a few tenths of a second each) are repeated."""
import os
import tempfile

import numpy as np
import pytest

from ancf_verify.fibres.beams import run_ancf
from ancf_verify.fibres.cases import ANCF, ANCF_MIXED, ANCF_VOL, BULK_RATIOS, LAWS, case_key, make_case
from ancf_verify.fibres.report import read_csv, render_block, replace_block, runs_of
from helpers import ROOT, petsc_init

CSV = os.path.join(ROOT, "docs", "solid_fibres.csv")
DOC = os.path.join(ROOT, "docs", "fibres.md")


@pytest.fixture(scope="module")
def cases():
    return runs_of(read_csv(CSV))


def test_the_docs_block_is_that_of_the_csv():
    with open(DOC, encoding="utf-8") as fh:
        text = fh.read()
    block = render_block(read_csv(CSV))
    assert replace_block(text, block) == text, \
        "docs/fibres.md's solid_fibres block differs from the CSV: python scripts/verify_solid_fibres.py --replot"


def test_the_csv_covers_the_study(cases):
    assert set(cases) == {case_key(law.key, r) for law in LAWS for r in BULK_RATIOS}
    for key, c in cases.items():
        assert len(c["solid"]) >= 3, key                          # a Richardson reference
        assert {r["res"] for r in c["ancf"]} >= {"8 el.", "16 el."}, key
        assert {r["res"] for r in c["vol"]} >= {"16 el."}, key
        assert {r["res"] for r in c["mixed"]} >= {"8 el.", "16 el."}, key
        for r in c["solid"]:                                      # the solid's fibres are the beam's
            assert c["law"] == "neo_hookean" or r["field_err"] <= 1e-12, (key, r["res"])
        assert c["unc_rot"] < 0.02, key


def test_what_the_page_says_holds(cases):
    """The page's statements, read off the CSV: the helical fibres' coupling is large; the beam
    meets 1 % where the matrix is compressible; the miss grows with K/μ (locking), and putting
    the volumetric term on a degree-2 section rule removes most of it."""
    twist, axis, nh = (cases[f"{law}_K50"] for law in ("goh_twist", "goh_axis", "neo_hookean"))
    assert twist["ref_rot"] < 5 * axis["ref_rot"] < 0 and twist["ref_rot"] < 4 * nh["ref_rot"]
    for n in (8, 16):
        r = next(r for r in cases["goh_twist_K2.1667"]["ancf"] if r["res"] == f"{n} el.")
        assert r["err_u"] < 0.01 and r["err_rot"] < 0.01
    errs = [next(r for r in cases[f"neo_hookean_K{k:g}"]["ancf"] if r["res"] == "16 el.")["err_rot"]
            for k in (2.1667, 8.34, 50.0)]
    assert errs[0] < errs[1] < errs[2]
    for law in ("goh_twist", "goh_axis", "neo_hookean"):
        c = cases[f"{law}_K50"]
        plain = next(r for r in c["ancf"] if r["res"] == "16 el.")
        vol = next(r for r in c["vol"] if r["res"] == "16 el.")
        assert vol["err_rot"] < 0.25 * plain["err_rot"], law
        assert plain["vol_share"] > 1.4 * c["solid"][-1]["vol_share"], law


def _at(c, kind, n):
    return next(r for r in c[kind] if r["res"] == f"{n} el.")


def test_what_the_page_says_of_locking_mixed(cases):
    """Issue 26, verification point 3, with the remedy on: the helical-fibre bar within 1 % of the
    solid in end displacement and rotation at 8 and 16 elements at K/μ = 8.34 and 50 (and 2.17);
    the controls' rotation errors fall to less than half at K/μ = 8.34 and 50; the volumetric
    share of the energy is the solid's to 15 %; the matrix alone untwists too little without the
    remedy and too much with it, at every K/μ (the ρ² dilatation, docs/fibres.md)."""
    for key, c in cases.items():
        for n in (8, 16):
            m = _at(c, "mixed", n)
            if c["law"] == "goh_twist":
                assert m["err_u"] < 0.01 and m["err_rot"] < 0.01, (key, n)
            elif c["ratio"] > 5:
                assert m["err_rot"] < 0.5 * _at(c, "ancf", n)["err_rot"], (key, n)
        assert abs(_at(c, "mixed", 16)["vol_share"] / c["solid"][-1]["vol_share"] - 1.0) < 0.15, key
        if c["law"] == "neo_hookean":
            assert abs(_at(c, "ancf", 16)["rot"]) < abs(c["ref_rot"]) < abs(_at(c, "mixed", 16)["rot"]), key


@pytest.mark.parametrize("key,model", [("goh_twist_K50", "ANCF"), ("goh_axis_K2.1667", "ANCF"),
                                       ("goh_twist_K50", "vol"), ("goh_twist_K50", "mixed"),
                                       ("neo_hookean_K8.34", "mixed")])
def test_the_csv_ancf_numbers_are_todays(cases, key, model):
    """The 8-element runs again, with today's code: end displacement and rotation as committed."""
    petsc_init()
    law = next(law for law in LAWS if key.startswith(law.key + "_K"))
    case = make_case(law, float(key.rsplit("_K", 1)[1]))
    with tempfile.TemporaryDirectory() as tmp:
        now = run_ancf(case, 8, tmp, {"ANCF": ANCF, "vol": ANCF_VOL,
                                             "mixed": ANCF_MIXED}[model])
    then = next(r for r in cases[key]["ancf" if model == "ANCF" else model] if r["res"] == "8 el.")
    assert np.allclose(now["u"], then["u"], rtol=1e-6, atol=1e-6 * np.abs(then["u"]).max())
    assert abs(now["rot"] - then["rot"]) <= 1e-6 * abs(then["rot"])
