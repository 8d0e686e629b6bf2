"""Newton steps held to a few fade-band widths of partner-place motion (contact/band_step.py)."""
import numpy as np
import pytest

from ancf_petsc.contact import band_step
from helpers import CONFIGS, probes_table, run_inline, subject2_stride_frames


@pytest.mark.slow
def test_steps_held_to_the_band_reach_the_same_states_in_fewer_iterations(tmp_path, monkeypatch):
    """The second subject's 90° uniform unilateral stride, frames 1-19: with full Newton steps
    partner places crossed a fade band in one iterate (1.4 mm against a 0.9 mm band) and Newton
    cycled (frame 19: period 3, |F| 0.044 / 0.465 / 0.421 N; 967 Newton iterations measured).
    Held to ``solver.band_step`` (1.5) band widths per step, under half the iterations and the
    same states through frame 13.  Frame 14 has two stable equilibria 11 µm apart (both converge
    to |F| < 1e-8 N with no negative tangent eigenvalue): which one a solve reaches depends on its
    path, so from there on both runs are only checked to converge near each other."""
    raw = subject2_stride_frames(90.0, "uniform", 19)
    raw.setdefault("solver", {})["band_step"] = 1.5
    calls = []
    moves = band_step.band_moves

    def counted(c, yl):
        calls.append(moves(c, yl))
        return calls[-1]
    monkeypatch.setattr("ancf_petsc.petsc.step_limits.band_moves", counted)
    held = run_inline(raw, tmp_path / "held", base_dir=CONFIGS)
    raw["solver"]["band_step"] = 0.0
    n_held = len(calls)
    free = run_inline(raw, tmp_path / "free", base_dir=CONFIGS)
    assert held["status"] == free["status"] == "completed"
    assert sum(m > 1.5 for m in calls) >= 10, "no step was held"
    assert len(calls) == n_held, "band_step: 0 still limits"
    its = held["newton_iterations"], free["newton_iterations"]
    assert 2 * its[0] < its[1], its
    a, b = probes_table(held).reshape(19, -1), probes_table(free).reshape(19, -1)
    scale = np.abs(b).max()
    assert np.abs(a[:13] - b[:13]).max() <= 1e-7 * scale
    assert np.abs(a[13:] - b[13:]).max() <= 1e-2 * scale            # the equilibria 11 µm apart
    assert all(s["negative_eigenvalues"] == 0 for r in (held, free) for s in r["steps"][13:14])


def test_band_step_is_checked():
    """``solver.band_step`` is a number ≥ 0 (0, the default: no limit)."""
    from ancf_petsc.config.solving import parse_solver
    from ancf_petsc.config.values import ConfigError
    assert parse_solver({"band_step": 1.5}).band_step == 1.5
    assert parse_solver({}).band_step == 0.0
    with pytest.raises(ConfigError, match="solver.band_step"):
        parse_solver({"band_step": -1})


def test_the_run_header_says_whether_steps_are_held(tmp_path):
    """With full Newton steps and contact the header says the steps are held; where a line search
    scales the steps (l2, friction's) ``solver.band_step`` does nothing, and the header says why."""
    from helpers import load_raw
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["steps"] = [10.0]
    raw.setdefault("solver", {})["band_step"] = 1.5
    held = run_inline(raw, tmp_path / "held")
    assert "Newton steps held to 1.5 fade-band widths" in held["solver"]
    scaled = run_inline(raw, tmp_path / "l2", petsc={"snes_linesearch_type": "l2"})
    assert ("Newton steps not held to the fade bands (solver.band_step needs full steps with contact, "
            "line search l2)") in scaled["solver"]
    raw["solver"]["band_step"] = 0.0
    assert "fade-band" not in run_inline(raw, tmp_path / "off")["solver"]
