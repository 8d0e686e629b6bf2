"""Loads within the rounding of the elastic forces at rest: the run's own absolute tolerance (20 x
|F(q0, 0)|) is then above them, the unloaded state meets it, and the levels were reported at rest,
'completed', without a word."""
from helpers import load_raw, run_inline

NOTE = "within the rounding of the elastic forces at rest"


def bar(force: float) -> dict:
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["loads"][0]["traction_force"] = [force, 0.0, 0.0]
    raw["steps"] = [0.5, 1.0]
    raw["output"] = {"vtk": False}
    return raw


def test_loads_below_the_rounding_at_rest_are_named(tmp_path):
    """Before: the bar pulled by 4.5e-11 N (rounding at rest 3.1e-12 N, tolerance 6.2e-11 N) ended
    'completed' at u = 0 in 0 Newton iterations, where the exact answer is 2.0e-15 m, with no
    warning.  Now the run says the loads are within the rounding and not resolved."""
    s = run_inline(bar(4.5e-11), tmp_path)
    assert s["status"] == "completed" and s["steps"][0]["probes"]["tip"]["displacement"][0] == 0.0
    notes = [w for w in s["warnings"] if NOTE in w]
    assert len(notes) == 1 and "load factor 0.5" in notes[0] and "2.25e-11 N" in notes[0]


def test_loads_above_it_are_solved_without_the_warning(tmp_path):
    """The same bar at 4.5e-6 N (1e5 x the rounding) moves by the linear answer, no warning."""
    s = run_inline(bar(4.5e-6), tmp_path)
    u = s["steps"][-1]["probes"]["tip"]["displacement"][0]
    strain = 4.5e-6 / (3.14159265358979 * 0.006 * 0.004) / (9 * 50e6 * 1e6 / (3 * 50e6 + 1e6))
    assert abs(u / (0.1 * strain) - 1.0) < 1e-4
    assert not [w for w in s["warnings"] if NOTE in w]
