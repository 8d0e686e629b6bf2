"""A level reported just past a gap of the load path (solving/step_over.py) is a level reached in
every table that matches a run's levels to the levels asked (io/levels.py ``step_at``), at its
reported load factor and marked so.  The run: the second subject's 180° column whose 1600 N is
reported at 1640 N (tests/solving/test_step_over.py), read as a paper column over a Table 1
of its own levels.  Before: 'not reached' in Tables 1 and 2, NaN in the contact study and the
accuracy ladder, and 'ψ = 45°: not reached 1600 N (the run ended completed)'."""
import importlib
import math
import os
import shutil

import numpy as np
import pytest

from ancf_petsc import paper as rp
from ancf_petsc.io.levels import step_at
from ancf_petsc.paper import contact_study, existing
from ancf_petsc.workflows import refinement, study
from helpers import PAPER_INPUTS

from solving.test_fade_switch import run
from solving.test_step_over import gap_column

pytestmark = pytest.mark.slow
LEVELS = (1000.0, 1200.0, 1600.0)
NOTE = "1600 N: reported at 1640 N, past a gap of the load path"


@pytest.fixture(scope="module")
def gap(tmp_path_factory):
    """(the run's RunResult, PaperInputs whose Table 1 has the run's levels)."""
    res = run(gap_column(), tmp_path_factory.mktemp("gap"))
    assert res.summary["steps"][-1]["passed_over"]["level"] == 1600.0, res.message
    configs = tmp_path_factory.mktemp("configs")
    os.makedirs(configs / "data")
    shutil.copy(PAPER_INPUTS.table2_csv, configs / "data")
    with open(configs / "data" / "paper_table1_elongation.csv", "w") as fh:
        fh.write("load_N,psi0_mm,psi15_mm,psi45_mm\n" + "".join(
            f"{f:g},{e},{e},{e}\n" for f, e in zip(LEVELS, (17.0, 44.0, 62.0))))
    return res, rp.PaperInputs(str(configs))


def soleus_mm(step: dict) -> float:
    return 1e3 * step["probes"]["soleus"]["displacement"][0]


def test_table1_and_the_levels_not_reached(gap):
    res, inputs = gap
    t1 = rp.table1_from(inputs, {45: res.summary})
    last = res.summary["steps"][-1]
    assert t1.ours[45][2] == soleus_mm(last) and t1.curve(45)[0] == [1000.0, 1200.0, 1640.0]
    text = t1.markdown()
    assert "not reached" not in text and f"| 62.000 | {soleus_mm(last):.3f}† | " in text
    assert f"† ψ=45°, {NOTE}" in text and "3 of 3 entries reached" in text
    assert existing.levels_missing(t1, {45: res.summary}) == ""


def test_table2(gap):
    res, inputs = gap
    row = rp.tables.table2_row(res.summary, "completed", "", load=1600.0)
    assert row["elong"] == soleus_mm(res.summary["steps"][-1]) and row["reported_at"] == 1640.0
    rows = {(v, p, n): dict(row) for v in rp.T2_VARIANTS for p in rp.TWISTS for n in rp.T2_ELEMENTS}
    text = rp.table2_markdown(inputs, rows)
    assert "stopped after" not in text and f"{row['elong']:.3f}†" in text
    assert "† linear gap, ψ=45°, 16 element(s), 400 N: reported at 1640 N, past a gap" in text


def test_contact_study(gap):
    res, inputs = gap
    loads = {"e10": 1200.0, "e400": 1600.0}
    row = contact_study.scaling_row(res.summary, "sliding", 1.0, None, "completed", loads)
    assert row["e400"] == soleus_mm(res.summary["steps"][-1]) and row["reported"] == {"e400": (1600.0, 1640.0)}
    text = contact_study.scaling_markdown([row, dict(row, mode="unilateral"), dict(row, space="per element")])
    assert f"{row['e400']:.6f}†" in text and f"† sliding, default, k_s scale 1, {NOTE}" in text
    t1 = rp.table1_from(inputs, {p: res.summary for p in rp.TWISTS})
    laws = contact_study.laws_markdown(t1, t1)
    line = next(ln for ln in laws.splitlines() if ln.startswith("| 1600 |"))
    assert line.count("†") == 6 and "| 0/0/0 % |" in line, line        # open shares of the 1640 N state
    assert f"† unilateral, ψ=0°, {NOTE}" in laws


def test_slip_figure_draws_the_level(gap, monkeypatch):
    res, inputs = gap
    figures = importlib.import_module("ancf_petsc.paper.figures")   # the package's name is its function
    read = []
    monkeypatch.setattr(figures, "SLIP_LEVELS", (1000.0, 1600.0))
    monkeypatch.setattr(figures, "read_contact", lambda h5, k: read.append(k) or {})
    monkeypatch.setattr(figures.viz, "plot_slip", lambda *a, **k: "slip.png")
    t1 = rp.table1_from(inputs, {45: dict(res.summary, output_dir=res.summary["output_dir"])})
    assert figures.slip_figures(t1, "unused") == ["slip.png"] and read == [1, 3]


def test_accuracy_and_study_values(gap, monkeypatch, tmp_path):
    res, _ = gap
    s = res.summary
    assert refinement.quantity(s, "soleus", "x", 1600.0) == s["steps"][-1]["probes"]["soleus"]["displacement"][0]
    assert math.isnan(refinement.quantity(s, "soleus", "x", 1500.0))
    assert step_at(s["steps"], 1640.0) is s["steps"][-1] and step_at(s["steps"], 1200.0) is s["steps"][1]
    # ancf-study's row at the level: its value and where it was reported
    monkeypatch.setattr(study, "solve_raw", lambda raw, base, out: (res, s))
    scene = study.Scene(gap_column(), "", "soleus", "x", 1600.0)
    row = study.measure(scene, refinement.Discretisation(), str(tmp_path))
    assert row.value == s["steps"][-1]["probes"]["soleus"]["displacement"][0]
    assert row.message == "reported at 1640, past a gap of the load path"


def test_existing_says_the_run_passed_over_a_level(gap):
    res, inputs = gap
    run_dir = existing.ExistingRun(res.summary["output_dir"], PAPER_INPUTS)
    assert run_dir.ended().startswith("completed (LEVELS_PASSED_OVER: completed, but 1 level(s) not reached")
    assert "1600 at 1640" in run_dir.ended()
    # the run's own tables name the level asked beside the load factor it was reported at
    text = "\n".join(existing.runs_markdown([run_dir]).splitlines())
    assert text.count("| 1640 (level 1600, past a gap of the load path) | ") == 2, text
    assert "| 1200 | " in text
