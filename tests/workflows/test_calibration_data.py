"""Calibration data as a researcher brings them (issue 39): NaN or infinite cells, a spreadsheet's
byte-order mark, repeated trials at one load, a forgotten value_scale, a negative one, a misspelt
or doubly used parameter key; a small fit that fits better than its σ keeps the σ's errors; the
report prints no Python objects."""
from __future__ import annotations

import os
import subprocess
import warnings

import numpy as np
import pytest
import yaml

from calibration_cases import MU, K, TRUE, bar_case, write_bar, write_fit
from helpers import MPI_ENV, ROOT, VENV_BIN, petsc_init

from ancf_petsc.workflows.calibration import CalibrationError, load_fit
from ancf_petsc.workflows.calibration.identify import uncertainty


def _csv(path, text: str, bom: bool = False) -> str:
    with open(path, "w", encoding="utf-8-sig" if bom else "utf-8") as fh:
        fh.write(text)
    return str(path)


def _elongation_fit(directory, csv_text: str, bom: bool = False, parameters=(MU, K), fit=None,
                    **data) -> str:
    """The bar fitted to an elongation column (``data``: keys of the data set to change, None
    removes one; ``fit``: top-level keys of the fit file)."""
    write_bar(directory)
    _csv(os.path.join(directory, "data.csv"), csv_text, bom)
    item = {"name": "elongation", "file": "data.csv", "load": "force_N", "value": "u_mm",
            "value_scale": 1e-3, "sigma": 5e-5, "quantity": "elongation", "probe": "tip", **data}
    return write_fit(directory, list(parameters), [{k: v for k, v in item.items() if v is not None}],
                     **(fit or {}))


GOOD = "force_N,u_mm\n0.1,1.9\n0.5,10.2\n1.0,22.6\n"


@pytest.mark.parametrize("cell", ["nan", "NaN", "inf", "-inf", ""])
def test_a_nan_or_infinite_value_is_refused_with_its_line_and_column(tmp_path, cell):
    """Before: NaN and inf were read as numbers and every sample's residual became the failure
    penalty (χ² 1e6, μ "weakly determined"), exit 0.  Now: the file, line and column, exit 2."""
    path = _elongation_fit(str(tmp_path), f"# a comment\nforce_N,u_mm\n0.1,1.9\n0.5,{cell}\n1.0,22.6\n")
    with pytest.raises(CalibrationError) as info:
        load_fit(path)
    assert info.value.path == "data[0].value"
    assert "data.csv, line 4, column 'u_mm'" in info.value.message and "finite number" in info.value.message
    p = subprocess.run([os.path.join(VENV_BIN, "ancf-fit"), path], capture_output=True, text=True,
                       env=dict(os.environ, **MPI_ENV), cwd=ROOT, timeout=120)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "Traceback" not in p.stderr, p.stderr


def test_a_nan_sigma_or_load_cell_is_refused_too(tmp_path):
    path = _elongation_fit(str(tmp_path), "force_N,u_mm,sd\n0.1,1.9,0.05\nnan,10.2,0.05\n")
    with pytest.raises(CalibrationError, match="line 3, column 'force_N'"):
        load_fit(path)
    path = _elongation_fit(str(tmp_path), "force_N,u_mm,sd\n0.1,1.9,0.05\n0.5,10.2,inf\n", sigma=None,
                           sigma_column="sd")
    with pytest.raises(CalibrationError, match="line 3, column 'sd'") as info:
        load_fit(path)
    assert info.value.path == "data[0].sigma_column"


def test_a_spreadsheet_csv_with_a_byte_order_mark_reads_its_first_column(tmp_path):
    """Excel's "CSV UTF-8" starts with a byte-order mark; before, its first column was
    '\\ufeffforce_N' and 'no column force_N' listed force_N among the columns."""
    spec = load_fit(_elongation_fit(str(tmp_path), GOOD, bom=True))
    assert list(spec.data[0].levels) == [0.1, 0.5, 1.0]


def test_repeated_trials_at_one_load_are_data_points_each(tmp_path):
    """Three trials at 0.5: three residuals at one solved level (before: refused without naming
    the level)."""
    spec = load_fit(_elongation_fit(str(tmp_path), "force_N,u_mm\n0.1,1.9\n0.5,10.1\n0.5,10.3\n1.0,22.6\n0.5,10.2\n"))
    d = spec.data[0]
    assert list(d.levels) == [0.1, 0.5, 0.5, 0.5, 1.0]
    assert list(d.values * 1e3) == pytest.approx([1.9, 10.1, 10.3, 10.2, 22.6])
    assert spec.levels == [0.1, 0.5, 1.0]


@pytest.mark.parametrize("scale", [-1e-3, 0.0])
def test_a_negative_or_zero_value_scale_is_refused(tmp_path, scale):
    with pytest.raises(CalibrationError) as info:
        load_fit(_elongation_fit(str(tmp_path), GOOD, value_scale=scale))
    assert info.value.path == "data[0].value_scale" and "must be > 0" in info.value.message


@pytest.mark.parametrize("quantity", ["elongation", "stiffness"])
def test_an_elongation_of_a_direction_vector_probe_is_refused(tmp_path, quantity):
    """The bar's r_y probe (tip_ry) as an elongation: its x-change (dimensionless, ~1e-18) was
    fitted as metres (mu 'not determined', cost 3e5); now refused, naming the probe."""
    with pytest.raises(CalibrationError) as info:
        load_fit(_elongation_fit(str(tmp_path), GOOD, quantity=quantity, probe=None, probes=["tip", "tip_ry"]))
    assert info.value.path == "data[0].probes[1]" and "measures r_y" in info.value.message
    assert "got 'tip_ry'" in info.value.message


def test_a_difference_of_a_position_and_a_direction_probe_is_refused(tmp_path):
    """tip (r, m) minus tip_ry (r_y, dimensionless) was fitted as a displacement difference."""
    with pytest.raises(CalibrationError) as info:
        load_fit(_elongation_fit(str(tmp_path), GOOD, quantity="difference", probe=None, probes=["tip", "tip_ry"]))
    assert info.value.path == "data[0].probes" and "mixes units" in info.value.message
    assert "got ['tip', 'tip_ry']" in info.value.message


def test_a_misspelt_parameter_key_is_blamed_on_the_key_not_the_bounds(tmp_path):
    """Before: "the model config refuses mu = 200000 ...; change the bounds"."""
    path = _elongation_fit(str(tmp_path), GOOD, parameters=(dict(MU, key="beams[0].material.muu"),))
    with pytest.raises(CalibrationError) as info:
        load_fit(path)
    assert info.value.path == "parameters[0].key"
    assert "not a value of the model config" in info.value.message and "check the key path" in info.value.message
    assert "bounds" not in info.value.message


def test_two_parameters_on_one_config_value_are_refused(tmp_path):
    path = _elongation_fit(str(tmp_path), GOOD, parameters=(MU, dict(K, key=MU["key"], name="mu2",
                                                                     bounds=MU["bounds"], start=MU["start"])))
    with pytest.raises(CalibrationError) as info:
        load_fit(path)
    assert info.value.path == "parameters[1]" and "also set by parameters[0]" in info.value.message


def test_the_linear_model_errors_keep_the_sigmas_when_the_fit_is_better_than_them():
    """s² = max(χ²/(m − n), 1): residuals of 0.1 σ do not shrink the errors 10-fold."""
    rng = np.random.default_rng(3)
    J = rng.normal(size=(5, 2))
    small = uncertainty(J, 0.1 * rng.normal(size=5))
    absolute = uncertainty(J, 0.1 * rng.normal(size=5), absolute=True)
    assert small.chi2_dof < 0.1 and small.s2 == 1.0 and small.floored
    assert small.se_u == pytest.approx(absolute.se_u) and small.t95 == pytest.approx(1.959964, abs=1e-6)
    big = uncertainty(J, 3.0 * rng.normal(size=5))
    assert big.s2 == pytest.approx(big.chi2_dof) and big.s2 > 1 and not big.floored and big.t95 > 3


def test_a_small_fit_better_than_its_sigma_gets_the_absolute_sigma_verdict(tmp_path):
    """Three elongations of the bar (σ = 50 µm) that the model meets to 0.1 σ, μ and K fitted:
    before, s² = χ²/(m − n) ≈ 0.01 shrank μ's interval 10-fold ("determined" where absolute σ
    said "not determined"); now both read the same."""
    petsc_init()
    from ancf_petsc.workflows.calibration.calibrate import run_calibration
    from ancf_petsc.workflows.calibration.report import markdown
    from ancf_petsc.workflows.calibration.twin import exact_data, with_data
    levels = [0.2, 0.6, 1.0]
    text = "force_N,u_mm\n" + "".join(f"{lv},1\n" for lv in levels)
    out = {}
    for absolute in (False, True):
        d = tmp_path / str(absolute)
        d.mkdir()
        spec = load_fit(_elongation_fit(str(d), text, fit={"objective": {"absolute_sigma": absolute}}))
        exact = exact_data(spec, TRUE)
        noisy = {"elongation": exact["elongation"] + 0.1 * 5e-5 * np.array([1.0, -1.0, 0.5])}
        spec.identifiability.points = 5
        out[absolute] = run_calibration(with_data(spec, noisy, str(d / "out")), fresh=True, say=lambda *_: None)
    default, absolute = out[False], out[True]
    assert default.uncertainty.chi2_dof < 0.1 and default.uncertainty.floored
    for p, q in zip(default.parameters, absolute.parameters):
        assert p.verdict == q.verdict and p.width == pytest.approx(q.width, rel=1e-6), (p, q)
    print([(p.name, p.verdict, p.width) for p in default.parameters])
    md = markdown(default, type("L", (), {"counts": lambda self: {"completed": 3}})())
    assert "the data fit better than their σ" in md and "{" not in md


def test_a_forgotten_value_scale_is_named_at_the_start_without_numpy_warnings(tmp_path):
    """Data in mm read as metres: the start's model / data ratio (about 1e-3) names value_scale;
    the fit at the bounds reports infinite intervals without an overflow warning."""
    petsc_init()
    from ancf_petsc.workflows.calibration.calibrate import run_calibration
    path = bar_case(str(tmp_path), identifiability={"profiles": False})
    doc = yaml.safe_load(open(path))
    doc["data"][0].pop("value_scale")
    yaml.safe_dump(doc, open(path, "w"))
    lines = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = run_calibration(load_fit(path), fresh=True, say=lines.append)
    hint = [line for line in lines if "warning: elongation: model / data" in line]
    assert len(hint) == 1 and "value_scale" in hint[0] and "(1e-3 for mm; now 1)" in hint[0], lines
    assert not any("warning: lateral" in line for line in lines)
    assert res.parameters[0].at_bound


@pytest.mark.parametrize("text,data,path,match", [
    ("force_N,u_mm,u_mm\n0.1,1.9,2.0\n0.5,10.2,10.0\n1.0,22.6,22.0\n", {}, "data[0].file",
     "data.csv: column 'u_mm' appears twice in the header line: rename one"),
    ("0.1,1.9\n0.5,10.2\n1.0,22.6\n", {"load": "0.1", "value": "1.9"}, "data[0].file",
     "its header line (line 1) '0.1,1.9' is numbers, not column names"),
    ("force_N,u_mm\n0.1,1.9\n0.5,10_2\n1.0,22.6\n", {}, "data[0].value",
     "data.csv, line 3, column 'u_mm': '10_2' is not a finite number"),
    ("force_N,1\n0.1,1.9\n0.5,10.2\n1.0,22.6\n", {"value": 1}, "data[0].value",
     "expected a column name; got the number 1: a column named by digits is quoted in YAML ('1')"),
], ids=["duplicate", "no-header", "underscore", "numeric-name"])
def test_a_data_table_read_otherwise_than_written_is_refused(tmp_path, text, data, path, match):
    """Before: a column named twice gave values of both interleaved (u_mm read as 1.9, 2.0, 10.2
    for 1.9, 10.2, 22.6); a file with no header line lost its first row; a cell 10_2 was read as
    102; value: 1 (YAML's int) said 'no column 1 in data.csv (columns: force_N, 1)'."""
    with pytest.raises(CalibrationError) as info:
        load_fit(_elongation_fit(str(tmp_path), text, **data))
    assert info.value.path == path and match in info.value.message, (info.value.path, info.value.message)
