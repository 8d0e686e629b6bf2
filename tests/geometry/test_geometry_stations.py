"""Sections that change along the tendon (geometry.sections.stations): exact references for a
linearly tapered bar and a bar whose section turns in place, and contact with interfaces kept
equal at every station (docs/geometry.md)."""
import copy

import numpy as np
import pytest

from ancf_petsc.config.values import ConfigError
from ancf_petsc.config.parse import parse_config
from ancf_petsc.model.build import build_model, build_section_at
from helpers import run_inline

E, F = 1.0e9, 1.0            # Young's modulus [Pa], end force [N]: strains ~1e-4 (small strain)


def bar(stations, L, elements=4, degree=1):
    """One SVK beam (nu = 0) clamped at x = 0, a uniform end traction F at x = L."""
    return {"name": "bar", "geometry": {"length": L, "sections": {
                "spline_degree": degree,
                "stations": [{"x": x, "units": "mm", "axes": ["y", "z"], "outlines": {"bar": {"points": P}}}
                             for x, P in stations]}},
            "beams": [{"name": "bar", "section": {"shape": "outline", "loop": "bar"}, "elements": elements,
                       "material": {"model": "svk", "E": E, "nu": 0.0}}],
            "boundary_conditions": [{"beam": "bar", "node": "first", "fix": "clamped"}],
            "loads": [{"beam": "bar", "node": "last", "traction_force": [F, 0.0, 0.0]}],
            "probes": [{"name": "tip", "beam": "bar", "node": "last"}],
            "steps": [1.0], "output": {"vtk": False}}


def square(a):
    return [[-a / 2, -a / 2], [a / 2, -a / 2], [a / 2, a / 2], [-a / 2, a / 2]]


def ellipse(a, b, turn_deg, n=64):
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    th = np.deg2rad(turn_deg)
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    return (np.column_stack([a * np.cos(t), b * np.sin(t)]) @ R.T).tolist()


def gauss_point_areas(beam):
    """Area of the section rule at every axial Gauss point, (E, na)."""
    from ancf_petsc.physics.cubature import gauss_legendre
    _, wa = gauss_legendre(beam.axial_points)
    return beam.wq.reshape(beam.n_elements, beam.axial_points, -1).sum(axis=2) / wa


def test_linearly_tapered_bar_axial_stiffness(tmp_path):
    """Side a(x) from 2 to 1.4 mm: u = F/E ∫ dx / a(x)^2 = F L / (E a0 a1)."""
    L, a0, a1 = 0.04, 2.0e-3, 1.4e-3
    raw = bar([(0.0, square(2.0)), (L, square(1.4))], L)
    model = build_model(parse_config(copy.deepcopy(raw)))
    beam = model.beams[0]
    assert beam.dN.ndim == 4 and beam.ring_at is not None       # one rule per element
    h = L / beam.n_elements
    from ancf_petsc.physics.cubature import gauss_legendre
    xa, _ = gauss_legendre(beam.axial_points)
    xg = (np.arange(beam.n_elements)[:, None] + 0.5 * (xa + 1.0)) * h
    a = a0 + (a1 - a0) * xg / L
    assert np.allclose(gauss_point_areas(beam), a * a, rtol=1e-5, atol=0)    # interpolated in size
    u = run_inline(raw, tmp_path / "out")["steps"][-1]["probes"]["tip"]["displacement"][0]
    exact = F * L / (E * a0 * a1)
    print(f"\n  tapered bar: u = {u:.6e} m, F L/(E a0 a1) = {exact:.6e} m, {u / exact - 1:+.2e}")
    # the 1D answer neglects the slope of the tapered faces (3D: O(slope^2) ~ 1e-4 here)
    assert u == pytest.approx(exact, rel=1e-3)


def test_bar_whose_section_turns_in_place(tmp_path):
    """An ellipse turning by 60 degrees over the length: every section is the same ellipse, so
    the area is constant and u = F L / (E A).  (Blending the outlines point by point would make
    the middle section the ellipse turned by 30 degrees shrunk by cos 30: area x 0.75.)"""
    L, a, b = 0.06, 2.0, 1.0
    raw = bar([(0.0, ellipse(a, b, 0.0)), (L, ellipse(a, b, 60.0))], L, degree=3)
    spec = parse_config(copy.deepcopy(raw))
    model = build_model(spec)
    beam = model.beams[0]
    A = beam.section.area
    assert A == pytest.approx(np.pi * a * b * 1e-6, rel=2e-4)
    assert np.allclose(gauss_point_areas(beam), A, rtol=1e-4, atol=0)
    from ancf_petsc.geometry_input.tendon import build_tendon
    tendon = build_tendon(spec.sections)
    for x, turn in ((0.25 * L, 15.0), (0.5 * L, 30.0), (L, 60.0)):
        sec = build_section_at(spec.beams[0].section, tendon, x)
        ang = 0.5 * np.degrees(np.arctan2(2 * sec.Syz, sec.Syy - sec.Szz))
        assert ang == pytest.approx(turn, abs=0.05), x
        assert sec.area == pytest.approx(A, rel=1e-4)
    u = run_inline(raw, tmp_path / "out")["steps"][-1]["probes"]["tip"]["displacement"][0]
    print(f"\n  turning section: u = {u:.6e} m, F L/(E A) = {F * L / (E * A):.6e} m, "
          f"{u * E * A / (F * L) - 1:+.2e}")
    assert u == pytest.approx(F * L / (E * A), rel=5e-4)


@pytest.mark.parametrize("second", ["egg", "circle"])
def test_symmetric_subtendon_in_a_section_turning_by_more_than_90_degrees(second):
    """An elliptic subtendon beside an egg-shaped (or circular) one, the whole section turned by
    100 degrees between the stations: the ellipse on its own matches equally at +100 and -80
    degrees; the smallest turn reversed its points against the section's and it shrank to 0 mm^2
    half-way (6.28 mm^2 at the stations).  Every outline keeps its area all along."""
    from ancf_petsc.config.sections import parse_sections
    from ancf_petsc.geometry_input import polyline as pl
    from ancf_petsc.geometry_input.tendon import build_tendon
    t = np.linspace(0.0, 2 * np.pi, 120, endpoint=False)
    a = np.column_stack([2.0 * np.cos(t) - 3.0, np.sin(t)])
    b = np.column_stack([1.5 * np.cos(t) + 0.4 * np.cos(2 * t) + 3.0, 1.2 * np.sin(t)]) if second == "egg" \
        else np.column_stack([1.3 * np.cos(t) + 3.0, 1.3 * np.sin(t)])
    th = np.deg2rad(100.0)
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    st = [{"x": x, "units": "mm", "axes": ["y", "z"],
           "outlines": {"a": {"points": (a @ Q.T).tolist()}, "b": {"points": (b @ Q.T).tolist()}}}
          for x, Q in ((0.0, np.eye(2)), (0.05, R))]
    tendon = build_tendon(parse_sections({"stations": st}, "geometry.sections", ".", 0.05))
    assert np.rad2deg(tendon.field.theta[0]) == pytest.approx(100.0, abs=0.05)
    for n, P in (("a", a), ("b", b)):
        for x in (0.0125, 0.025, 0.0375):
            ring = tendon.field.ring_at(n, x)
            assert pl.signed_area(ring) == pytest.approx(pl.signed_area(P) * 1e-6, rel=2e-3), (n, x)


def two_halves(bulge_right: float, iface_end: float = 1.0) -> dict:
    """Two subtendons sharing the straight interface 'mid' (curves form); the right one bulges."""
    return {"units": "mm", "axes": ["y", "z"],
            "curves": {"mid": [[0.0, -1.0], [0.0, 0.0], [0.0, iface_end]],
                       "left_outer": [[0.0, iface_end], [-1.0, 0.7], [-1.4, 0.0], [-1.0, -0.7], [0.0, -1.0]],
                       "right_outer": [[0.0, -1.0], [bulge_right * 0.7, -0.7], [bulge_right, 0.0],
                                       [bulge_right * 0.7, 0.7], [0.0, iface_end]]},
            "outlines": {"left": {"curves": ["mid", "left_outer"]},
                         "right": {"curves": ["right_outer", "-mid"]}}}


def halves_config(st1: dict) -> dict:
    return {"name": "halves", "geometry": {"length": 0.03, "sections": {"stations": [
                dict(two_halves(1.4), x=0.0), dict(st1, x=0.03)]}},
            "beams": [{"name": n, "section": {"shape": "outline", "loop": n}, "elements": 2,
                       "material": {"model": "neo-hookean", "mu": 1.0e6, "bulk_modulus": 1.0e7}}
                      for n in ("left", "right")],
            "boundary_conditions": [{"beam": n, "node": "first", "fix": "clamped"} for n in ("left", "right")],
            "loads": [{"beam": "right", "node": "last", "force": [0.05, 0.0, 0.0]}],
            "probes": [{"name": n, "beam": n, "node": "last"} for n in ("left", "right")],
            "steps": [1.0], "contact": {"mode": "sliding"}, "output": {"vtk": False}}


def test_contact_with_interfaces_equal_at_every_station(tmp_path):
    raw = halves_config(two_halves(2.0))           # the right outline grows, 'mid' stays
    model = build_model(parse_config(copy.deepcopy(raw)))
    assert any("interfaces shared by every station" in ln for ln in model.geometry_report)
    right = model.beams[1]
    areas = gauss_point_areas(right)
    assert areas[-1, -1] > 1.2 * areas[0, 0]                    # the right section grows along x
    s = run_inline(raw, tmp_path / "out")       # contact checks that the reference gaps are zero
    assert s["status"] == "completed"
    last = s["steps"][-1]
    gap = last["contact"]["mid (left|right)"]
    # held closed under load: the weighted gaps exactly, the local gap to well below a micron
    assert gap["max_weighted_gap"] < 1e-12 and gap["max_gap"] < 1e-6
    # the pulled right beam bends towards +y (its section grows on that side) and pushes the
    # left one along through the interface
    uy = {n: last["probes"][n]["displacement"][1] for n in ("left", "right")}
    assert uy["right"] > 0 and uy["left"] > 0.5 * uy["right"]
    # an interface that differs between the stations is not supported with contact (yet)
    bad = halves_config(two_halves(2.0, iface_end=1.2))
    with pytest.raises(ConfigError, match=r"^contact: sections that vary along x work with contact only "
                                          r"when every interface curve is the same at every station"):
        build_model(parse_config(bad))
    bad["contact"] = None                                        # without contact it is fine
    assert build_model(parse_config(bad)).beams[1].ring_at is not None
