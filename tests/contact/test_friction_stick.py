"""Friction's stick flags and stick share say where the interface sticks (issue 39).

A point sticks where most of its tangential functions, weighted by their values φ_k at the point,
stick.  The weights were the functions' columns of tΦ, φ_k(x_p) w_p / A_k, whose sum is far below
1: almost every point read "slipping" (the tendon at μ = 3, 10 N: 57 % of the functions stick, 0–4 %
of the points did).  The stick share is the sticking part of the pressed area."""
import os

import numpy as np
import scipy.sparse as sp

from helpers import CONFIGS, load_raw, run_inline
from ancf_petsc.contact.friction import stick_fraction
from ancf_petsc.io.reader import read_contact


def test_the_stick_fraction_weighs_the_functions_by_their_values():
    """Two functions over three points, φ = (1, 0), (0.5, 0.5), (0, 1), stored as φ w / A with
    w = 1e-6 m², A = 2e-6 m²: the sums of the stored columns are 0.5, not 1."""
    phi = np.array([[1.0, 0.5, 0.0], [0.0, 0.5, 1.0]])
    area = np.array([2e-6, 2e-6])
    tPhi = sp.csr_matrix(phi * 1e-6 / area[:, None])
    share = stick_fraction(tPhi, area, np.array([True, False]))
    assert np.allclose(share, [1.0, 0.5, 0.0])
    assert np.allclose(stick_fraction(tPhi, area, np.array([True, True])), 1.0)


def test_the_tendon_at_mu_3_sticks_where_it_does_not_slide(tmp_path):
    """The paper's tendon (ψ = 45°, 4 elements) pulled by its three muscles equally with μ = 3, at
    10 N: part of the tangential functions stick (0.13 of them; mg_sol's stick share 0.61), and
    the points flagged sticking move less in the increment than those that slide (median 0.39 and
    0.45 of theirs: a linear function sticks on average over its element, so its points may
    slip a little; 0.02-0.05 on the quadratic pressure's shorter functions).  (Until
    2026-12-07 this was the soleus pulled alone, where 57 % of the functions stuck: on the
    quadratic pressure along the beam, then friction's default, whose coefficients reached
    ±9e7 Pa and whose pressing force 712 N at a 10 N load; on the linear one, now friction's
    default (config/contact.default_axial), the pressing forces are 0.4-1.2 N there and every
    function slides.)"""
    raw = load_raw("achilles_psi45_equal_muscles.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["contact"]["tangential"] = {"law": "coulomb", "friction": 3.0}
    raw["steps"] = [10.0]
    raw["output"] = {"vtk": False}
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed"
    c = read_contact(str(tmp_path / "results.h5"), 1)
    assert 0.05 < c["multiplier_stick"].mean() < 0.95
    shares = [v["stick_share"] for v in s["steps"][-1]["contact"].values()]
    assert max(shares) > 0.5, shares
    for k, (name, v) in enumerate(s["steps"][-1]["contact"].items()):
        on = (c["interface"] == k) & (c["pressure"] > 0) & (c["weight"] > 0)
        inc = np.linalg.norm(c["slip_increment"][on], axis=1)
        stick = c["stick"][on].astype(bool)
        every = np.linalg.norm(c["slip_increment"][c["interface"] == k], axis=1)
        assert abs(v["max_slip_increment"] - every.max()) <= 1e-6 * every.max()
        if stick.any() and (~stick).any():
            assert np.median(inc[stick]) < 0.6 * np.median(inc[~stick]), name


def test_the_header_names_the_tangential_law_and_the_supported_ends():
    """Before: "sliding (normal gap held at zero, frictionless); Coulomb friction, mu = 3" on one
    line, and nothing about supported_ends."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from ancf_petsc.model.contact_setup import contact_for
    from helpers import CONFIGS
    lines = {}
    for law in (None, {"law": "coulomb", "friction": 3.0}):
        raw = load_raw("achilles_type3_psi45.yaml")
        if law:
            raw["contact"]["tangential"] = law
        spec = parse_config(raw, base_dir=CONFIGS)
        out = []
        contact_for(build_model(spec), spec.contact, out.append)
        lines[bool(law)] = "\n".join(out)
    assert "frictionless" not in lines[True] and "Coulomb friction, mu = 3" in lines[True]
    assert "supported ends: pressure merge (0 clamped interface end(s)" in lines[True]
    assert "tangential merge (3 end(s) where both bodies' r is held folded)" in lines[True]
    assert "; frictionless;" in lines[False] and "tangential merge" not in lines[False]


def test_the_normal_force_is_split_into_pressing_and_pulling_and_bounds_the_friction(tmp_path):
    """summary.json's normal_force is the net ∫p dA, where pressing and pulling parts cancel: with
    μ = 0.3 the lg_sol interface showed a shear force 182 N against a net −387 N at 400 N (a
    Coulomb law broken, as it read).  pressing_force = ∫p⁺ dA and tension_force = ∫p⁻ dA sum to
    the net, and μ pressing_force bounds the shear force on every interface and level (the bound
    is ∫p⁺: measured 608 N at 400 N, μ × 608 = 182.4 N)."""
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["contact"]["tangential"] = {"law": "coulomb", "friction": 0.3}
    raw["steps"] = [10.0, 100.0]
    raw["output"] = {"vtk": False}
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed"
    beyond_net = 0
    for st in s["steps"]:
        for name, c in st["contact"].items():
            assert c["pressing_force"] >= 0.0 >= c["tension_force"]
            assert abs(c["pressing_force"] + c["tension_force"] - c["normal_force"]) <= 1e-9 * c["pressing_force"] + 1e-12
            shear = float(np.linalg.norm(c["shear_force"]))
            assert shear <= 0.3 * c["pressing_force"] * (1 + 1e-6), (name, shear, c["pressing_force"])
            beyond_net += shear > 0.3 * abs(c["normal_force"])
    assert beyond_net >= 1          # where the net force alone would read as a broken Coulomb law


def test_the_multipliers_scaling_changes_no_friction_answer(tmp_path):
    """``contact.scaling`` scales the multipliers' k_s (README: it changes no answer).  Friction's
    trial traction y + c U has y in units of k_s: with c as given, s = 1000 ran the iteration of
    c × 1000 and the paper's tendon (2 elements, μ = 0.3) ended on another solution, the soleus
    at 4.81 mm against 4.11 mm at 400 N; c / s keeps the iteration's physics."""
    import os
    from helpers import CONFIGS
    ends = []
    for s in (1.0, 1000.0):
        raw = load_raw("achilles_type3_psi45.yaml")
        for b in raw["beams"]:
            b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
            b["elements"] = 2
        raw["contact"] = {"mode": "sliding", "tangential": {"law": "coulomb", "friction": 0.3}, "scaling": s}
        raw["steps"] = [100.0, 400.0]
        summary = run_inline(raw, tmp_path / f"s{s:g}")
        assert summary["status"] == "completed"
        ends.append(np.array(summary["steps"][-1]["probes"]["soleus"]["displacement"]))
    assert np.abs(ends[1] - ends[0]).max() <= 1e-7 * np.abs(ends[0]).max(), ends


def test_a_level_with_no_slip_sticks_everywhere(tmp_path):
    """The pressed strips (4 elements, mu = 0.5) pulled out by 0.1 mm and then held: at the held
    levels nothing moves (slip increment 0, no Newton step), every function's trial sits on its
    bound, and which side it lands on was rounding's: stick_share 0.0 here, and on a 13-frame
    stride's rest frames 0.07 / 0.04 / 0.12 in one run, 0.40 / 0 / 0 restarted (states equal to
    5e-17 m).  They now stick (1.0), as the zero slip says; the sliding levels still slide."""
    raw = load_raw("friction_pressed_strips.yaml")
    raw["boundary_conditions"][-1]["curve"] = [[0, 0], [1, 0], [2, 1], [3, 1]]
    for load in raw["loads"]:
        load["curve"] = [[0, 0], [1, 1], [3, 1]]
    raw["steps"] = [1, 1.5, 2, 2.5, 3]
    raw["output"] = {"vtk": False}
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed"
    (sliding, held) = ([st for st in s["steps"] if lo <= st["load_factor"] <= hi] for lo, hi in ((1.5, 2), (2.5, 3)))
    for st in sliding:
        assert st["contact"]["interface (base|slider)"]["stick_share"] == 0.0
    for st in held:
        rep = st["contact"]["interface (base|slider)"]
        assert rep["max_slip_increment"] == 0.0 and rep["stick_share"] == 1.0, rep
        c = read_contact(str(tmp_path / "results.h5"), s["steps"].index(st) + 1)
        assert c["multiplier_stick"].all()
