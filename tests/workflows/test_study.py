"""ancf-study: the speed-accuracy study and the stability map (small grids of the bending scene)."""
import csv
import math
import os

import pytest
import yaml

from helpers import CONFIGS, FAILURE_MESSAGE, MPI_ENV, ROOT, VENV_BIN, petsc_init


def _write(tmp_path, doc, name="study.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return str(path)


BASE = os.path.join(CONFIGS, "bending_neohookean.yaml")


def test_pareto_study_ranks_discretisations_against_the_reference(tmp_path):
    petsc_init()
    from ancf_petsc.workflows.study import load_study, run_study
    spec = load_study(_write(tmp_path, {
        "kind": "pareto", "base": BASE, "probe": "tip", "component": "z",
        "grid": {"elements": [1, 2, 4, 8], "axial_points": [2, 3]},
        "reference": {"elements": 32, "axial_points": 2, "richardson": True},
        "output": str(tmp_path / "out")}))
    res = run_study(spec, log=lambda *_: None)
    rows = res["rows"]
    assert len(rows) == 8 and all(r.status == "completed" for r in rows)
    ref = res["reference"]
    for r in rows:
        assert r.rel_error == pytest.approx(abs(r.value - ref) / abs(ref))
    # reduced axial integration converges much faster than full (shear/Poisson locking)
    err = {(r.elements, r.axial_points): r.rel_error for r in rows}
    assert err[(8, 2)] < 1e-3 < 0.02 < err[(8, 3)]
    assert err[(2, 2)] > err[(4, 2)] > err[(8, 2)]          # (1 element: pre-asymptotic)
    # the Pareto front: non-dominated, and every other row is dominated by one of its members
    front = [r for r in rows if r.pareto]
    assert front
    for r in rows:
        beaten = any(f.wall_time <= r.wall_time and f.rel_error <= r.rel_error for f in front)
        assert beaten
    with open(res["csv"]) as fh:
        table = list(csv.DictReader(fh))
    assert len(table) == 8 and {"wall_time", "rel_error", "pareto", "dofs"} <= set(table[0])
    assert os.path.getsize(res["png"]) > 10_000


def test_rows_give_the_cubature_degree_the_run_integrates_with(tmp_path):
    """33103 raises its section rule to degree 6: the grid's degrees 2 and 4 were two rows
    'deg 2' and 'deg 4' (CSV cubature_degree 2, 4) of one degree-6 run; 3363 keeps its own."""
    petsc_init()
    from ancf_petsc.workflows.study import load_study, run_study
    spec = load_study(_write(tmp_path, {
        "kind": "pareto", "base": BASE, "probe": "tip", "component": "z",
        "grid": {"element": ["33103", "3363"], "cubature_degree": [2, 4], "elements": [1]},
        "reference": {"elements": 2, "element": "3363"}, "output": str(tmp_path / "out")}))
    rows = run_study(spec, log=lambda *_: None)["rows"]
    got = sorted((r.element, r.cubature_degree, r.label) for r in rows)
    assert got == [("33103", 6, "33103, 1 el, deg 6")] * 2 + [("3363", 2, "3363, 1 el, deg 2"),
                                                               ("3363", 4, "3363, 1 el, deg 4")], got
    r33103 = [r.value for r in rows if r.element == "33103"]
    assert r33103[0] == r33103[1]


def test_stability_map_default_strategy_converges_and_failures_are_clean(tmp_path):
    petsc_init()
    from ancf_petsc.workflows.stability import default_strategy_converged, load_stability, run_stability
    spec = load_stability(_write(tmp_path, {
        "kind": "stability", "base": BASE, "probe": "tip", "component": "z",
        "axes": {"increment": ["adaptive", 1.0], "linesearch": ["basic"],
                 "bulk_ratio": [10, 10000], "element": ["3363", "3333", "3333-none"]},
        "reference": {"elements": 16, "axial_points": 2}, "max_it": 30,
        "output": str(tmp_path / "map")}))
    res = run_stability(spec, log=lambda *_: None)
    cells = res["cells"]
    assert len(cells) == 12
    assert default_strategy_converged(res)
    failed = [c for c in cells if c["status"] != "completed"]
    assert failed, "full Newton in one load increment is expected to fail here"
    for c in failed:
        assert FAILURE_MESSAGE.match(c["message"]), c["message"]
        assert c["increment"] == 1.0          # only the one-increment raw method fails
    # locking: 3333 without its remedy converges to a far too stiff answer near incompressibility
    locked = [c for c in cells if c["element"] == "3333-none" and c["increment"] == "adaptive"]
    assert all(c["rel_error"] > 0.5 for c in locked)
    healthy = [c for c in cells if c["element"] == "3363" and c["increment"] == "adaptive"]
    assert all(c["rel_error"] < 0.1 for c in healthy)
    assert os.path.getsize(res["png"]) > 10_000


@pytest.mark.parametrize("doc,words", [
    ({"kind": "pareto", "probe": "tip"}, "base: missing value"),
    ({"kind": "pareto", "base": BASE, "probe": "nope", "grid": {"elements": [1]}}, "probe: no probe 'nope'"),
    ({"kind": "pareto", "base": BASE, "probe": "tip", "grid": {"elements": [0]}},
     "grid.elements: expected a non-empty list of integers >= 1"),
    ({"kind": "pareto", "base": BASE, "probe": "tip", "grid": {"element": ["3300"]}},
     "grid.element: expected a list of element types"),
    ({"kind": "stability", "base": BASE, "probe": "tip", "axes": {"contact": ["sliding"]}},
     "axes.contact: the base config has no contact"),
    ({"kind": "stability", "base": BASE, "probe": "tip", "axes": {"increment": [2.0]}},
     "axes.increment: expected 'adaptive' or fractions"),
    ({"kind": "sideways", "base": BASE}, "kind: must be pareto or stability"),
])
def test_study_file_errors_are_one_line_with_the_key(tmp_path, doc, words):
    import subprocess
    cmd = [os.path.join(VENV_BIN, "ancf-study"), _write(tmp_path, doc)]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=dict(os.environ, **MPI_ENV))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr and math.isfinite(2.0)


def test_a_bundle_is_a_scene_and_a_history_is_refused_by_name(tmp_path):
    """A ``bundle:`` config (configs/bundle_hex7.yaml) was refused as 'is not a model config (no
    beams/steps)', and so was a load history, though both are model configs.  A bundle is now
    expanded as ancf-solve expands it (its probes 'centre' and 'outer'); a cell's value is the
    single run's; a history is refused as a history."""
    petsc_init()
    from ancf_petsc.config.parse import load_config
    from ancf_petsc.workflows.study import StudyError, load_study, run_study
    from helpers import run_inline, load_raw
    spec = load_study(_write(tmp_path, {
        "kind": "pareto", "base": os.path.join(CONFIGS, "bundle_hex7.yaml"), "probe": "outer",
        "component": "x", "grid": {"elements": [1]}, "reference": {"elements": 2},
        "output": str(tmp_path / "out")}))
    res = run_study(spec, log=lambda *_: None)
    raw = load_raw("bundle_hex7.yaml")
    raw["bundle"]["elements"] = 1
    single = run_inline(raw, tmp_path / "single")["steps"][-1]["probes"]["outer"]["displacement"][0]
    assert res["rows"][0].status == "completed" and res["rows"][0].value == pytest.approx(single, rel=1e-10)
    hist = tmp_path / "hist.yaml"
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.pop("steps")
    raw["history"] = {"table": {"time": [0.0, 1.0], "f": [10.0, 30.0]}}
    raw["loads"][0]["column"] = "f"
    hist.write_text(yaml.safe_dump(raw, sort_keys=False))
    with pytest.raises(StudyError) as exc:
        load_study(_write(tmp_path, {"kind": "pareto", "base": str(hist), "probe": "tip",
                                     "grid": {"elements": [1]}}, name="h.yaml"))
    assert exc.value.path == "base" and "follows a load history" in str(exc.value)
    assert load_config(str(hist)).history is not None


@pytest.mark.parametrize("kind", ["pareto", "stability"])
def test_a_reference_of_zero_is_refused_by_its_component(tmp_path, kind):
    """bundle_hex7's outer tip y is held by the grip: its reference is 0 and every row's error
    divided by it raised ZeroDivisionError (a traceback from ancf-study, exit 1)."""
    petsc_init()
    from ancf_petsc.workflows.stability import load_stability, run_stability
    from ancf_petsc.workflows.study import StudyError, load_study, run_study
    doc = {"kind": kind, "base": os.path.join(CONFIGS, "bundle_hex7.yaml"), "probe": "outer", "component": "y",
           "reference": {"elements": 1}, "output": str(tmp_path / "out")}
    doc.update({"grid": {"elements": [1]}} if kind == "pareto" else {"axes": {"linesearch": ["basic"]}})
    load, run = (load_study, run_study) if kind == "pareto" else (load_stability, run_stability)
    with pytest.raises(StudyError) as exc:
        run(load(_write(tmp_path, doc)), log=lambda *_: None)
    assert exc.value.path == "component" and "is 0" in exc.value.message and "got y" in exc.value.message


def test_an_axis_value_the_scene_refuses_is_named_by_its_axis(tmp_path):
    """configs/bundle_circle7.yaml with axes.contact [sliding] (circles touch along lines only):
    the reference's config error was reported as 'reference: the reference at {'contact':
    'sliding'} did not converge: ...', a solver failure at a key the study file did not set."""
    petsc_init()
    from ancf_petsc.workflows.stability import load_stability, run_stability
    from ancf_petsc.workflows.study import StudyError
    spec = load_stability(_write(tmp_path, {
        "kind": "stability", "base": os.path.join(CONFIGS, "bundle_circle7.yaml"), "probe": "outer",
        "component": "x", "axes": {"contact": ["sliding"]}, "reference": {"elements": 1},
        "output": str(tmp_path / "map")}))
    with pytest.raises(StudyError) as exc:
        run_stability(spec, log=lambda *_: None)
    assert exc.value.path == "axes.contact" and "the scene refuses {'contact': 'sliding'}" in exc.value.message



@pytest.mark.parametrize("elements", [10, 6])
def test_a_richardson_reference_is_a_multiple_of_four_elements(tmp_path, elements):
    """richardson() takes its three meshes as each refined by 2, but reference elements 10 solved
    2, 5 and 10 elements: on the cantilever with 3 axial points a 'limit' of 0.039198 m where the
    meshes 20, 40, 80 extrapolate to 0.040069 m, every row's error measured from it. Such a count
    is refused before anything is solved or written, naming reference.elements."""
    from ancf_petsc.workflows.study import StudyError, load_study
    doc = {"kind": "pareto", "base": BASE, "probe": "tip", "component": "z",
           "grid": {"elements": [1]}, "reference": {"elements": elements, "richardson": True},
           "output": str(tmp_path / "out")}
    with pytest.raises(StudyError) as exc:
        load_study(_write(tmp_path, doc))
    assert exc.value.path == "reference.elements" and "multiple of 4" in exc.value.message
    assert f"got {elements}" in exc.value.message and not os.path.exists(tmp_path / "out")
    doc["reference"] = {"elements": 8, "richardson": True}
    assert load_study(_write(tmp_path, doc)).reference.elements == 8
