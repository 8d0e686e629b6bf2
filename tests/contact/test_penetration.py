"""Pointwise penetration under unilateral contact (issue 42): the weighted gaps hold while the
contact points themselves may interpenetrate; a run whose last level does
so by more than 1 % of the thinner section says so in a warning (log and summary.json), sliding
runs never (their gaps are held at zero both ways).  The section's smallest width it is measured
against is checked against shapes whose width is known."""
import re

import numpy as np
import pytest

from helpers import build_problem, load_raw, run_inline
from ancf_petsc.contact.reports import PENETRATION_SHARE
from ancf_petsc.physics.section import make_ellipse, make_rectangle


def test_smallest_width_of_known_shapes_and_of_the_type3_outlines():
    """A rectangle's smaller side; an ellipse's minor axis (its boundary polyline lies inside:
    within 1e-5 relative); the Type III outlines against the least of their widths over 3600
    directions."""
    assert make_rectangle((0.004, 0.002)).smallest_width == pytest.approx(0.002, rel=1e-12)
    assert make_ellipse((0.003, 0.001)).smallest_width == pytest.approx(0.002, rel=1e-5)
    P, _ = build_problem(load_raw("achilles_type3_psi45.yaml"))
    theta = np.linspace(0.0, np.pi, 3600, endpoint=False)
    directions = np.column_stack([np.cos(theta), np.sin(theta)])
    for b in P.model.beams:
        pts, _ = b.section._fine_polygon()
        h = pts @ directions.T
        sampled = float((h.max(axis=0) - h.min(axis=0)).min())
        # sampling only finds a width at least the least one, larger by up to the extent x dθ
        exact = b.section.smallest_width
        assert exact * (1.0 - 1e-12) <= sampled <= exact + 2.0 * b.section.extent.max() * (theta[1] - theta[0])
        assert 2.5e-3 < b.section.smallest_width < 3.5e-3


def _column(mode: str, curve: int | None = None, steps: tuple = (10.0,)) -> dict:
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["contact"]["mode"] = mode
    if curve is not None:
        raw["contact"]["projection"] = {"curve": curve}
        raw["contact"]["curve_points"] = 4
    raw["steps"] = list(steps)
    return raw


def _notes(summary: dict) -> list[str]:
    return [w for w in summary["warnings"] if "interpenetrate" in w]


MG_SOL = "mg_sol (soleus|medial_gastrocnemius)"


def test_a_unilateral_run_that_ends_interpenetrating_warns_and_sliding_never(tmp_path):
    """The paper's tendon, unilateral, 10 N: the soleus and medial gastrocnemius interpenetrate
    by 0.17 mm between the contact points of the default pressure space (linear across) where
    the interface is open: one warning naming that interface and its depth.  Sliding leaves
    pointwise gaps of either sign and no warning."""
    s = run_inline(_column("unilateral"), tmp_path / "unilateral")
    depth = s["steps"][-1]["contact"][MG_SOL]["max_penetration"]
    assert depth > 1e-4
    notes = _notes(s)
    assert len(notes) == 1 and notes[0].startswith(f"warning: contact interface {MG_SOL}")
    assert f"{depth * 1e6:.3g} um" in notes[0] and f"above {PENETRATION_SHARE:.0%}" in notes[0]
    # what it measures: the points themselves (they are where the gap is read), not between them
    assert "interpenetrate at the contact points by up to" in notes[0], notes[0]
    assert "weighted gap >= 0, not each point's" in notes[0], notes[0]
    # one edge in, the other open: across, none of it along (tests/contact/test_penetration_along.py)
    assert s["steps"][-1]["contact"][MG_SOL]["max_penetration_along"] < 0.5 * depth
    assert "curve_spans: 4" in notes[0] and "elements along" not in notes[0], notes[0]
    s = run_inline(_column("sliding"), tmp_path / "sliding")
    assert max(c["max_penetration"] for c in s["steps"][-1]["contact"].values()) > 0.0
    assert not _notes(s)


def test_the_last_level_decides_and_the_threshold_is_the_thinner_section(tmp_path):
    """With pressure functions of degree 5 across (docs/contact.md, "Pointwise penetration") the
    paper's unilateral column ends at 400 N with every interface within 1 % of its thinner
    section (3.36 mm for mg_sol), though at 10 N it was not: no warning.  bundle_circle7
    (touching circles of radius 0.5 mm, unilateral) ends 22 µm deep in its 1 mm wide sections:
    one warning line for its 12 interfaces above 10 µm (12 near-identical lines before), naming
    the deepest with its depth and the others after it."""
    s = run_inline(_column("unilateral", curve=5, steps=(10.0, 100.0, 400.0)), tmp_path / "curve5")
    first, last = s["steps"][0]["contact"], s["steps"][-1]["contact"]
    assert first[MG_SOL]["max_penetration"] > PENETRATION_SHARE * 3.36e-3
    assert max(c["max_penetration"] for c in last.values()) < PENETRATION_SHARE * 2.73e-3
    assert s["status"] == "completed" and not _notes(s)
    raw = load_raw("bundle_circle7.yaml")
    raw["contact"]["mode"] = "unilateral"
    s = run_inline(raw, tmp_path / "circle7")
    limit = PENETRATION_SHARE * 2.0 * raw["bundle"]["radius"]
    deep = [name for name, c in s["steps"][-1]["contact"].items() if c["max_penetration"] > limit]
    notes = _notes(s)
    assert len(deep) == 12 and len(notes) == 1, notes
    first, others = re.match(r"warning: contact interface (.+?\)) and 11 other\(s\) \((.+?):", notes[0]).groups()
    depths = {name: c["max_penetration"] for name, c in s["steps"][-1]["contact"].items()}
    assert depths[first] == max(depths.values())
    assert f"up to {depths[first] * 1e6:.3g} um" in notes[0]
    assert sorted([first.split(" (")[0]] + others.split(", ")) == sorted(n.split(" (")[0] for n in deep)


def test_pressure_functions_across_on_spans():
    """One span: the Bernstein polynomials, bitwise.  More: B-splines that are non-negative, sum
    to one, and live on degree + 1 spans each (degree 1: the hat functions on the span ends)."""
    from ancf_petsc.contact.multipliers import across_functions, bernstein
    tau = np.linspace(-1.0, 1.0, 41)
    for d in (0, 1, 2, 3):
        assert np.array_equal(across_functions(tau, d, 1), bernstein(tau, d))
    for d, n in ((1, 4), (2, 3), (0, 5), (1, 5)):
        phi = across_functions(tau, d, n)
        assert phi.shape == (41, d + n) and phi.min() >= 0.0
        assert np.allclose(phi.sum(axis=1), 1.0, rtol=0, atol=1e-14)
        width = ((phi > 0).sum(axis=0) - 1) / 40 * n          # spans each function covers
        assert width.max() <= d + 1 + 1e-9
    nodes = np.linspace(-1.0, 1.0, 5)
    hats = np.clip(1.0 - np.abs(tau[:, None] - nodes[None, :]) / 0.5, 0.0, None)
    assert np.allclose(across_functions(tau, 1, 4), hats, rtol=0, atol=1e-14)


def test_local_pressure_functions_across_hold_the_points(tmp_path):
    """The paper's unilateral tendon at 10 N with linear pressure functions on 4 spans across
    (`projection.curve_spans: 4`): the points stay within 20 µm of the medial gastrocnemius
    (0.17 mm deep with one span), no warning, and the soleus end moves by less than 0.3 %."""
    raw = _column("unilateral")
    raw["contact"]["projection"] = {"curve": 1, "curve_spans": 4}
    raw["contact"]["curve_points"] = 4
    s = run_inline(raw, tmp_path / "spans")
    assert s["steps"][-1]["contact"][MG_SOL]["max_penetration"] < 20e-6 and not _notes(s)
    one = run_inline(_column("unilateral"), tmp_path / "one")
    u, u1 = (x["steps"][-1]["probes"]["soleus"]["displacement"][0] for x in (s, one))
    assert abs(u - u1) < 3e-3 * abs(u1)


def test_penetration_counts_only_points_over_the_partner_surface():
    """A partner place past the interface curve's ends or past B's beam ends has its gap to a
    continued end piece: it is not on the surface (``Projector.on_surface``), so its gap is no
    penetration; inside both it is."""
    P, _ = build_problem(_column("unilateral"))
    pj = P.contact.projector
    idx = np.arange(4)
    T = pj.t_end[idx]
    eB = pj.eB[idx].copy()
    first = np.array([P.contact.interfaces[k].b.element_offset for k in pj.points.itf[idx]])
    inside = pj.on_surface(idx, eB, np.zeros(4), 0.5 * T)
    assert inside.all()
    assert not pj.on_surface(idx, eB, np.zeros(4), -1e-9 * T).any()
    assert not pj.on_surface(idx, eB, np.zeros(4), (1 + 1e-9) * T).any()
    assert not pj.on_surface(idx, first, np.full(4, -1.01), 0.5 * T).any()
    assert pj.on_surface(idx, first, np.full(4, -0.99), 0.5 * T).all()


def test_too_many_pressure_functions_across_is_a_config_error():
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.config.values import ConfigError
    from helpers import CONFIGS
    raw = _column("unilateral")
    raw["contact"]["projection"] = {"curve": 1, "curve_spans": 6}      # 3 x 7 = 21 > 18
    with pytest.raises(ConfigError) as err:
        parse_config(raw, base_dir=CONFIGS)
    assert str(err.value).startswith("contact.projection: (axial + 1) x (curve + curve_spans)")


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [2, 3])
def test_local_pressure_functions_and_the_warning_on_ranks_are_serial(tmp_path, ranks):
    """The B-splines across (`curve_spans: 4`) and the penetration report on 2 and 3 ranks: the
    serial probes and the serial largest penetration (the warning's figure) to 1e-9, and the
    surfaces' normal turns at element boundaries (contact/kinks.py) to 1e-6."""
    from helpers import CONFIGS, read_summary, solve_cli, write_config
    raw = _column("unilateral", steps=(10.0, 20.0))
    raw["contact"]["projection"] = {"curve": 1, "curve_spans": 4}
    raw["contact"]["curve_points"] = 4
    for b in raw["beams"]:
        b["section"]["file"] = f"{CONFIGS}/{b['section']['file']}"
    serial = run_inline(raw, tmp_path / "serial")
    raw["output"] = {"vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "spans.yaml"), ranks=ranks,
                  extra=["--output-dir", str(tmp_path / "mpi"), "--quiet"], cwd=CONFIGS)
    assert p.returncode == 0, p.stderr
    par = read_summary(tmp_path / "mpi")
    assert par["ranks"] == ranks
    for a, b in zip(serial["steps"], par["steps"]):
        assert np.allclose(a["probes"]["soleus"]["displacement"], b["probes"]["soleus"]["displacement"],
                           rtol=1e-9, atol=1e-15)
        assert b["contact"][MG_SOL]["max_penetration"] == pytest.approx(a["contact"][MG_SOL]["max_penetration"],
                                                                       rel=1e-9, abs=1e-12)
        for name, rep in a["contact"].items():          # contact/kinks.py, from rank 0's gathered state
            assert rep["normal_turn_deg"] > 0.0
            assert b["contact"][name]["normal_turn_deg"] == pytest.approx(rep["normal_turn_deg"], rel=1e-6)


def test_a_restart_warns_of_its_own_last_level_only(tmp_path):
    """A unilateral run stopped after 10 N (penetration 0.17 mm there) and restarted to 100 N
    warns as the uninterrupted run does, of 100 N only (the stopped run's warning about its own
    last level was kept beside it); restarting the finished run warns once, not twice."""
    import os
    from helpers import CONFIGS, read_summary, solve_cli, write_config

    def column(steps):
        raw = _column("unilateral", steps=steps)
        for b in raw["beams"]:
            b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
        raw["output"] = {"vtk": False}
        return raw
    full = run_inline(column((10.0, 100.0)), tmp_path / "full")
    assert len(_notes(full)) == 1
    stopped = column((10.0,))
    p = solve_cli(write_config(stopped, tmp_path / "a.yaml"), extra=["--output-dir", str(tmp_path / "run"), "--quiet"])
    assert p.returncode == 0, p.stderr
    assert _notes(read_summary(tmp_path / "run")) and _notes(read_summary(tmp_path / "run")) != _notes(full)
    cfg = write_config(column((10.0, 100.0)), tmp_path / "b.yaml")
    for _ in range(2):                       # the stopped run, then the finished one
        p = solve_cli(cfg, extra=["--restart", str(tmp_path / "run"), "--quiet"])
        assert p.returncode == 0, p.stderr
        assert _notes(read_summary(tmp_path / "run")) == _notes(full)
        assert p.stderr.count("interpenetrate") == 1


def test_under_friction_the_warning_does_not_send_to_a_space_that_fails(tmp_path):
    """The paper's tendon, unilateral with Coulomb friction (mu = 0.5), 10 N: mg_sol
    interpenetrates and the warning named curve_spans 4 with curve_points 4 as the remedy; with
    friction that run fails at load factor 0.0006 of its first level (DIVERGED_DTOL, 2 502 Newton
    iterations; so do 5 spans of degree 0 and Bernstein 3 across).  The warning now says so;
    frictionless runs keep the advice (the test above)."""
    raw = _column("unilateral")
    raw["contact"]["tangential"] = {"law": "coulomb", "friction": 0.5}
    notes = _notes(run_inline(raw, tmp_path / "friction"))
    assert len(notes) == 1 and notes[0].startswith(f"warning: contact interface {MG_SOL}"), notes
    assert "under Coulomb friction every richer pressure across tried" in notes[0], notes[0]
    assert "none is known: read max_penetration" in notes[0], notes[0]
