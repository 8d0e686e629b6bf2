"""Fits on a one-element bar (issue 28): a synthetic twin recovers its parameters within the
reported 95 % intervals, a parameter the data cannot see is reported "not determined", and a
sample that fails is recorded with its reason code and penalised, not fatal."""
from __future__ import annotations

import os

import numpy as np
import pytest

from calibration_cases import BAR, BAR_TWIN, MU, K, TRUE, bar_case, write_yaml
from helpers import petsc_init

petsc_init()

from ancf_petsc.workflows.calibration import load_fit  # noqa: E402
from ancf_petsc.workflows.calibration.calibrate import run_calibration  # noqa: E402
from ancf_petsc.workflows.calibration.evaluate import Evaluator  # noqa: E402
from ancf_petsc.workflows.calibration.identify import DETERMINED, NOT  # noqa: E402
from ancf_petsc.workflows.calibration.log import SampleLog  # noqa: E402
from ancf_petsc.workflows.calibration.parameters import to_u  # noqa: E402
from ancf_petsc.workflows.calibration.twin import coverage, draw, exact_data, with_data  # noqa: E402

#: noise draws: the issue's "90 % of 20 draws" is a statement about coverage; 20 draws cannot
#: test it (honest 95 % intervals give 18 or more of 20 with probability 0.92 only), 100 can
#: (90 or more of 100 with probability 0.99)
DRAWS = 100


def test_the_twin_recovers_its_parameters_within_the_reported_errors(tmp_path):
    """Data from mu = 1.2 MPa, K = 3.6 MPa plus Gaussian noise of the data's sigma (elongation
    50 um, lateral stretch 5e-4; 10 levels each), 100 draws from a fixed seed (0, not chosen).

    * Every fit lands where linear theory puts it, u - u_true = (J^T J)^-1 J^T eps (J at the
      truth, eps the weighted noise), to 10 % of a standard error (the rest is the model's
      curvature), so the scatter of the estimates is the noise's, not the optimiser's; and the
      reported standard errors equal the truth's s (J^T J)^-1 to 5 %.
    * The true value lies in the reported 95 % interval (Student's t) in >= 90 % of the draws
      per parameter (this seed, with s^2 = max(chi^2/(m - n), 1): 94 % for mu, 94 % for K; its
      first 20 draws give 17 and 18 of 20, docs/calibration.md).
    """
    spec = load_fit(BAR_TWIN)                      # configs/fits/bar_twin.yaml
    exact = exact_data(spec, TRUE)
    ref = run_calibration(with_data(spec, exact, str(tmp_path / "exact")), fresh=True, say=lambda *_: None)
    J = ref.fit.jac
    C = np.linalg.inv(J.T @ J)
    u_true = to_u(spec.parameters, TRUE)
    assert np.abs(ref.fit.u - u_true).max() < 1e-9             # exact data: the truth itself
    rng = np.random.default_rng(0)
    fitted, se, t95 = [], [], []
    for k in range(DRAWS):
        noisy = draw(spec, exact, rng)
        res = run_calibration(with_data(spec, noisy, str(tmp_path / f"draw{k}")), fresh=True,
                              say=lambda *_: None)
        assert res.fit.status == "converged" and res.best.ok
        eps = np.concatenate([(noisy[d.name] - exact[d.name]) / d.sigmas for d in spec.data])
        linear = C @ J.T @ eps
        assert np.all(np.abs(res.fit.u - u_true - linear) < 0.1 * np.sqrt(np.diag(C)))
        se_abs = res.uncertainty.se_u / np.sqrt(res.uncertainty.s2)     # without the s^2 scaling
        assert se_abs == pytest.approx(np.sqrt(np.diag(C)), rel=0.05)
        fitted.append(res.fit.u)
        se.append(res.uncertainty.se_u)
        t95.append(res.uncertainty.t95)          # Student's t, or 1.96 where s^2 is the floor
    within = coverage(u_true, np.array(fitted), np.array(se), np.array(t95)[:, None])
    assert np.all(within.sum(axis=0) >= 0.9 * DRAWS), within.sum(axis=0)


def test_the_bulk_modulus_from_elongation_alone_is_not_determined(tmp_path):
    """A nearly incompressible bar (K / mu = 50): its elongation depends on E = 9 K mu / (3 K + mu)
    ~ 3 mu, K only through mu / (3 K) = 0.7 %.  Fitting both to the elongation (1 % noise):
    mu determined, K not determined (and said so) anywhere in 20 MPa - 1 GPa (K / mu >= 16).
    (With K free down to K / mu ~ 1, only E is determined and mu too is merely weakly so.)"""
    d = str(tmp_path)
    path = bar_case(d, parameters=(MU, dict(K, bounds=[2e7, 1e9], start=1e8)), lateral=False,
                    identifiability={"points": 5})
    write_yaml(os.path.join(d, "bar.yaml"), {**BAR, "beams": [dict(BAR["beams"][0], material={
        "model": "neo-hookean", "mu": 1.2e6, "bulk_modulus": 60e6})]})
    spec = load_fit(path)
    exact = exact_data(spec, (1.2e6, 60e6))
    data = {"elongation": exact["elongation"] * (1 + 0.01 * np.random.default_rng(3).normal(size=10))}
    spec.data[0].sigmas[:] = 0.01 * exact["elongation"]
    res = run_calibration(with_data(spec, data, os.path.join(d, "out")), fresh=True, say=lambda *_: None)
    mu, k = res.parameters
    assert mu.verdict == DETERMINED and abs(mu.value / 1.2e6 - 1) < 0.05, (mu.verdict, mu.reason, mu.value, mu.profile, k.value)
    assert k.verdict == NOT, (k.verdict, k.reason)
    assert not any(k.profile.closed)                # flat over the bounds
    assert os.path.exists(os.path.join(d, "out", "samples.jsonl"))


def test_a_failing_sample_is_recorded_and_penalised_not_fatal(tmp_path):
    """A Newton budget (26 for the 10 levels) the soft bar (mu = 0.15 MPa, 360 % elongation: 35
    iterations) exceeds and the stiff one (5 MPa: 21) does not: the sample is 'failed' with the solver's reason code
    (from the run, not its message), keeps the levels it reached and gets the penalty beyond."""
    d = str(tmp_path)
    path = bar_case(d, parameters=(MU,), lateral=False)
    write_yaml(os.path.join(d, "bar.yaml"), {**BAR, "solver": {"max_newton_iterations": 26}})
    spec = load_fit(path)
    log = SampleLog(os.path.join(d, "out"), spec, fresh=True)
    ev = Evaluator(spec, log)
    try:
        soft, stiff = ev([to_u(spec.parameters, [1.5e5]), to_u(spec.parameters, [5e6])], "test")
    finally:
        ev.close()
    assert stiff.ok and stiff.levels_reached == 10
    assert soft.status == "failed" and soft.reason_code == "NEWTON_BUDGET_EXCEEDED", soft
    assert 0 < soft.levels_reached < 10
    n, data = soft.levels_reached, spec.data[0]
    assert np.all(soft.r[n:] == spec.penalty)
    assert soft.r[:n] == pytest.approx((np.array(soft.model[data.name][:n]) - data.values[:n]) / data.sigmas[:n])
    assert [s.status for s in SampleLog(os.path.join(d, "out"), spec).samples] == ["failed", "completed"]


def test_the_log_fingerprint_follows_the_files_the_model_reads(tmp_path):
    """A fit resumed its log after an outline file the model reads had changed (the log's
    fingerprint hashed the model YAML only): the old geometry's samples, mu 1.07e8 where a fresh
    fit gives 2.60e7.  The files' contents are now part of it."""
    import copy
    from ancf_petsc.workflows.calibration.log import fingerprint
    d = str(tmp_path)
    spec = load_fit(bar_case(d, parameters=(MU,), lateral=False))
    (tmp_path / "secs.yaml").write_text("scale_m_per_px: 1.0e-5\n")
    spec.model_raw = copy.deepcopy(spec.model_raw)
    spec.model_raw["beams"][0]["section"] = {"shape": "outline", "file": "secs.yaml", "loop": "a"}
    spec.model_dir = d
    before = fingerprint(spec)
    assert fingerprint(spec) == before
    (tmp_path / "secs.yaml").write_text("scale_m_per_px: 2.0e-5\n")
    assert fingerprint(spec) != before


def test_a_fitted_level_reported_past_a_gap_is_named(tmp_path, monkeypatch):
    """A level of the data in a gap of the load path (no solve converges in (0.49, 0.5]; the step
    over taken for any failure) is reported at 0.5001: the fit compared the model there with the
    data at 0.5 and said nothing (sample 'COMPLETED'). Now the sample says LEVELS_PASSED_OVER and
    the level, and the fit's log and report.md name it, one line per level."""
    from ancf_petsc.solving import step_over
    from ancf_petsc.workflows.calibration.report import markdown
    from helpers import fail_solves
    fail_solves(lambda solver, lam: 0.49 < lam <= 0.5, put=monkeypatch.setattr)
    monkeypatch.setattr(step_over, "applies", lambda stepper, failure: True)
    d = str(tmp_path)
    spec = load_fit(bar_case(d, parameters=(MU,), lateral=False, identifiability={"profiles": False}))
    said = []
    res = run_calibration(spec, fresh=True, say=said.append)
    assert res.best.ok and res.best.reason_code == "LEVELS_PASSED_OVER", res.best
    assert res.best.passed_over == [[0.5, pytest.approx(0.5001)]]
    gaps = [s for s in said if "gap of the load path" in s]
    assert len(gaps) == 1 and gaps[0].startswith("[fit] warning: level 0.5 (elongation)"), said
    assert "at load factor 0.5001" in gaps[0]
    assert "- level 0.5 (elongation) lies in a gap" in markdown(res, SampleLog(os.path.join(d, "out"), spec))


def test_a_fit_whose_optimum_failed_says_so(tmp_path):
    """A Newton budget (2) no sample meets: every sample failed, the fit 'converged' at its start
    (mu 2e6, 'not determined') and the log said nothing of the failures (exit 0; report.md: '2
    failed'). Now one warning names the fitted sample's status, reason and the levels it reached."""
    from ancf_petsc.workflows.calibration.report import markdown
    d = str(tmp_path)
    path = bar_case(d, parameters=(MU,), lateral=False, identifiability={"profiles": False})
    write_yaml(os.path.join(d, "bar.yaml"), {**BAR, "solver": {"max_newton_iterations": 2}})
    spec = load_fit(path)
    said = []
    res = run_calibration(spec, fresh=True, say=said.append)
    assert not res.best.ok
    notes = [s for s in said if "fitted sample is failed" in s]
    assert len(notes) == 1 and "NEWTON_BUDGET_EXCEEDED" in notes[0] and "reached 0 of 10" in notes[0], said
    assert "- the fitted sample is failed" in markdown(res, SampleLog(os.path.join(d, "out"), spec))


def test_a_sample_past_a_gap_is_no_warm_start(tmp_path, monkeypatch):
    """A sample whose level was reported past a gap of the load path (0.5 at 0.5001) kept its
    states in the warm-start library: a neighbour's level 0.5 started from the state at 0.5001,
    where the neighbour's own path passes over. Such a sample is now left out of the library."""
    from ancf_petsc.solving import step_over
    from helpers import fail_solves
    fail_solves(lambda solver, lam: 0.49 < lam <= 0.5, put=monkeypatch.setattr)
    monkeypatch.setattr(step_over, "applies", lambda stepper, failure: True)
    d = str(tmp_path)
    spec = load_fit(bar_case(d, parameters=(MU,), lateral=False))
    ev = Evaluator(spec, SampleLog(os.path.join(d, "out"), spec, fresh=True))
    try:
        s = ev([to_u(spec.parameters, [2e6])], "test")[0]
    finally:
        ev.close()
    assert s.ok and s.passed_over and len(ev.library) == 0


def test_a_linear_parameter_with_wide_bounds_is_differenced_on_its_own_size(tmp_path):
    """mu linear in [0.2 MPa, 100 GPa]: its finite-difference step was fd_step x the upper bound
    (1 MPa on mu = 1.2 MPa), so on exact data the fit stopped at 1.2059 MPa, "converged", with a
    standard error of 3.2 kPa; central differences of the solves (step 1e-4 of each value) give 1.55."""
    wide = dict(MU, bounds=[2.0e5, 1.0e11], log=False)
    spec = load_fit(bar_case(str(tmp_path), parameters=(wide, K)))
    exact = exact_data(spec, TRUE)
    res = run_calibration(with_data(spec, exact, str(tmp_path / "out")), fresh=True, say=lambda *_: None)
    assert np.array([p.value for p in res.parameters]) == pytest.approx(TRUE, rel=1e-6)

    def weighted(p):
        out = exact_data(spec, p)
        return np.concatenate([out[d.name] / d.sigmas for d in spec.data])
    cols = [(weighted(np.where(np.arange(2) == j, 1.0001, 1.0) * TRUE)
             - weighted(np.where(np.arange(2) == j, 0.9999, 1.0) * TRUE)) / (2e-4 * TRUE[j]) for j in range(2)]
    J = np.array(cols).T
    se = np.sqrt(np.diag(np.linalg.inv(J.T @ J)))
    assert [p.se for p in res.parameters] == pytest.approx(se, rel=0.02)


def test_differential_evolution_counts_parameter_sets_not_batches(tmp_path):
    """scipy counts a vectorized call (a generation: popsize x parameters sets) as one evaluation:
    the log said '(cost ..., 3 samples)' after 3 batches of 5 solved sets (15)."""
    spec = load_fit(bar_case(str(tmp_path), optimizer={"method": "differential_evolution", "popsize": 2,
                                                       "generations": 2, "polish": False},
                             identifiability={"profiles": False}))
    said = []
    res = run_calibration(spec, fresh=True, say=said.append)
    batches = [int(m.split(": ")[1].split()[0]) for m in said if "differential evolution batch" in m]
    line = next(m for m in said if m.startswith("[fit] differential evolution:"))
    assert len(batches) == 3 and f"{sum(batches)} samples)" in line, (batches, line)
    assert res.fit.samples == sum(batches) + 1          # and the best one solved again
