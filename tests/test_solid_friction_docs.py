"""docs/interface.md's section "Against a 3D solid with friction" is what
scripts/verify_solid_friction.py makes of the committed docs/solid_friction.csv, and the CSV's ANCF
columns are today's ANCF answers.  No dolfinx: the solid is not solved here (make
verify-solid-friction does), only the beams, in-process, to the first load level."""
import os
import tempfile

import numpy as np
import pytest

from ancf_verify.contact.tendon import NAMES, SOURCE, tendon_sections
from ancf_verify.friction import across
from ancf_verify.friction.beams import ancf_config, zone_label
from ancf_verify.friction.page import HEAD, across_csv, read_profiles, section
from ancf_verify.friction.profiles import ancf_profile, read
from ancf_verify.friction.rows import (ANCF, BEGIN, BODIES, CHECK, END, SOLID, SPACE, ancf_variant, differences,
                                       read_csv, solid_runs)
from ancf_verify.studies.supported_ends import ends
from helpers import ROOT

DOCS = os.path.join(ROOT, "docs")
CSV = os.path.join(DOCS, "solid_friction.csv")
MD = os.path.join(DOCS, "interface.md")

pytestmark = pytest.mark.skipif(not os.path.exists(CSV), reason="docs/solid_friction.csv not committed")


def _tables(text: str) -> list:
    return [ln for ln in text.splitlines() if ln.startswith("|")]


def test_the_section_is_that_of_the_csv():
    rows = read_csv(CSV)
    prof = read_profiles(os.path.join(DOCS, "solid_friction_profiles.csv"))
    across = read_profiles(across_csv(CSV))
    regenerated = _tables(section(rows, prof, {}, across=across))
    with open(MD, encoding="utf-8") as fh:
        text = fh.read()
    assert HEAD in text and BEGIN in text and END in text
    mine = _tables(text[text.index(HEAD):text.index(END)])
    assert regenerated and mine == regenerated, "docs/interface.md's solid-friction tables differ from the CSV"


def test_the_solid_study_is_complete():
    """Two meshes or more over Table 1's 13 levels, the stick stiffness x 10 and the other slip
    measure on the coarse mesh; the friction tangent checked by FD."""
    rows = read_csv(CSV)
    runs = solid_runs(rows, 45.0)
    assert len(runs) >= 2 and all(len(lv) == 13 for lv in runs.values())
    coarse = max(runs)
    for v in ("stick 1000", "slip closest"):
        assert len(solid_runs(rows, 45.0, v).get(coarse, {})) == 13, v
    fd = [r for r in rows if r["model"] == CHECK and r["variant"].startswith("finite differences")]
    assert len(fd) == 2 and all(float(r["value"]) < 1e-6 for r in fd)
    # everything slides: the regularisation changes nothing the comparison could see
    d = differences(solid_runs(rows, 45.0, "stick 1000")[coarse], runs[coarse])
    assert max(d[f"{b}_abs"] for b in BODIES) < 1e-4


@pytest.mark.parametrize("aug, elements, zone, space", [(None, 4, 0.0, None), (10.0, 4, 0.0, None), (0.1, 8, 0.0, None),
                                                        (None, 4, 0.01, None), (None, 4, 0.0, "quadratic across")])
def test_the_ancf_columns_are_todays(aug, elements, zone, space):
    """Each kind of column to the first level (10 N): the CSV's u_x of the three ends, to 1e-6
    (aug: the Coulomb law's augmentation c, None the default; zone: the diagnostic without
    friction within 10 mm of the clamp; space: the pressure space, None the default)."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    rows = read_csv(CSV)
    variant = zone_label(ancf_variant(aug, space), zone)
    want = [r for r in rows if r["model"] == ANCF and r["variant"] == variant
            and r["resolution"] == f"{elements} el." and float(r["psi_deg"]) == 45.0 and r["load_N"]
            and float(r["load_N"]) == 10.0]
    assert len(want) == 1
    with tempfile.TemporaryDirectory() as tmp:
        raw = ancf_config(45.0, elements, 0.3, aug, tmp, space)
        raw["steps"] = [10.0]
        spec = parse_config(raw, base_dir=SOURCE.configs)
        spec.contact.tangential.free_zone = zone
        res = run_model(spec, log=lambda *_: None)
    assert res.status == "completed", res.message
    probes = res.summary["steps"][0]["probes"]
    for body, name in zip(BODIES, NAMES):
        ref = float(want[0][f"{body}_ux_m"])
        assert probes[name]["displacement"][0] == pytest.approx(ref, rel=1e-6, abs=1e-12), body


def test_the_beams_pressures_near_the_clamp_are_todays():
    """The profile the page's diagnosis rests on: the frictionless 4-element beams at 10 N carry
    the CSV's compressive normal force within 10 mm of the clamped roots (today's answer, to
    1e-6 of the largest), no more than the solid's plus 1 N (the clamped ends' pressure
    functions folded: contact.md, "Supported ends"); with them kept, the constraints that repeat
    the supports carry more than ten times the solid's."""
    prof = read(os.path.join(DOCS, "solid_friction_profiles.csv"))

    def near(rows, model, resolution):
        sel = [r for r in rows if r["model"] == model and r["variant"] == "mu 0" and r["resolution"] == resolution
               and float(r["load_N"]) == 10.0 and float(r["x_lo_m"]) < 10e-3 - 1e-12]
        assert sel
        return {(r["interface"], round(float(r["x_lo_m"]), 6)):
                float(r["q_plus_N_per_m"]) * (float(r["x_hi_m"]) - float(r["x_lo_m"])) for r in sel}
    want = near(prof, ANCF, "4 el.")
    with tempfile.TemporaryDirectory() as tmp:
        got = near(ancf_profile(45.0, 4, 0.0, 10.0, None, tmp), ANCF, "4 el.")
        kept = near(ancf_profile(45.0, 4, 0.0, 10.0, None, os.path.join(tmp, "keep"), contact=ends("keep")),
                    ANCF, "4 el.")
    scale = max(want.values())
    assert got.keys() == want.keys()
    for k in want:
        assert abs(got[k] - want[k]) <= 1e-6 * scale, k
    solid = sum(near(prof, SOLID, "h 2.00 mm").values())
    assert sum(want.values()) <= solid + 1.0, (sum(want.values()), solid)
    assert sum(kept.values()) > 10.0 * solid, (sum(kept.values()), solid)


def test_the_pressure_across_is_todays():
    """docs/solid_friction_across.csv: the frictionless 4-element beams' pressure across the
    interfaces at 100 N is today's (every window and bin, to 1e-6 of the largest force); and the
    page's reading of the stored runs holds: on lg_sol and lg_mg the quadratic-across beams
    (16 el., μ = 0.3) press more than three times as hard as either solid mesh, the default
    beams no harder than the coarse solid plus 10 kPa."""
    rows = across.read()

    def sel(model, variant, resolution):
        return {(r["interface"], round(float(r["x_c_m"]), 6), round(float(r["s_lo_m"]), 7)):
                (float(r["force_plus_N"]), float(r["force_minus_N"]), float(r["weight_m2"]))
                for r in rows if (r["model"], r["variant"], r["resolution"]) == (model, variant, resolution)}
    want = sel(ANCF, "mu 0", "4 el.")
    with tempfile.TemporaryDirectory() as tmp:
        pts = across.ancf_points(45.0, 4, 0.0, 100.0, tmp, None)
    secs = tendon_sections()
    centres = sorted({float(r["x_c_m"]) for r in rows})
    got = across.binned_rows(pts, across.across_coordinates(secs), centres, {})
    got = {(r["interface"], round(r["x_c_m"], 6), round(r["s_lo_m"], 7)):
           (r["force_plus_N"], r["force_minus_N"], r["weight_m2"]) for r in got}
    assert got.keys() == want.keys()
    scale = max(max(abs(v[0]), abs(v[1])) for v in want.values())
    for k in want:
        assert np.allclose(got[k][:2], want[k][:2], rtol=0, atol=1e-6 * scale), k
        assert got[k][2] == pytest.approx(want[k][2], rel=1e-6), k

    def mean_plus(part, itf, x):
        v = [f for (i, xc, _), f in part.items() if i == itf and xc == round(x, 6)]
        return sum(f[0] for f in v) / sum(f[2] for f in v)
    quad = sel(ANCF, f"mu 0.3{SPACE}quadratic across", "16 el.")
    default = sel(ANCF, "mu 0.3", "16 el.")
    solids = [sel(SOLID, "mu 0.3", f"h {h} mm") for h in ("2.00", "1.40")]
    for itf in ("lg_sol", "lg_mg"):
        for x in centres:
            ps = [mean_plus(s, itf, x) for s in solids]
            assert mean_plus(quad, itf, x) > 3.0 * max(ps), (itf, x)
            assert mean_plus(default, itf, x) < ps[0] + 10e3, (itf, x)


def test_the_refined_reference_is_complete():
    """Issue 41, item 4: two locally refined meshes or more at the soleus-medial interface, the
    two finest at h <= 1 mm, the finest two that reach it give 10, 100 and 400 N (the levels the
    beams are judged at); the generated subsection is in the page (its tables: the test above)."""
    from ancf_verify.friction.refined import JUDGED, finest_two, refined_md, refined_runs
    rows = read_csv(CSV)
    loc = refined_runs(rows, 45.0)
    assert len(loc) >= 2 and sorted(loc)[1] <= 1e-3 + 1e-12
    for F in JUDGED:
        two = finest_two(rows, 45.0, F)
        assert len(two) == 2 and all(h <= 1e-3 + 1e-12 for h, _ in two), F
    assert all(r["resolution"].startswith("h 2.00 mm, ") for lv in loc.values() for r in lv.values())
    with open(MD, encoding="utf-8") as fh:
        text = fh.read()
    assert refined_md(rows, 45.0)[2] in text


def test_richardson_recovers_a_power_law():
    from ancf_verify.friction.refined import richardson
    hs = [1e-3, 7e-4, 5e-4]
    p, limit = richardson([3.0 - 2e3 * h ** 1.5 * 30 for h in hs], hs)
    assert p == pytest.approx(1.5, rel=1e-6) and limit == pytest.approx(3.0, rel=1e-9)
    assert np.isnan(richardson([1.0, 2.0, 1.5], hs)[0])        # not monotone: no estimate


def test_the_element_option_reaches_every_beam():
    """Issue 42: the friction comparison's beams take an element (``--element``); unset, the
    config is the committed columns' (no element key: the default 3363) and the rows keep the
    model label the page's tables read."""
    from ancf_petsc.config.parse import parse_config
    from ancf_verify.friction.rows import ancf_model
    with tempfile.TemporaryDirectory() as tmp:
        raw = ancf_config(45.0, 2, 0.3, None, tmp, "quadratic across", element="33103")
        assert [b["element"] for b in raw["beams"]] == ["33103"] * 3
        spec = parse_config(raw, base_dir=SOURCE.configs)
        assert [b.element for b in spec.beams] == ["33103"] * 3
        assert spec.contact.projection == (2, 2)
        plain = ancf_config(45.0, 2, 0.3, None, tmp)
        assert all("element" not in b for b in plain["beams"])
    assert ancf_model(None) == ANCF and ancf_model("33103") == "ANCF 33103 2pt"


def test_the_orders_tables_are_those_of_the_csvs():
    """docs/interface.md's section "Orders 3 and 4 against the friction solid" shows the element
    columns of docs/solid_friction.csv against the finest refined solid and the inf-sup constants
    of docs/solid_friction_infsup.csv as friction.orders makes them."""
    from ancf_verify.friction import orders
    rows = read_csv(CSV)
    with open(MD, encoding="utf-8") as fh:
        text = fh.read()
    tables = [orders.summary_md(rows, 45.0), orders.per_level_md(rows, 45.0),
              orders.infsup_md(orders.read_infsup())]
    for table in tables:
        assert len(table) > 2
        missing = [ln for ln in table if ln not in text]
        assert not missing, missing[:3]
    cols = orders.columns(rows, 45.0)
    want = {(el, d) for el in ("33103", "33153") for d in (1, 2, 3)} | {("3363", 1), ("3363", 2)}
    assert {(el, deg) for el, deg, ne in cols if ne == 8 and len(cols[(el, deg, ne)]["levels"]) == 13} >= want


@pytest.mark.parametrize("element, space", [("3363", "cubic across"), ("33103", "quadratic across")])
def test_the_infsup_constants_are_todays(element, space):
    """docs/solid_friction_infsup.csv at 4 elements is today's friction.infsup (to 1e-6): the
    cubic pressure across 3363 is not determined (β² over 1000 times below the quadratic's),
    the quadratic across 33103 is."""
    from ancf_verify.friction import orders
    from ancf_verify.friction.infsup import infsup
    rows = {(r["element"], r["space"], r["elements"]): r for r in orders.read_infsup()}
    want = rows[(element, space, "4")]
    with tempfile.TemporaryDirectory() as tmp:
        got = infsup(element, 4, space, tmp)
    assert got["multipliers"] == int(want["multipliers"])
    for k in ("all", "mg_sol", "lg_sol", "lg_mg"):
        assert got[k] == pytest.approx(float(want[k]), rel=1e-6), k
    quad = float(rows[(element, "quadratic across", "4")]["all"])
    assert (got["all"] < 1e-3 * quad) == (element == "3363")
