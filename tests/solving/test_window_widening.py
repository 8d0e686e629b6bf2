"""A level whose solves lose a contact point from its search window at every increment is solved
on with the whole partner beam as every point's window (solving/window_widening.py).

The window (``contact.search_margin`` of the partner beam per load step) only decides whether a
projection's result is accepted, so a run that widens goes on along the same iterates: with the
solves made to lose a point past the first level while the windows are narrow, the paper's
ψ = 45° tendon (4 elements: a window of 3 of them) widens there, completes, and repeats a run
that never lost one, bitwise; without the widening the same run fails there.  A restart of it
widens again; 2 and 3 ranks: tests/parallel/test_mpi.py."""
import numpy as np
import pytest

from contact.test_contact import achilles
from helpers import fail_solves, petsc_init, probes_table
from solving.test_fade_switch import run

STEPS = [100.0, 250.0, 400.0]


def column(steps=STEPS) -> dict:
    raw = achilles(elements=4, contact={"mode": "sliding"})
    raw["steps"] = list(steps)
    raw["output"] = {"vtk": False}
    # the secant predictor: a level retried after cut-backs starts as its first attempt did, so the
    # widened run repeats the narrow one bitwise; the tangent predictor (the default here) has no
    # factor of a converged state there and starts the retried level unpredicted
    raw["solver"] = {"predictor": "secant"}
    return raw


def lose_points_past(above: float, put=setattr) -> None:
    """Every SNES solve above load factor ``above`` fails as a contact point slid out of its
    window (DIVERGED_FNORM_NAN, the projection lost) while the windows are narrower than the
    whole partner beam (``put``: a monkeypatch's setattr, or setattr in a driver process)."""
    petsc_init()
    from ancf_petsc.solving.window_widening import whole_windows

    def narrow_past(solver, lam):
        return lam > above * (1.0 + 1e-12) and not whole_windows(solver.problem.contact.projector)
    fail_solves(narrow_past, put, lost=True)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    res = run(column(), tmp_path_factory.mktemp("narrow"))
    assert res.status == "completed", res.message
    assert "search_window_whole_from" not in res.summary
    return res.summary


def test_the_windows_widen_to_the_whole_partner_beam(tmp_path):
    petsc_init()
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from ancf_petsc.model.contact_setup import contact_for
    from ancf_petsc.solving.window_widening import WHOLE, whole_windows, widen
    from helpers import CONFIGS
    model = build_model(parse_config(column(), base_dir=CONFIGS))
    p = contact_for(model, parse_config(column(), base_dir=CONFIGS).contact, lambda *_: None).projector
    first = np.array([i.b.element_offset for i in p.interfaces])[p.points.itf]
    assert not whole_windows(p)
    assert np.all(p.hi - p.lo == 2)                        # 3 of the 4 elements
    widen(p, WHOLE)
    assert whole_windows(p)
    assert np.array_equal(p.lo, first) and np.array_equal(p.hi, first + 3)
    p.checkpoint()                                         # later checkpoints keep them whole
    assert np.array_equal(p.lo, first) and np.array_equal(p.hi, first + 3)


def test_a_level_that_loses_a_point_from_its_window_is_solved_with_whole_windows(
        tmp_path, monkeypatch, reference):
    lose_points_past(STEPS[0], monkeypatch.setattr)
    lines = []
    res = run(column(), tmp_path / "widened", log=lines.append)
    assert res.status == "completed", res.message
    s = res.summary
    assert s["search_window_whole_from"] == STEPS[0]
    assert "contact search windows the whole partner beam from load factor 100" in s["message"]
    assert any("slid out of its search window (0.1 of the partner beam per load step) at every "
               "increment; on with the whole partner beam as every point's window" in line
               and f"load factor {STEPS[0]:g}" in line for line in lines)
    assert np.array_equal(probes_table(s), probes_table(reference))
    assert [x["iterations"] for x in s["steps"]] == [x["iterations"] for x in reference["steps"]]
    # the test can tell: without the widening the run stops at the first level
    from ancf_petsc.solving.window_widening import WindowWidening
    monkeypatch.setattr(WindowWidening, "take", lambda *a: False)
    res = run(column(), tmp_path / "stopped")
    assert res.status == "failed" and len(res.summary["steps"]) == 1
    assert "DIVERGED_FNORM_NAN" in res.message and "search_window_whole_from" not in res.summary


def test_a_restart_after_the_widening_widens_again(tmp_path, monkeypatch, reference):
    lose_points_past(STEPS[0], monkeypatch.setattr)
    part = run(column(steps=STEPS[:2]), tmp_path / "part")
    assert part.summary["search_window_whole_from"] == STEPS[0]
    res = run(column(), tmp_path / "part", restart=str(tmp_path / "part"))
    assert res.status == "completed", res.message
    # widened from the restart on, not again at the next level
    assert res.summary["search_window_whole_from"] == STEPS[0]
    assert np.abs(probes_table(res.summary) - probes_table(reference)).max() \
        < 1e-8 * np.abs(probes_table(reference)).max()
