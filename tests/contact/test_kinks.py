"""B's normal turning across element boundaries (contact/kinks.py): none on a prismatic beam at
rest, the exact angle atan(4δ/L_e) where one element's middle node moves by δ along the normal,
and the end-of-run note above TURN_NOTE_DEG."""
import numpy as np
import pytest

from helpers import build_problem


def _problem(twist: float):
    from ancf_petsc.workflows.envelope import NEO, EnvelopeCell, cell_config
    raw = cell_config(EnvelopeCell(NEO, twist, "uniform", "sliding", 0.0, 4))
    raw.setdefault("output", {})["dir"] = "unused"
    P, _ = build_problem(raw)
    return P, P.gather(P.q0), P.model.connectivity()


def test_the_reference_surface_turns_by_nothing_straight_and_little_twisted():
    from ancf_petsc.contact.kinks import normal_turns
    P, q, conn = _problem(0.0)
    assert max(normal_turns(P.contact, q, conn).values()) < 1e-4
    P, q, conn = _problem(180.0)
    turns = normal_turns(P.contact, q, conn)
    assert set(turns) == {i.name for i in P.contact.interfaces}
    assert 0.0 < max(turns.values()) < 0.1                  # 0.07 deg: 45 deg of twist an element


def test_a_middle_node_moved_along_the_normal_turns_it_by_atan_4_delta_over_le():
    """Prismatic beam: the centre line of B's first element becomes y = 4δ ξ(1 − ξ) (ξ ∈ [0, 1])
    along the normal n̂ at the curve's middle, so at its end the surface's tangent, and the normal
    at that place, turn by atan(4δ / L_e) against the straight next element."""
    from ancf_petsc.contact.kinks import normal_turns
    P, q, conn = _problem(0.0)
    pj = P.contact.projector
    first, _, T = (v[0] for v in pj.wrap_bounds(np.array([0])))
    x_of = lambda els: q[conn[els]].reshape(len(els), -1, 3)      # noqa: E731
    _, Yz, _, _, _ = pj.surface(x_of, np.array([0]), np.array([first]), np.array([1.0]), np.array([T / 2]))
    n = np.cross(Yz[0, :, 1], Yz[0, :, 0])
    n /= np.linalg.norm(n)
    assert abs(n[0]) < 1e-12                                  # in the section's plane
    B = P.contact.interfaces[0].b
    delta, Le = 1e-4, float(np.ptp(B.x_nodes)) / B.n_elements
    moved = q.copy()
    moved[conn[first][1], 0] += delta * n                     # r of the middle node
    turn = normal_turns(P.contact, moved, conn)[P.contact.interfaces[0].name]
    assert abs(turn - np.degrees(np.arctan(4.0 * delta / Le))) < 1e-6


def test_a_turn_above_the_threshold_is_noted_once_and_made_again_on_restart():
    from ancf_petsc.contact.kinks import TURN_NOTE_DEG, turn_notes
    from ancf_petsc.contact.reports import made_at_the_end
    steps = [{"load_factor": 100.0, "contact": {"a": {"normal_turn_deg": TURN_NOTE_DEG - 1.0}}},
             {"load_factor": 200.0, "contact": {"a": {"normal_turn_deg": TURN_NOTE_DEG + 1.5},
                                                 "b": {"normal_turn_deg": 1.0}}}]
    notes = turn_notes(None, steps)
    assert len(notes) == 1 and " a:" in notes[0] and "200" in notes[0] and "6.5" in notes[0]
    assert made_at_the_end(notes[0])
    assert turn_notes(None, steps[:1]) == []


def test_a_kink_next_to_a_point_force_is_not_sent_to_more_elements(tmp_path):
    """The paper's tendon at 90 deg (2 axial points): B's normal turned 3.4 deg at 4 elements and
    7.1 deg at 16, an element from the soleus' point force on r, and the note said 'more elements
    along the beams make the surface smoother'.  Now it names the place and the point force."""
    import copy
    from helpers import load_raw, run_inline
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["geometry"]["twist_deg"] = 90.0
    for b in raw["beams"]:
        b["elements"], b["axial_points"] = 16, 2
    raw["steps"], raw["output"] = [100.0, 400.0], {"vtk": False}
    s = run_inline(copy.deepcopy(raw), tmp_path)
    rep = s["steps"][-1]["contact"]["mg_sol (soleus|medial_gastrocnemius)"]
    assert rep["normal_turn_deg"] > 6.0 and rep["normal_turn_x"] == pytest.approx(0.07 * 15 / 16, rel=1e-12)
    note = next(w for w in s["warnings"] if w.startswith("note: the surface's normal turns"))
    assert "at x = 65.62 mm" in note and "point force on r of loads[0] (soleus)" in note
    assert "more elements along the beams make the surface smoother" not in note
