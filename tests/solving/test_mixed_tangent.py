"""``solver.tangent: mixed`` (petsc/mixed_tangent.py, physics/mixed_point.py): the initial-stress
part of the element tangent from the stress of the strain linearised along the last Newton step.
The correction is checked against its definition written out point by point; the converged states
are the displacement model's (only the iterates differ); and on a neo-Hookean unilateral column
at 90° it takes fewer Newton iterations (measured 67 → 57 to 1.2 kN), on 1, 2 and 3 ranks alike."""
import os

import numpy as np
import pytest

from helpers import CONFIGS, run_inline

from ancf_petsc.physics.goh import GOH
from ancf_petsc.physics.materials import NeoHookean
from ancf_petsc.physics.mixed_point import MIN_EIGENVALUE, initial_stress_correction, linearised_stretch
from ancf_petsc.workflows.envelope import NEO, EnvelopeCell, cell_config


def _gradients(E=2, P=3, S=4, seed=0):
    rng = np.random.default_rng(seed)
    F_prev = np.eye(3) + 0.1 * rng.normal(size=(E, P, 3, 3))
    dF = 0.05 * rng.normal(size=(E, P, 3, 3))
    return F_prev, F_prev + dF, rng.normal(size=(E, P, S, 3)), rng.uniform(0.5, 1.0, size=(E, P))


def test_the_stretch_is_that_of_the_strain_linearised_about_the_previous_iterate():
    """F̂ᵀF̂ = C(F_prev) + F_prevᵀΔF + ΔFᵀF_prev: the Green strain without the step's ½ΔFᵀΔF."""
    F_prev, F, _, _ = _gradients()
    F_hat, ok = linearised_stretch(F, F_prev)
    dF = F - F_prev
    C_lin = F_prev.swapaxes(-1, -2) @ F_prev + F_prev.swapaxes(-1, -2) @ dF + dF.swapaxes(-1, -2) @ F_prev
    assert ok.all()
    assert np.allclose(F_hat.swapaxes(-1, -2) @ F_hat, C_lin, rtol=0, atol=1e-14)


def test_the_same_iterate_gives_no_correction_and_a_long_step_keeps_its_stress():
    """ΔF = 0: Ĉ = C, δK = 0 (to rounding: S from the Cholesky factor of C).  A step whose linearised strain is not a stretch (Ĉ with an
    eigenvalue under MIN_EIGENVALUE) keeps the iterate's own stress at that point."""
    F_prev, F, G, w = _gradients()
    law = NeoHookean(1e6, 5e7)
    step = np.abs(initial_stress_correction(F, F_prev, G, w, law)).max()
    assert np.abs(initial_stress_correction(F, F, G, w, law)).max() <= 1e-12 * step
    F_long = F.copy()
    F_long[0, 0] = F_prev[0, 0] - 2.0 * np.eye(3)     # Ĉ = C_prev − 4 sym F_prev ≈ −3 I there
    _, ok = linearised_stretch(F_long, F_prev)
    assert not ok[0, 0] and ok.sum() == ok.size - 1
    assert MIN_EIGENVALUE > 0


@pytest.mark.parametrize("law", ["neo-Hookean", "GOH"])
def test_the_correction_is_the_initial_stress_term_of_the_stress_difference(law):
    """δK[(a,i),(b,k)] = δ_ik Σ_p w_p G_a·(S(Ĉ) − S(C))·G_b, written out point by point."""
    F_prev, F, G, w = _gradients()
    if law == "GOH":
        a0 = np.broadcast_to(np.array([1.0, 0.2, 0.1]) / np.linalg.norm([1.0, 0.2, 0.1]), (1,) + w.shape + (3,))
        material = GOH(1e5, 5e6, 8e6, 5.0).with_directions(a0)
    else:
        material = NeoHookean(1e6, 5e7)
    K = initial_stress_correction(F, F_prev, G, w, material)
    F_hat, _ = linearised_stretch(F, F_prev)
    E, Np, S = G.shape[:3]
    S_hat = np.linalg.solve(F_hat, material.stress(F_hat)[0])
    S_now = np.linalg.solve(F, material.stress(F)[0])
    expected = np.zeros((E, S, 3, S, 3))
    for e in range(E):
        for p in range(Np):
            dS = S_hat[e, p] - S_now[e, p]
            block = w[e, p] * G[e, p] @ (0.5 * (dS + dS.T)) @ G[e, p].T
            for i in range(3):
                expected[e, :, i, :, i] += block
    assert np.abs(K).max() > 0
    assert np.allclose(K, expected.reshape(E, 3 * S, 3 * S), rtol=1e-12, atol=1e-12 * np.abs(K).max())
    assert np.allclose(K, K.swapaxes(1, 2), rtol=0, atol=1e-12 * np.abs(K).max())


def test_a_projected_dilatation_keeps_an_element_whole():
    """``locking: mixed`` (θ = Π_h J couples an element's points): one point whose Ĉ is not a
    stretch leaves its whole element uncorrected; the other element is corrected as alone."""
    from ancf_petsc.physics.mixed import ProjectedDilatation, pressure_basis
    rng = np.random.default_rng(5)
    F_prev, F, G, _ = _gradients(E=2, P=24, S=4, seed=5)
    yz, wq = rng.uniform(-1e-3, 1e-3, (24, 2)) + [2e-3, -1e-3], rng.uniform(0.5, 1.5, 24)
    w = wq[None] * rng.uniform(0.8, 1.2, (2, 24))
    law = ProjectedDilatation(NeoHookean(1e6, 5e7), pressure_basis(yz, wq, 2)).on(w)
    whole = initial_stress_correction(F, F_prev, G, w, law)
    F[0, 3] = F_prev[0, 3] - 2.0 * np.eye(3)          # Ĉ ≈ −3 I at one point of element 0
    K = initial_stress_correction(F, F_prev, G, w, law)
    assert np.abs(whole[0]).max() > 0 and np.abs(K[0]).max() == 0.0
    assert np.array_equal(K[1], whole[1])


def _column(tangent: str | None) -> dict:
    raw = cell_config(EnvelopeCell(NEO, 90.0, "uniform", "unilateral", levels=(30.0, 100.0, 200.0, 400.0,
                                                                                   600.0, 800.0, 1000.0, 1200.0)))
    if tangent:
        raw.setdefault("solver", {})["tangent"] = tangent
    return raw


def test_the_unilateral_column_at_90_degrees_reaches_the_same_states_in_fewer_iterations(tmp_path):
    """The 90° uniform unilateral column to 1.2 kN (4 elements): 57 Newton iterations against 67,
    and the same probes at every level to the Newton tolerance's order."""
    runs = {t: run_inline(_column(t), tmp_path / t) for t in ("standard", "mixed")}
    plain, mixed = runs["standard"], runs["mixed"]
    assert plain["status"] == mixed["status"] == "completed"
    assert mixed["newton_iterations"] < plain["newton_iterations"]
    for a, b in zip(plain["steps"], mixed["steps"]):
        assert a["load_factor"] == b["load_factor"]
        for name, probe in a["probes"].items():
            u, v = np.asarray(probe["displacement"]), np.asarray(b["probes"][name]["displacement"])
            assert np.abs(u - v).max() <= 1e-7 * np.abs(u).max(), name


@pytest.mark.mpi
def test_the_mixed_tangent_gives_the_serial_answer_on_two_and_three_ranks(tmp_path):
    """Each rank keeps its own elements' previous F: 2 and 3 ranks take the serial Newton
    iterations to the serial answer."""
    from helpers import assert_same_as_serial, probes_table, run_on_ranks
    raw = _column("mixed")
    raw["steps"] = [30.0, 100.0, 200.0]
    runs = run_on_ranks(raw, tmp_path, ranks=(1, 2, 3))
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
    its = {n: [st["iterations"] for st in s["steps"]] for n, (_, s) in runs.items()}
    assert its[1] == its[2] == its[3], its
    assert os.path.isdir(CONFIGS)


def test_after_a_failed_sub_step_the_retries_take_the_plain_tangent(tmp_path, monkeypatch):
    """A level's retries after a cut-back use the plain tangent (the corrected iterates' course is
    another, not a safer one: the 180° soleus-biased unilateral column failed at 2 kN with the
    correction kept through its cut-backs and completes with this); the next level corrects again.
    The 135° soleus-biased sliding column to 400 and 1200 N cuts back once in each level."""
    from ancf_petsc.petsc.mixed_tangent import MixedTangent
    from ancf_petsc.solving.stepper import LoadStepper
    events = []
    correct, cut_back = MixedTangent.correct, LoadStepper._cut_back

    def recording_correct(self, key, qe, parts, K):
        out = correct(self, key, qe, parts, K)
        events.append(("corrected" if self.corrected else "plain", self.paused))
        return out

    def recording_cut_back(self, *args, **kwargs):
        events.append(("cut back", None))
        return cut_back(self, *args, **kwargs)

    monkeypatch.setattr(MixedTangent, "correct", recording_correct)
    monkeypatch.setattr(LoadStepper, "_cut_back", recording_cut_back)
    raw = cell_config(EnvelopeCell(NEO, 135.0, "soleus", "sliding", levels=(400.0, 1200.0),
                                   predictor="secant"))       # the path with a cut-back per level
    raw.setdefault("solver", {})["tangent"] = "mixed"
    summary = run_inline(raw, tmp_path)
    assert summary["status"] == "completed"
    assert [s["cutbacks"] for s in summary["steps"]] == [1, 1]
    cuts = [i for i, e in enumerate(events) if e[0] == "cut back"]
    assert len(cuts) == 2
    first, second = events[:cuts[0]], events[cuts[0] + 1:cuts[1]]
    assert ("corrected", False) in first
    retries = second[:next(i for i, e in enumerate(second) if not e[1])]   # until the level ends
    assert retries and all(e == ("plain", True) for e in retries)
    assert ("corrected", False) in second[len(retries):]                 # the next level corrects
    assert all(e[0] != "corrected" for e in events if e[1])
