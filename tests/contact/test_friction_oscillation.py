"""The pressed strips (configs/friction_pressed_strips.yaml) meshed finer: the pressure oscillates
in sign near the gripped end and Coulomb's bound μ ∫ p⁺ dA carries more than μN (1.011 μN at
8 elements, μ = 0.5). The run says so once (contact/oscillation.py); coarser meshes do not."""
import numpy as np
import pytest

from helpers import load_raw, run_inline
from ancf_petsc.contact.oscillation import OSCILLATION_NOTE
from ancf_petsc.contact.reports import made_at_the_end

N, LENGTH = 0.01, 0.02                     # the strips' pressing force [N] and length [m]
LEVELS = [1, 1.25, 1.5]                    # pressed, then sliding out


def strips(elements: int, mu: float = 0.5) -> dict:
    """The shipped strips with ``elements`` per beam: the base held at every node, the uniform
    line load N / L as consistent nodal forces (1 4 1 / 6 per element), the first levels."""
    raw = load_raw("friction_pressed_strips.yaml")
    nodes = 2 * elements + 1
    for beam in raw["beams"]:
        beam["elements"] = elements
    raw["boundary_conditions"] = ([{"beam": "base", "node": i, "fix": "clamped"} for i in range(nodes)]
                                  + raw["boundary_conditions"][-2:])
    force = np.zeros(nodes)
    for e in range(elements):
        force[2 * e:2 * e + 3] += N / elements * np.array([1.0, 4.0, 1.0]) / 6.0
    curve = raw["loads"][0]["curve"]
    raw["loads"] = [{"beam": "slider", "node": i, "force": [0.0, 0.0, -float(f)], "curve": curve}
                    for i, f in enumerate(force)]
    raw["contact"]["tangential"]["friction"] = mu
    # the quadratic pressure along the beam, friction's default until 2026-12-07 (now linear:
    # config/contact.default_axial), whose oscillation the warning is about
    raw["contact"]["projection"] = {"axial": 2}
    raw["steps"] = LEVELS
    return raw


def _notes(summary) -> list[str]:
    return [w for w in summary["warnings"] if OSCILLATION_NOTE in w]


def test_the_shipped_nodal_loads_are_the_strips_at_4_elements():
    """``strips`` builds the shipped config's loads and supports (its other meshes are these)."""
    raw, shipped = strips(4), load_raw("friction_pressed_strips.yaml")
    assert raw["boundary_conditions"] == shipped["boundary_conditions"]
    for a, b in zip(raw["loads"], shipped["loads"]):
        assert np.allclose(a["force"], b["force"], rtol=1e-9) and a["node"] == b["node"]


def test_an_oscillating_pressure_under_friction_is_reported(tmp_path):
    """8 elements, mu = 0.5: the grip carries 1.011 mu N while sliding; one warning names the
    interface, the worst level, the ratio, the cause and both remedies (2 s)."""
    s = run_inline(strips(8), tmp_path)
    assert s["status"] == "completed"
    assert s["steps"][-1]["reactions"]["grip"][0] / (0.5 * N) == pytest.approx(1.0108, abs=2e-4)
    notes = _notes(s)
    assert len(notes) == 1, s["warnings"]
    note = notes[0]
    assert note.startswith("warning: contact interface interface (base|slider): "), note
    for words in ("at 2 level(s) (worst at load factor 1.5)", "reach 1.011 x mu N",
                  "the friction force is 1.011 x mu N", "inf-sup", "near a supported end",
                  "contact.projection: {axial: 1}", "contact.axial_points: 2", "with either 1.000"):
        assert words in note, (words, note)
    assert made_at_the_end(note)                      # a restart makes it again, not twice
    rep = s["steps"][-1]["contact"]["interface (base|slider)"]
    assert rep["pull_within_elements"] == pytest.approx(-rep["tension_force"], rel=1e-12)


@pytest.mark.parametrize("elements, mu", [(1, 1.0), (2, 1.0), (4, 1.0), (4, 0.5)])
def test_coarser_strips_are_silent(tmp_path, elements, mu):
    """1, 2 and 4 elements carry mu N (no point pulls): no warning, even at mu = 1."""
    s = run_inline(strips(elements, mu), tmp_path)
    assert s["status"] == "completed" and not _notes(s), s["warnings"]
    assert all(r["pull_within_elements"] == 0.0 for st in s["steps"] for r in st["contact"].values())


@pytest.mark.parametrize("remedy", [{"projection": {"axial": 1}}, {"axial_points": 2}])
def test_the_remedies_named_silence_it(tmp_path, remedy):
    """8 elements with the remedies the warning names: mu N (to 1e-8), no pull, no warning."""
    raw = strips(8)
    del raw["contact"]["projection"]
    raw["contact"].update(remedy)
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed" and not _notes(s), s["warnings"]
    assert s["steps"][-1]["reactions"]["grip"][0] / (0.5 * N) == pytest.approx(1.0, abs=1e-8)


@pytest.mark.mpi
def test_the_warning_is_the_same_on_2_ranks(tmp_path):
    """The pull within elements is summed over the ranks: the same warning on 1 and 2 ranks."""
    from helpers import run_on_ranks
    runs = run_on_ranks(strips(8), tmp_path, ranks=(1, 2))
    one, two = (_notes(s) for _, s in runs.values())
    assert len(one) == 1 and one == two, (one, two)


def test_the_default_linear_pressure_is_told_other_remedies(tmp_path):
    """16 elements, mu = 1, friction's default pressure (linear along the beam): pulled back past
    the reversal the grip carries 1.0055 mu N and the warning named contact.projection: {axial: 1},
    the setting in use; it now names {axial: 0} and 2 axial points, which carry mu N (5 s)."""
    raw = strips(16, 1.0)
    del raw["contact"]["projection"]
    raw["steps"] = [1, 1.5, 2, 2.1, 2.2, 2.3, 2.4]
    s = run_inline(raw, tmp_path / "default")
    assert s["steps"][-1]["reactions"]["grip"][0] / N == pytest.approx(-1.0055, abs=2e-4)
    notes = _notes(s)
    assert len(notes) == 1, s["warnings"]
    assert "{axial: 1}" not in notes[0] and "degree 1 along the beam" in notes[0], notes[0]
    for words in ("contact.projection: {axial: 0}", "contact.axial_points: 2", "1.006 x mu N"):
        assert words in notes[0], (words, notes[0])
    for name, remedy, ratio in (("axial0", {"projection": {"axial": 0}}, 1.0),
                                ("points2", {"axial_points": 2}, 1.0009)):
        fixed = dict(raw, contact=dict(raw["contact"], **remedy))
        s = run_inline(fixed, tmp_path / name)
        assert s["status"] == "completed" and not _notes(s), s["warnings"]
        assert -s["steps"][-1]["reactions"]["grip"][0] / N == pytest.approx(ratio, abs=2e-4)
