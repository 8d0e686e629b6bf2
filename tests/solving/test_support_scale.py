"""The support check does not depend on the model's size: the pressed strips scaled to fascicle
size (lengths × s, forces × s², the same stresses) are held as at 20 mm, and solve to the same
answers scaled."""
import numpy as np
import pytest

from helpers import build_problem, load_raw, run_inline
from ancf_petsc.solving.supports import free_rigid_motions, rigid_mode_gram


def scaled_strips(s: float) -> dict:
    """configs/friction_pressed_strips.yaml with every length × s and every force × s²."""
    raw = load_raw("friction_pressed_strips.yaml")
    raw["geometry"]["length"] *= s
    for beam in raw["beams"]:
        for curve in beam["section"]["curves"]:
            curve["points"] = [[s * y, s * z] for y, z in curve["points"]]
    for load in raw["loads"]:
        load["force"] = [s * s * f for f in load["force"]]
    grip = raw["boundary_conditions"][-1]
    grip["displacement"]["r"]["x"] *= s
    return raw


@pytest.mark.parametrize("s", [0.1, 0.01, 10.0])
def test_the_support_check_of_scaled_strips_is_the_check_at_20_mm(s):
    """Before: at 2 mm (s = 0.1) 'nothing holds slider (free: rotation about x)', at 0.2 mm about
    x, y and z too: its turns, held by the r_y supports and the contact, were measured in metres
    (6.2e-4 at 20 mm, 6.2e-5 at 2 mm against the bound 1e-4).  Now in units of the beams' length:
    the same Gram eigenvalues at every size (3.1e-2 the smallest root)."""
    def roots(raw):
        P, _ = build_problem(raw)
        gram, _ = rigid_mode_gram(P)
        return np.sqrt(np.clip(np.linalg.eigvalsh(gram), 0.0, None)), free_rigid_motions(P)
    base, free = roots(scaled_strips(1.0))
    scaled, free_scaled = roots(scaled_strips(s))
    assert free == [] and free_scaled == []
    assert np.abs(scaled - base).max() <= 1e-8 * base.max()
    assert base.min() > 1e-2


def test_strips_an_eighth_the_size_solve_to_the_scaled_answers(tmp_path):
    """At s = 1/8 (2.5 mm; a power of two, so that the rounding scales exactly) the run was
    refused; now it completes and its grip force and displacement are the 20 mm run's x s² and
    x s to 1e-9, in as many Newton iterations."""
    runs = {}
    for s in (1.0, 0.125):
        raw = scaled_strips(s)
        raw["steps"] = [1, 1.05, 1.1]
        runs[s] = run_inline(raw, tmp_path / str(s))
        assert runs[s]["status"] == "completed"
    for a, b in zip(runs[1.0]["steps"], runs[0.125]["steps"]):
        assert b["iterations"] == a["iterations"]
        force = np.array(a["reactions"]["grip"])
        assert np.abs(np.array(b["reactions"]["grip"]) / 0.125 ** 2 - force).max() <= 1e-9 * np.abs(force).max() + 1e-15
        u = np.array(a["probes"]["grip"]["displacement"])
        assert np.abs(np.array(b["probes"]["grip"]["displacement"]) / 0.125 - u).max() <= 1e-9 * np.abs(u).max()

