"""A settled active set (solving/newton.py): where the last increment's prediction and check
changed no status, the increment is solved with the status kept before any prediction, and the
check reads the status from the converged solve's last evaluation (contact.decide_kept).  Both
are measured against the path that predicts every increment and evaluates every check again."""
import numpy as np
import pytest

from ancf_petsc.contact import contact as contact_module
from ancf_petsc.petsc.complementarity import ComplementarityPredictor
from ancf_petsc.solving import contact_steps

from helpers import CONFIGS, run_inline, unilateral_stride_frames as stride_frames


def _probes(s: dict) -> np.ndarray:
    return np.array([st["probes"][n]["displacement"] for st in s["steps"] for n in sorted(st["probes"])])


def _counted(monkeypatch, cls, name: str, counts: dict) -> None:
    """Count the calls of ``cls.name`` (and what they returned) in ``counts``."""
    original = getattr(cls, name)

    def wrapper(*args, **kwargs):
        out = original(*args, **kwargs)
        counts[bool(out)] = counts.get(bool(out), 0) + 1
        return out
    monkeypatch.setattr(cls, name, wrapper)


@pytest.mark.slow
def test_a_settled_active_set_is_solved_before_it_is_predicted(tmp_path, monkeypatch):
    """18 loading frames: most are not predicted, and every frame reaches the state the
    Josephy–Newton path reaches (to the solves' tolerance), its Newton count within the one more
    prediction of a frame whose check changed the status."""
    raw = stride_frames()
    predictions: dict = {}
    _counted(monkeypatch, ComplementarityPredictor, "predict", predictions)
    settled = run_inline(raw, tmp_path / "settled", base_dir=CONFIGS)
    made = sum(predictions.values())
    predictions.clear()
    never = property(lambda self: False, lambda self, value: None)         # no increment settles
    monkeypatch.setattr(ComplementarityPredictor, "settled", never, raising=False)
    every = run_inline(raw, tmp_path / "every", base_dir=CONFIGS)
    assert settled["status"] == every["status"] == "completed"
    assert len(settled["steps"]) == len(every["steps"]) == 18
    assert sum(predictions.values()) >= 17 and made <= sum(predictions.values()) // 2, (made, predictions)
    a, b = _probes(settled), _probes(every)
    assert np.abs(a - b).max() <= 1e-7 * np.abs(b).max()
    assert every["newton_iterations"] <= settled["newton_iterations"] <= every["newton_iterations"] + 2 * made


@pytest.mark.slow
def test_the_check_reads_the_converged_evaluation(tmp_path, monkeypatch):
    """The exact rule's check of a converged state reads its status from the solve's last
    evaluation: the same Newton counts frame by frame and the same probes as evaluating the
    residual there again; where the rule would change the status it evaluates after all."""
    raw = stride_frames(0, 16)
    kept: dict = {}
    _counted(monkeypatch, contact_module, "decide_kept", kept)
    monkeypatch.setattr(contact_steps, "decide_kept", contact_module.decide_kept)
    read = run_inline(raw, tmp_path / "read", base_dir=CONFIGS)
    monkeypatch.setattr(contact_steps, "decide_kept", lambda *args: False)
    evaluated = run_inline(raw, tmp_path / "evaluated", base_dir=CONFIGS)
    assert read["status"] == evaluated["status"] == "completed"
    assert kept.get(True, 0) >= 10, kept
    assert [st["iterations"] for st in read["steps"]] == [st["iterations"] for st in evaluated["steps"]]
    a, b = _probes(read), _probes(evaluated)
    assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max()


@pytest.mark.slow
def test_a_prediction_that_repeats_the_failed_settled_solve_is_not_solved(tmp_path, monkeypatch):
    """The second subject's 120° uniform unilateral column to 400 N: the settled solve of 400 N
    fails, and the prediction after it changes no status.  Solving that prediction repeats the
    failure (the same 15 iterations); skipping it reaches the same states in exactly those
    iterations fewer.  (Found on the 90° gastrocnemius-biased column at 600 N until the outlines
    were started at their farthest vertex, geometry_input/polyline.py; that column repeats none.)"""
    from ancf_petsc.solving.newton import PhasedNewton
    from ancf_petsc.workflows.envelope import SUBJECT2, EnvelopeCell, cell_config

    raw = cell_config(EnvelopeCell(SUBJECT2, 120.0, "uniform", "unilateral", levels=(30.0, 100.0, 200.0, 400.0)))
    seen: dict = {}
    _counted(monkeypatch, PhasedNewton, "_repeats", seen)
    skipped = run_inline(raw, tmp_path / "skipped", base_dir=CONFIGS)
    monkeypatch.setattr(PhasedNewton, "_repeats", lambda self, status: False)
    solved = run_inline(raw, tmp_path / "solved", base_dir=CONFIGS)
    assert skipped["status"] == solved["status"] == "completed"
    assert seen.get(True) == 1, seen        # (and one settled failure whose prediction changes the status)
    a, b = _probes(skipped), _probes(solved)
    assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max()
    its = [st["iterations"] for st in skipped["steps"]], [st["iterations"] for st in solved["steps"]]
    assert its[0][:3] == its[1][:3] and its[1][3] - its[0][3] >= 10, its
