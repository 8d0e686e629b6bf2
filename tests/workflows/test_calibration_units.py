"""Calibration pieces without solves: the fit file's errors (key path and fix, one line, exit 2),
the quantities, the warm-start library's prediction, the standard errors and verdicts."""
from __future__ import annotations

import os
import subprocess
from dataclasses import dataclass

import numpy as np
import pytest
import yaml

from calibration_cases import MU, K, bar_case
from helpers import MPI_ENV, ROOT, VENV_BIN

from ancf_petsc.workflows.calibration import CalibrationError, load_fit
from ancf_petsc.workflows.calibration.identify import (CHI2_95, DETERMINED, NOT, WEAK, Profile,
                                                        close_profile, uncertainty, verdict)
from ancf_petsc.workflows.calibration.library import StateLibrary
from ancf_petsc.workflows.calibration.parameters import Parameter, apply
from ancf_petsc.workflows.calibration.quantities import evaluate


def _edit(path, change) -> str:
    doc = yaml.safe_load(open(path))
    change(doc)
    with open(path, "w") as fh:
        yaml.safe_dump(doc, fh, sort_keys=False)
    return path


BAD = [
    ("unknown top key", lambda d: d.update(optimiser={}), "optimiser", "unknown key"),
    ("bad key path", lambda d: d["parameters"][0].update(key="beams[0]..mu"), "parameters[0].key", "bad key path"),
    ("index out of range", lambda d: d["parameters"][0].update(key="beams[3].material.mu"),
     "parameters[0].key", "out of range"),
    ("bounds inverted", lambda d: d["parameters"][0].update(bounds=[1e7, 1e6]), "parameters[0].bounds", "lower"),
    ("log of a negative bound", lambda d: d["parameters"][0].update(bounds=[-1.0, 1e7]),
     "parameters[0].bounds", "lower > 0"),
    ("start outside", lambda d: d["parameters"][0].update(start=1.0), "parameters[0].start", "outside"),
    ("config refuses a bound", lambda d: d["parameters"][0].update(bounds=[-1e6, 1e7], log=False),
     "parameters[0]", "refuses"),
    ("factor on a missing key", lambda d: d["parameters"][0].update(key="contact.friction", factor=True),
     "parameters[0].key", "not in the model config"),
    ("no such column", lambda d: d["data"][0].update(value="u_m"), "data[0].value", "no column"),
    ("no such probe", lambda d: d["data"][0].update(probe="tipp"), "data[0].probe", "no probe"),
    ("unknown quantity", lambda d: d["data"][0].update(quantity="strain"), "data[0].quantity", "must be one of"),
    ("two sigmas", lambda d: d["data"][0].update(relative_sigma=0.1), "data[0]", "one uncertainty"),
    ("key of another quantity", lambda d: d["data"][0].update(component="x"), "data[0].component",
     "not a key of quantity elongation"),
    ("method", lambda d: d.update(optimizer={"method": "nelder-mead"}), "optimizer.method", "must be one of"),
]


@pytest.mark.parametrize("name,change,key,words", BAD, ids=[b[0] for b in BAD])
def test_bad_fit_files_name_the_key(tmp_path, name, change, key, words):
    path = _edit(bar_case(str(tmp_path)), change)
    with pytest.raises(CalibrationError) as info:
        load_fit(path)
    assert info.value.path == key and words in info.value.message, (info.value.path, info.value.message)


def test_a_bad_fit_file_is_one_line_and_exit_2(tmp_path):
    path = _edit(bar_case(str(tmp_path)), lambda d: d["parameters"][0].update(bounds=[1e7, 1e6]))
    p = subprocess.run([os.path.join(VENV_BIN, "ancf-fit"), path], capture_output=True, text=True,
                       env=dict(os.environ, **MPI_ENV), cwd=ROOT, timeout=120)
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and "parameters[0].bounds:" in p.stderr and "Traceback" not in p.stderr


def test_the_fit_file_reads_parameters_data_and_levels(tmp_path):
    spec = load_fit(bar_case(str(tmp_path), parameters=(MU, dict(K, factor=True, bounds=[0.5, 2.0],
                                                                 start=1.0, log=False))))
    assert [p.name for p in spec.parameters] == ["mu", "K"]
    assert spec.parameters[1].base == (3.6e6,)
    raw = apply(spec.model_raw, spec.parameters, [1.5e6, 2.0])
    assert raw["beams"][0]["material"]["mu"] == 1.5e6 and raw["beams"][0]["material"]["bulk_modulus"] == 7.2e6
    assert spec.levels == pytest.approx([0.1 * k for k in range(1, 11)])
    assert spec.config([1.5e6, 2.0])["steps"] == spec.levels
    d = spec.data[0]
    assert d.values[0] == pytest.approx(1e-3) and d.sigmas[0] == 5e-5


def test_parameters_map_to_the_optimisers_coordinates_and_back():
    p = Parameter("mu", [("a",)], 1e5, 1e7, 1e6, log=True)
    assert p.to_u(1e6) == pytest.approx(6.0) and p.from_u(p.to_u(3.3e6)) == pytest.approx(3.3e6)
    q = Parameter("f", [("b",)], -2.0, 4.0, 1.0)
    assert q.scale == 4.0 and q.from_u(q.to_u(-1.5)) == pytest.approx(-1.5)
    assert q.dp_du(1.0) == 4.0 and p.dp_du(1e6) == pytest.approx(1e6 * np.log(10))


def test_quantities_from_probe_displacements():
    solved = [10.0, 20.0, 40.0]
    disp = {"a": np.array([[1.0, 2, 0], [2.0, 4, 0], [4.5, 9, 0]]), "b": np.array([[0.5, 0, 0], [1.0, 1, 0], [np.nan] * 3])}
    lv = np.array([10.0, 20.0, 40.0])
    assert evaluate("elongation", {"probes": ["a"]}, disp, lv, solved) == pytest.approx([1, 2, 4.5])
    assert evaluate("probe", {"probes": ["a"], "component": "norm"}, disp, lv[:1], solved) == pytest.approx([5 ** 0.5])
    diff = evaluate("difference", {"probes": ["a", "b"], "component": "x"}, disp, lv, solved)
    assert diff[:2] == pytest.approx([0.5, 1.0]) and np.isnan(diff[2])        # b did not reach 40
    k = evaluate("stiffness", {"probes": ["a"], "force": 2.0, "lower": 10.0}, disp, np.array([20.0, 40.0]), solved)
    assert k == pytest.approx([2.0 * 10 / 1.0, 2.0 * 30 / 3.5])
    mean = evaluate("elongation", {"probes": ["a", "b"]}, disp, lv[:2], solved)
    assert mean == pytest.approx([0.75, 1.5])


def test_a_stiffness_reads_the_load_its_curve_applies(tmp_path):
    """The bar's 45 N ramped to load factor 0.5 and held (a load curve), stiffness data without
    ``force``: F was λ × 45 N, so the stiffness grew 2x from 0.5 to 1.0 at a constant elongation;
    now F follows the curve (45 N from 0.5 on). A history column's load is refused."""
    path = bar_case(str(tmp_path), parameters=(MU,), lateral=False)
    _edit(os.path.join(str(tmp_path), "bar.yaml"),
          lambda d: d["loads"][0].update(curve=[[0.0, 0.0], [0.5, 1.0], [1.0, 1.0]]))
    _edit(path, lambda d: d["data"][0].update(quantity="stiffness", value_scale=1.0, sigma=10.0))
    data = load_fit(path).data[0]
    disp = {"tip": np.array([[2.0e-3, 0, 0], [4.0e-3, 0, 0], [4.0e-3, 0, 0]])}
    k = evaluate("stiffness", data.options, disp, np.array([0.25, 0.5, 1.0]), [0.25, 0.5, 1.0])
    assert k == pytest.approx([22.5 / 2e-3, 45.0 / 4e-3, 45.0 / 4e-3])
    held = dict(data.options, loads=[[[[0.0, 1.0], [1.0, 1.0]], [45.0, 0.0, 0.0]]])   # 45 N from the start
    assert evaluate("stiffness", held, disp, np.array([0.5]), [0.25, 0.5, 1.0]) == pytest.approx([45.0 / 4e-3])

    def history(d):
        d.pop("steps")
        d["history"] = {"table": {"time": [0.0, 0.1, 0.2], "s": [10.0, 30.0, 45.0]}}
        d["loads"][0].update(column="s", traction_force=[1.0, 0.0, 0.0])
        d["loads"][0].pop("curve")
    _edit(os.path.join(str(tmp_path), "bar.yaml"), history)
    with pytest.raises(CalibrationError) as info:
        load_fit(path)
    assert info.value.path == "data[0].force" and "history column" in info.value.message, info.value


def test_one_level_written_two_ways_is_one_level(tmp_path):
    """Two data files at 0.3 and 0.1 x 3 = 0.30000000000000004: both were solved as levels, which
    the model config refuses (closer than its step resolution), so every sample was a config
    error and the fit 'converged' at its start, 'not determined', exit 0. Now one level."""
    from ancf_petsc.config.parse import parse_config
    from calibration_cases import write_csv
    path = bar_case(str(tmp_path), parameters=(MU,), lateral=False)
    write_csv(tmp_path / "d2.csv", {"level": [0.1, 0.1 * 3, 0.5], "u_mm": [1.0, 5.0, 9.0]})
    write_csv(tmp_path / "d3.csv", {"level": [0.3, 0.5], "u_mm": [5.0, 9.0]})

    def two_files(d):
        d["data"] = [dict(d["data"][0], file="d2.csv"), dict(d["data"][0], name="e2", file="d3.csv")]
    spec = load_fit(_edit(path, two_files))
    assert len(spec.levels) == 3 and spec.levels[1] == pytest.approx(0.3, rel=1e-15), spec.levels
    parse_config(spec.config([1e6]), base_dir=spec.model_dir)         # refused before
    disp = {"tip": np.array([[1.0, 0, 0], [3.0, 0, 0], [5.0, 0, 0]])}
    for d in spec.data:
        assert evaluate(d.quantity, d.options, disp, d.levels, spec.levels)[-2:] == pytest.approx([3.0, 5.0])


def test_a_model_with_a_load_history_is_refused_before_any_solve(tmp_path):
    """A model solved through a load history (its frames are its steps): every sample was a
    config error ('with history every frame ... remove steps'), and the fit 'converged' at its
    start, 'not determined', exit 0. Now load_fit refuses it, naming data."""
    path = bar_case(str(tmp_path), parameters=(MU,), lateral=False)

    def history(d):
        d.pop("steps")
        d["history"] = {"table": {"time": [0.0, 0.1, 0.2], "s": [10.0, 30.0, 45.0]}}
        d["loads"][0].update(column="s", traction_force=[1.0, 0.0, 0.0])
    _edit(os.path.join(str(tmp_path), "bar.yaml"), history)
    with pytest.raises(CalibrationError) as info:
        load_fit(path)
    assert info.value.path == "data" and "with history every frame" in info.value.message, info.value


@dataclass
class _State:                       # the fields of solving.samples.LevelState
    x: np.ndarray
    projection: None = None
    status: None = None


def test_the_library_predicts_states_that_are_linear_in_the_parameters():
    """States affine in u are predicted exactly from a point and its finite-difference cloud;
    far away the sample is solved cold; a lone close neighbour is used as it is."""
    A, b = np.random.default_rng(0).normal(size=(2, 50, 3)), np.ones(50)

    def states(u):
        return [_State(A[k] @ u + b) for k in range(2)]
    lib = StateLibrary()
    u0 = np.array([6.0, 6.5, 7.0])
    lib.add(u0, states(u0))
    one, how = lib.start_for(u0 + 1e-5)
    assert how == "nearest" and one[0].x is lib.states[0][0].x
    for e in np.eye(3):
        lib.add(u0 + 1e-5 * e, states(u0 + 1e-5 * e))
    target = u0 + np.array([0.04, -0.02, 0.03])
    pred, how = lib.start_for(target)
    assert how == "affine"
    assert max(np.abs(p.x - s.x).max() for p, s in zip(pred, states(target))) < 1e-8
    assert lib.start_for(u0 + 0.5)[1] == "cold"


def test_standard_errors_of_a_linear_model_and_a_parameter_it_cannot_see():
    rng = np.random.default_rng(1)
    J = rng.normal(size=(30, 2))
    r = 2.0 * rng.normal(size=30)                 # a misfit beyond the σ: s² = χ²/(m − n) > 1
    unc = uncertainty(J, r)
    s2 = r @ r / 28
    assert s2 > 1 and unc.s2 == pytest.approx(s2)
    assert unc.se_u == pytest.approx(np.sqrt(np.diag(s2 * np.linalg.inv(J.T @ J))))
    J2 = np.column_stack([J[:, 0], np.zeros(30)])              # the second parameter is invisible
    unc2 = uncertainty(J2, r)
    assert np.isfinite(unc2.se_u[0]) and np.isinf(unc2.se_u[1])
    assert verdict(np.inf, None)[0] == NOT


def test_verdicts_follow_the_stated_rule():
    closed = close_profile(Profile([1.0, 3.0], [5.0, 6.0], ["completed"] * 2), 2.0)
    flat = close_profile(Profile([1.0, 3.0], [0.1, 0.2], ["completed"] * 2), 2.0)
    one_side = close_profile(Profile([1.0, 3.0], [0.1, 9.0], ["completed"] * 2), 2.0)
    assert closed.closed == (True, True) and flat.closed == (False, False)
    assert verdict(0.1, closed)[0] == DETERMINED
    assert verdict(0.1, one_side)[0] == WEAK
    assert verdict(0.5, closed)[0] == WEAK
    assert verdict(0.1, flat)[0] == NOT and verdict(1.5, closed)[0] == NOT
    assert CHI2_95 == pytest.approx(3.8415, abs=1e-4)
    failed = close_profile(Profile([1.0, 1.5, 3.0], [1e6, 0.5, 9.0], ["failed", "completed", "completed"]), 2.0)
    assert failed.closed == (False, True) and failed.interval[0] == 1.5     # a failure proves nothing


@pytest.mark.parametrize("unit,bounds,start,si", [("MPa", [0.2, 10.0], 2.0, "2e+06"),
                                                   ("N/mm", [0.2, 10.0], 2.0, "2000")])
def test_a_prefixed_unit_is_refused_not_taken_as_a_label(tmp_path, unit, bounds, start, si):
    # bounds in MPa went to the model as Pa (mu = 2 Pa: no level reached, exit 0), or SI values got
    # an MPa label; the values are the model config's, in SI
    path = _edit(bar_case(str(tmp_path)), lambda d: d["parameters"][0].update(unit=unit, bounds=bounds,
                                                                              start=start))
    with pytest.raises(CalibrationError) as info:
        load_fit(path)
    assert info.value.path == "parameters[0].unit" and si in info.value.message, info.value.message


@pytest.mark.parametrize("unit", ["Pa", "m", "N/m", "kg", "1", ""])
def test_an_si_unit_labels_the_parameter(tmp_path, unit):
    spec = load_fit(_edit(bar_case(str(tmp_path)), lambda d: d["parameters"][0].update(unit=unit)))
    assert spec.parameters[0].unit == unit and spec.parameters[0].start == 2.0e6
