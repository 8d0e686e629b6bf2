"""Coulomb friction takes the pressure linear along the beam unless the config gives its degree
(config/contact.default_axial; docs/interface.md, "Friction's pressure along the beam").  On the
quadratic pressure, friction's default until 2026-12-07, the paper's tendon with μ = 3 pulled by
the soleus to 10 N at 8 elements pressed its interfaces by 1 154 / 149 / 210 N (coefficients
±2.9e8 Pa): friction's bounds read the oscillating pointwise pressure and carried it into the
answer (the soleus end 0.0880 mm against 0.1097 mm; 2 / 16 elements 0.0695 / 0.0925 mm, the
linear pressure's 0.1371 / 0.1097 mm)."""
import os

from helpers import CONFIGS, load_raw, run_inline
from ancf_petsc.config.parse import parse_config


def _tendon(contact: dict, elements: int = 4) -> dict:
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
        b["elements"] = elements
    raw["contact"] = {"mode": "sliding"} | contact
    raw["steps"] = [10.0]
    raw["output"] = {"vtk": False}
    return raw


def test_the_pressure_along_the_beam_by_law():
    coulomb = {"tangential": {"law": "coulomb", "friction": 0.3}}
    cases = [({}, (2, 1)), (coulomb, (1, 1)), ({"tangential": {"law": "elastic", "stiffness": 1e9}}, (2, 1)),
             (coulomb | {"projection": {"axial": 2}}, (2, 1)), (coulomb | {"axial_points": 2}, (1, 1)),
             (coulomb | {"projection": {"curve": 0}}, (1, 0))]
    for contact, expected in cases:
        assert parse_config(_tendon(contact)).contact.projection == expected, contact


def test_more_contact_points_along_keep_the_elements_degree():
    """contact.axial_points: 4 alone made the pressure cubic along the quadratic elements (the
    default axial_points - 1), richer than their trace: the paper's tendon (ψ = 45°, 4 elements,
    sliding) 1.1 % stiffer at 400 N (soleus 6.1341 against 6.2046 mm; 6.2015 with axial: 2 on the
    4 points) and mg_sol pressed by 3 703 N at 10 N (36 N).  The default now stops at the
    elements' degree along; an explicit axial: 3 is still the config's choice."""
    for contact, expected in (({"axial_points": 4}, (2, 1)), ({"mode": "unilateral", "axial_points": 5}, (2, 1)),
                              ({"axial_points": 4, "projection": {"axial": 3}}, (3, 1)),
                              ({"axial_points": 2}, (1, 1))):
        assert parse_config(_tendon(contact)).contact.projection == expected, contact


def test_friction_at_mu_3_presses_about_its_load(tmp_path):
    """8 elements, μ = 3, 10 N on the soleus: each interface's pressing force stays near the load's
    scale (measured 0.5-1.2 N), not the quadratic pressure's 149-1 154 N."""
    s = run_inline(_tendon({"tangential": {"law": "coulomb", "friction": 3.0}}, elements=8), tmp_path)
    assert s["status"] == "completed"
    pressing = [v["pressing_force"] for v in s["steps"][-1]["contact"].values()]
    assert max(pressing) < 5.0, pressing
    ux = s["steps"][-1]["probes"]["soleus"]["displacement"][0]
    assert abs(ux - 1.0967e-4) < 2e-7, ux


def test_a_quadratic_pressure_per_element_is_refused_under_friction():
    """projection {axial: 2, per_element: true} has arbitrary multipliers (docs/contact.md) and
    Coulomb's bounds read them: the pressed strips at 2 elements, mu = 0.5, completed with the grip
    at 5.5-28.8 x mu N (39 x at 4 elements), the tendon failed at its first step.  Refused, naming
    the key and the fix; axial 1 per element (mu N to 1e-12) and the frictionless model run."""
    import pytest
    from ancf_petsc.config import ConfigError
    coulomb = {"tangential": {"law": "coulomb", "friction": 0.5}}
    with pytest.raises(ConfigError) as err:
        parse_config(_tendon(coulomb | {"projection": {"axial": 2, "per_element": True}}))
    assert str(err.value).startswith("contact.projection.per_element: "), str(err.value)
    assert "give axial: 1 or 0 with it" in str(err.value) and str(err.value).endswith("got true")
    for contact in (coulomb | {"projection": {"axial": 1, "per_element": True}},
                    {"projection": {"axial": 2, "per_element": True}}):
        assert parse_config(_tendon(contact)).contact.per_element, contact


def test_a_degree_above_the_contact_points_names_them():
    """contact.axial_points: 2 with projection {axial: 2} said only 'must be <= 1; got 2'."""
    import pytest
    from ancf_petsc.config import ConfigError
    with pytest.raises(ConfigError) as err:
        parse_config(_tendon({"axial_points": 2, "projection": {"axial": 2},
                              "tangential": {"law": "coulomb", "friction": 0.5}}))
    assert str(err.value) == ("contact.projection.axial: must be <= contact.axial_points - 1 = 1 (the "
                              "contact points along the beam determine no higher degree): give "
                              "contact.axial_points: 3 or a lower axial; got 2"), str(err.value)


def test_more_pressure_functions_across_than_the_sections_determine_are_refused_under_friction():
    """The paper's tendon (ψ = 45°, 4 elements, 10 N) under Coulomb friction with more than p + 1
    pressure functions across sections of degree p: curve: 3 and curve_spans: 4 failed at the
    first level (Newton cycles, stick-slip flips; 33103 with 5 functions too), curve_spans: 3
    (4 functions, μ = 0.5) completed with the soleus end at 0.069 mm against the default space's
    0.160, the interfaces pressed by 102 / 1 081 / 395 N (default 0.7 / 0.2 / 0.6 N).  Refused,
    naming the key;
    p + 1 functions, other elements' richer sections and frictionless models still run."""
    import pytest
    from ancf_petsc.config import ConfigError
    coulomb = {"tangential": {"law": "coulomb", "friction": 0.5}}
    for projection, key, got in (({"curve": 3}, "curve", 3), ({"curve_spans": 4}, "curve_spans", 4),
                                 ({"curve_spans": 3}, "curve_spans", 3),
                                 ({"curve": 0, "curve_spans": 4}, "curve_spans", 4)):
        with pytest.raises(ConfigError) as err:
            parse_config(_tendon(coulomb | {"curve_points": 4, "projection": projection}))
        text = str(err.value)
        assert text.startswith(f"contact.projection.{key}: under Coulomb friction at most 3 pressure "
                               "functions across"), text
        assert "give curve + curve_spans <= 3" in text and text.endswith(f"; got {got}"), text
    richer = _tendon(coulomb | {"curve_points": 4, "projection": {"curve": 3}})
    for b in richer["beams"]:
        b["element"] = 33103
    assert parse_config(richer).contact.projection == (1, 3)
    for contact in (coulomb | {"curve_points": 3, "projection": {"curve": 2}},
                    coulomb | {"projection": {"curve_spans": 2}},
                    {"mode": "unilateral", "curve_points": 4, "projection": {"curve_spans": 4}}):
        assert parse_config(_tendon(contact)).contact is not None, contact


def test_more_pressure_functions_across_than_the_sections_determine_are_refused_under_sliding():
    """The sliding law holds every pressure function, so more than p + 1 across lock the
    sections and leave the multipliers undetermined: the paper's tendon (ψ = 45°, 4 elements)
    with curve: 3 completed 1.3 % stiffer at 400 N (soleus 6.121 against 6.205 mm) with its
    interfaces pressed and pulled by 5.2e4 N (default: at most 1.1e3 N), curve_spans: 4 failed at
    194 N after 652 Newton iterations, curve: 5 at 2 elements at 2.9 N.  Refused, naming the key;
    p + 1 functions and the unilateral law (its extra functions open) still run."""
    import pytest
    from ancf_petsc.config import ConfigError
    for projection, key, got in (({"curve": 3}, "curve", 3), ({"curve_spans": 4}, "curve_spans", 4),
                                 ({"curve": 0, "curve_spans": 4}, "curve_spans", 4)):
        with pytest.raises(ConfigError) as err:
            parse_config(_tendon({"curve_points": 4, "projection": projection}))
        text = str(err.value)
        assert text.startswith(f"contact.projection.{key}: under the sliding law (every pressure function "
                               "held) at most 3 pressure functions across"), text
        assert "give curve + curve_spans <= 3, mode: unilateral" in text and text.endswith(f"; got {got}"), text
    for contact in ({"curve_points": 3, "projection": {"curve": 2}}, {"projection": {"curve_spans": 2}},
                    {"mode": "unilateral", "curve_points": 4, "projection": {"curve": 5}}):
        assert parse_config(_tendon(contact)).contact is not None, contact
