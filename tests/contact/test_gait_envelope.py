"""The gait envelope's failures at 38a07d3, each at small size (issue 38; workflows/envelope.py
builds the cells: the paper's outlines, plane roots, end tractions split by the bias, 2 axial
points).  Unilateral contact at ψ = 90°, gastrocnemius-biased, raised a traceback on its first
level (a complementarity linearisation at a state with an inverted element); the sliding column at
ψ = 180°, soleus-biased, cycled at 1030 N; the unilateral one lost its projections at 815 N; the
sliding ψ = 90° columns took 72-91 Newton iterations to 1.2 kN.  A stride's push-off with
unilateral contact, loading and unloading, holds too."""
import re

import numpy as np
import pytest

from ancf_petsc.workflows.envelope import NEO, EnvelopeCell, cell_config
from ancf_petsc.workflows.stride import OPENSIM_COLUMNS, synthetic_stride
from helpers import CONFIGS, run_inline


def _run(cell, tmp_path, petsc: dict | None = None):
    raw = cell_config(cell)
    return run_inline(raw, tmp_path / cell.name, base_dir=CONFIGS, petsc=petsc)


def _cutbacks(s):
    return sum(st["cutbacks"] for st in s["steps"])


def _first_frames(raw: dict, frames: int, out) -> None:
    """The config ``raw``'s history file cut to its first ``frames`` frames (a file in ``out``)."""
    with open(raw["history"]["file"]) as fh:
        lines = fh.readlines()
    header = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    (out / "frames.csv").write_text("".join(lines[:header + 1 + frames]))
    raw["history"]["file"] = str(out / "frames.csv")


def _stride_frames(bias: str, first: int, stop: int, out, fade_forces: str | None = None,
                   solver: dict | None = None):
    """Frames first+1 … stop of the shipped stride in ``bias`` at ψ = 90°, unilateral contact, as
    a history of their own (the first reached from rest; ``fade_forces``: contact.fade_forces;
    ``solver``: solver keys)."""
    times, forces = synthetic_stride(bias)
    sel = slice(first, stop)
    raw = cell_config(EnvelopeCell(NEO, 90, bias, "unilateral", stride=True))
    if fade_forces is not None:
        raw["contact"]["fade_forces"] = fade_forces
    if solver:
        raw.setdefault("solver", {}).update(solver)
    raw["history"] = {"table": {"time": times[sel].tolist(),
                                **{c: forces[c][sel].tolist() for c in OPENSIM_COLUMNS}}}
    return run_inline(raw, out, base_dir=CONFIGS)


@pytest.mark.slow
def test_unilateral_twist_90_gastrocnemius_biased_first_levels(tmp_path):
    """The traceback case (ValueError: array must not contain infs or NaNs, 38a07d3) reaches its
    first levels without a cut-back."""
    s = _run(EnvelopeCell(NEO, 90, "gastrocnemius", "unilateral", levels=(30.0, 100.0, 200.0)), tmp_path)
    assert s["status"] == "completed" and _cutbacks(s) == 0


@pytest.mark.slow
def test_held_predictions_reach_the_same_states_in_fewer_iterations(tmp_path, monkeypatch):
    """At ψ = 90° the bodies' tangent without the constraints is indefinite and S with it, far
    from semidefinite at 600 and 800 N: there was no prediction and the level started again from
    the converged state (petsc/complementarity.py).  With the active constraints held the
    prediction is an exact solution of the linearised LCP: the same converged states (to 1e-12 m),
    in fewer Newton iterations (measured 62 against 67 to 800 N)."""
    from ancf_petsc.petsc import complementarity
    held = complementarity.held_lcp
    used = []

    def counting(S, d, E):
        z = held(S, d, E)
        used.append(z is not None)
        return z

    cell = EnvelopeCell(NEO, 90, "gastrocnemius", "unilateral", levels=(30.0, 100.0, 200.0, 400.0, 600.0, 800.0))
    monkeypatch.setattr(complementarity, "held_lcp", counting)
    new = _run(cell, tmp_path / "held")
    monkeypatch.setattr(complementarity, "held_lcp", lambda S, d, E: None)
    old = _run(cell, tmp_path / "none")
    assert new["status"] == old["status"] == "completed" and _cutbacks(new) == 0
    assert any(used)
    assert new["newton_iterations"] < old["newton_iterations"], (new["newton_iterations"], old["newton_iterations"])
    for a, b in zip(new["steps"], old["steps"]):
        for k in a["probes"]:
            assert np.allclose(a["probes"][k]["displacement"], b["probes"][k]["displacement"], rtol=0, atol=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("law,bias,predictor,budget", [("sliding", "soleus", None, 70),
                                                      ("sliding", "uniform", None, 70),
                                                      ("unilateral", "soleus", "tangent", 250)])
def test_twist_180_columns_to_1200_newtons(tmp_path, law, bias, predictor, budget):
    """ψ = 180° to 1.2 kN: the sliding soleus-biased column (a Newton 2-cycle at 1030 N before)
    and the unilateral one (projection lost at 815 N) complete within their Newton budgets, the
    sliding ones without a cut-back (measured 66 and 64 with the default secant predictor; the
    unilateral column 191 with the tangent predictor, about 1000 with the secant)."""
    levels = (30.0, 100.0, 200.0, 400.0, 600.0, 800.0, 1000.0, 1200.0)
    s = _run(EnvelopeCell(NEO, 180, bias, law, levels=levels, predictor=predictor), tmp_path)
    assert s["status"] == "completed" and s["steps"][-1]["load_factor"] == 1200.0
    assert s["newton_iterations"] <= budget
    if law == "sliding":
        assert _cutbacks(s) == 0


@pytest.mark.slow
def test_unilateral_twist_165_soleus_biased_column_to_3_kilonewtons(tmp_path):
    """With the fade weights' derivatives shared out over det H / det a 0.25–0.5, points at
    converged states sat in the fade and the weighted gaps' gradients lacked (1 − s) g ∇w: from
    2881.9 N Newton converged linearly (0.946 per iteration from |F| 1e-6) and the column stopped
    (contact/weights.py).  With the fade at 0.05–0.1 it reaches 3 kN."""
    s = _run(EnvelopeCell(NEO, 165, "soleus", "unilateral"), tmp_path)
    assert s["status"] == "completed" and s["steps"][-1]["load_factor"] == 3000.0


@pytest.mark.slow
def test_unilateral_push_off_loading_and_unloading(tmp_path):
    """Frames 40-60 of the gastrocnemius-biased stride (the push-off peak, 2.63 kN, and the
    unloading to toe-off) at ψ = 90° with unilateral contact: every frame converges, none after
    the first (a ramp from rest to 0.5 kN in sub-steps) takes a cut-back, and the median frame
    takes at most 8 Newton iterations (measured 5)."""
    s = _stride_frames("gastrocnemius", 40, 61, tmp_path / "push_off")
    its = [st["iterations"] for st in s["steps"]]
    assert s["status"] == "completed" and len(its) == 21
    assert sum(st["cutbacks"] for st in s["steps"][1:]) == 0
    assert np.median(its[1:]) <= 8


@pytest.mark.slow
def test_unilateral_twist_90_soleus_biased_frames_46_to_47(tmp_path):
    """Frames 46-47 of the soleus-biased stride at ψ = 90°, unilateral contact (the whole stride
    stopped at frame 46.8 before, 2.4 kN: a point 0.52 mm off the end piece of its partner's
    interface curve sat at the projection conditioning where its weight's derivatives were cut
    off, and the residual jumped by a 0.87 N force pair between states 5e-13 apart; the weights'
    derivatives now fade in with the conditioning, contact/weights.conditioned).  Frame 46 is
    reached from rest, and frame 47 from it without a cut-back (measured: 9 Newton iterations;
    the code before cycled at 1.798 at every increment down to 6e-5 of a frame)."""
    s = _stride_frames("soleus", 45, 47, tmp_path / "frames_46_47")
    assert s["status"] == "completed", s.get("message")
    last = s["steps"][-1]
    assert last["load_factor"] == 2.0 and last["cutbacks"] == 0 and last["iterations"] <= 15


@pytest.mark.slow
def test_the_old_single_cut_fails_frame_47_and_the_failure_names_the_jump(tmp_path, monkeypatch):
    """The same frames with the weights' derivatives cut at one conditioning value again (as on
    da3c67c: at 0.5, ILL_POSED just below WELL_POSED): Newton cycles at 1.798 at every increment,
    and the failure's scan (solving/continuity.py) names the residual's jump, 0.87 N on the medial
    gastrocnemius, instead of the cycle alone; that with the variational fade forces chosen.  The
    default, ``auto``, goes on from there with the pointwise ones (solving/fade_switch.py) and
    completes the frames.  The cut-backs stop at increments of 4e-3 frames (the default 1e-4
    took 40 % more Newton iterations to the same switch and failure)."""
    from ancf_petsc.contact import weights
    monkeypatch.setattr(weights, "WELL_POSED", 0.5)
    monkeypatch.setattr(weights, "ILL_POSED", np.nextafter(0.5, 0.0))
    floor = {"min_increment": 4e-3}
    s = _stride_frames("soleus", 45, 47, tmp_path / "auto", solver=floor)
    assert s["status"] == "completed" and 1.79 < s["fade_forces_pointwise_from"] < 1.8, s["message"]
    s = _stride_frames("soleus", 45, 47, tmp_path / "frames_46_47_cut", fade_forces="variational", solver=floor)
    assert s["status"] == "failed" and s["steps"][-1]["load_factor"] == 1.0
    message = s["message"]
    size = re.search(r"the residual jumps by ([0-9.e+-]+) N", message)
    assert "Newton cycles" in message and size is not None and 0.8 < float(size.group(1)) < 0.95, message
    assert "beam medial_gastrocnemius" in message, message


@pytest.mark.slow
def test_unilateral_twist_180_uniform_stride_switches_branch_at_frame_13(tmp_path):
    """The uniform stride at ψ = 180°, unilateral contact, stopped at frame 13.16 (455 N): a sub-step
    converged at frame 13.375 on a saddle (the lateral gastrocnemius' sections turning near the
    loaded end, eigenvalue −1.6) and every smaller one failed.  The branch switch
    (solving/branch_switch.py) leaves that saddle along its critical mode for a stable state
    about 1 mm away, and the stride goes on from it: every frame a stable equilibrium.  Run with
    the general Newton budget (15 iterations a solve, PETSc's own convergence test): with the
    unilateral law's (60, ended after 15 without a new low; contact/laws.py) the stride passes
    frame 13 without meeting the saddle (docs/gait.md).  The stride's first 16 frames as a
    history of their own (the same frames; the whole stride, 78 s, also switches at a second
    saddle at frame 37.5, eigenvalue −3.8, by 1.0 mm: docs/gait.md)."""
    raw = cell_config(EnvelopeCell(NEO, 180, "uniform", "unilateral", stride=True))
    _first_frames(raw, 16, tmp_path)
    s = run_inline(raw, tmp_path, base_dir=CONFIGS, petsc={"snes_max_it": 15, "snes_convergence_test": "default"})
    assert s["status"] == "completed" and s["reason_code"] == "BRANCH_SWITCHED", s["message"]
    switches = [x for st in s["steps"] for x in st.get("branch_switches", [])]
    assert len(switches) == 1 and 13.0 < switches[0]["load_factor"] < 14.0, switches
    for sw in switches:
        assert sw["negative_before"] == 1 and sw["negative_after"] == 0
        assert 0.2e-3 < sw["jump"] < 2e-3 and sw["potential_drop"] > 0.0
    assert len(s["steps"]) == 16 and all(st["negative_eigenvalues"] == 0 for st in s["steps"])


@pytest.mark.slow
def test_every_accepted_frame_of_the_135_degree_uniform_stride_is_unilateral(tmp_path):
    """The unilateral 135° uniform stride accepted frame 1 with multipliers pulling (normal force
    −28.1 N between soleus and medial gastrocnemius, 4.2 N of it tension; 1bf68c3 … 705fef4): a
    failed prediction's status, kept by the solve for the new weights, was not checked again
    (solving/newton.py ``_reweigh``), and frame 2 then failed at every increment.  The whole
    stride within a budget of 200 Newton iterations: every accepted frame presses only."""
    raw = cell_config(EnvelopeCell(NEO, 135.0, "uniform", "unilateral", stride=True))
    raw.setdefault("solver", {})["max_newton_iterations"] = 200
    s = run_inline(raw, tmp_path, base_dir=CONFIGS)
    assert len(s["steps"]) >= 2
    for step in s["steps"]:
        for name, c in step["contact"].items():
            assert c["tension_force"] >= -1e-9 and c["normal_force"] >= 0.0, (step["load_factor"], name)


@pytest.mark.slow
def test_a_state_the_exact_rule_would_change_is_not_accepted(tmp_path, monkeypatch):
    """The guard behind ``_reweigh``'s check: with the weights' solve accepted unchecked again
    (the solver before the fix), the stepper itself refuses a converged state whose status the
    exact rule would change (UNILATERAL_CONDITIONS_VIOLATED, petsc/problem.py ``unclean``) and
    cuts back: every accepted frame still presses only.  Which frames reach such a state turns on
    rounding (frame 1 did with the compact factor's matching 5, 5edf9cb to be7ff5b, not with the
    bottleneck matching), so the rule is made to report one pending change at frame 1's first
    converged state, the stepper's check of it being what is tested."""
    from ancf_petsc.contact import forget_evaluation
    from ancf_petsc.petsc import problem as problem_module
    from ancf_petsc.solving import newton

    def unchecked(self, X, lam, its, weighed):
        if weighed is not None:
            weighed[0].destroy()
        forget_evaluation(self.steps.contact)
        reason, n = self.snes_solve(X)
        return reason, its + n, False

    real, forced = problem_module.pending_status, []

    def pending_once(contact):
        out = real(contact)
        if not forced and len(out):
            forced.append(True)
            out = out.copy()
            out[:1] = True
        return out

    monkeypatch.setattr(newton.PhasedNewton, "_reweigh", unchecked)
    monkeypatch.setattr(problem_module, "pending_status", pending_once)
    raw = cell_config(EnvelopeCell(NEO, 135.0, "uniform", "unilateral", stride=True))
    raw.setdefault("solver", {})["max_newton_iterations"] = 200
    s = run_inline(raw, tmp_path, base_dir=CONFIGS)
    assert forced and len(s["steps"]) >= 2 and s["steps"][0]["cutbacks"] >= 1
    for step in s["steps"]:
        for name, c in step["contact"].items():
            assert c["tension_force"] >= -1e-9 and c["normal_force"] >= 0.0, (step["load_factor"], name)


@pytest.mark.slow
def test_unilateral_twist_180_soleus_biased_stride_stays_stable_through_frame_19(tmp_path):
    """The soleus-biased stride at ψ = 180°, unilateral contact, met frame 19 from a converged
    frame-18.5 state whose multiplier 40 was about to let go (1 kPa against 120–770 kPa): there S
    = G K⁻¹ Gᵀ is slightly indefinite (−3.2e8 against 5.9e10), the converged status is an exact
    solution of the increment's LCP, and the nearest semidefinite S's chose another, 6 constraints
    changed, whatever the increment (down to 1e-4).  Newton then landed on a saddle 1.5 mm away
    (a neighbour pressed at 13: one negative eigenvalue) or failed; the whole stride went on from
    there to frame 100 on saddles (status unstable, 985 Newton iterations at frame 19).  The LCP is
    now solved from the status it starts at (petsc/lcp.py ``pivoted_from``): frame 19 is reached on
    stable states, 40 released, 122 iterations.  The stride's first 25 frames as a history of their
    own."""
    raw = cell_config(EnvelopeCell(NEO, 180, "soleus", "unilateral", stride=True))
    _first_frames(raw, 25, tmp_path)
    s = run_inline(raw, tmp_path, base_dir=CONFIGS)
    assert s["status"] == "completed", s["message"]
    assert len(s["steps"]) == 25 and all(st["negative_eigenvalues"] == 0 for st in s["steps"])
    assert not any(st.get("branch_switches") for st in s["steps"])
    assert s["steps"][18]["iterations"] <= 250, s["steps"][18]["iterations"]
