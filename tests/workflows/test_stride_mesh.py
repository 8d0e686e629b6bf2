"""The stride's mesh study (workflows/stride_mesh.py): its outputs and errors on made-up series,
a two-rung ladder of the real stride, and the docs' table against the committed CSV."""
import csv
import math
import os
import re

import numpy as np

from ancf_petsc.workflows.stride_mesh import (LAWS, kind_of, markdown, mesh_errors, observed_order,
                                              run_ladder, stride_series, with_errors)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _step(strain, diff, normal, pressing):
    return {"subtendons": {"soleus": {"strain": strain}},
            "displacement_differences": {"soleus|medial_gastrocnemius": {"end": diff}},
            "contact": {"mg_sol (soleus|medial_gastrocnemius)": {"normal_force": normal, "pressing_force": pressing}}}


def test_series_errors_and_order_on_made_up_outputs():
    s = stride_series({"steps": [_step(0.1, 1e-3, -5.0, 2.0), _step(0.2, 2e-3, -10.0, 4.0)]})
    assert sorted(s) == ["difference soleus|medial_gastrocnemius", "normal force mg_sol", "pressing force mg_sol",
                         "strain soleus"]
    assert kind_of("pressing force mg_sol") == "pressing force" and kind_of("normal force x") == "normal force"
    # q_n = q + c / n^2: errors against the finest and an observed order of 2
    ladder = {n: {k: v + 1e-3 * np.abs(v).max() * 64.0 / n ** 2 for k, v in s.items()} for n in (2, 4, 8, 16)}
    err = mesh_errors(ladder)
    assert sorted(err) == [2, 4, 8]
    for k in s:
        expected = 1e-3 * np.abs(s[k]).max() * 64.0 * (1 / 64 - 1 / 256) / np.abs(ladder[16][k]).max()
        assert math.isclose(err[8][k], expected, rel_tol=1e-9)
        assert math.isclose(observed_order(ladder, k), 2.0, rel_tol=1e-9)
    # a rung with other frames has no error, and a zero output has none either
    ladder[4] = {k: v[:1] for k, v in ladder[4].items()}
    assert all(math.isnan(e) for e in mesh_errors(ladder)[4].values())
    assert math.isnan(mesh_errors({1: {"strain a": np.zeros(2)}, 2: {"strain a": np.zeros(2)}})[1]["strain a"])


def test_a_two_rung_ladder_of_the_stride(tmp_path):
    """The sliding stride at 1 and 2 elements: both complete all 100 frames, and the coarse one's
    strains are within 1 % of the finer one's (docs/gait.md: 2e-3 of 16 elements at 2)."""
    rows, series = run_ladder(LAWS["sliding"], [1, 2], [os.path.join(ROOT, ".venv", "bin", "ancf-solve")],
                              str(tmp_path))
    assert [r["status"] for r in rows] == ["completed", "completed"], rows
    assert all(r["frames"] == 100 and r["frames_per_s"] > 0 for r in rows)
    out = with_errors(rows, series)
    assert out[1]["error_strain"] == "" and 0.0 < float(out[0]["error_strain"]) < 1e-2, out
    assert "reference" in markdown(out)


def test_the_docs_table_is_the_committed_csv():
    path = os.path.join(ROOT, "docs", "gait_stride_mesh.csv")
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    with open(os.path.join(ROOT, "docs", "gait.md")) as fh:
        text = fh.read()
    assert markdown(rows) in text
    assert {r["law"] for r in rows} == {law.label for law in LAWS.values()}
    assert os.path.isfile(os.path.join(ROOT, "docs", "figures", "stride_mesh.png"))
    assert re.search(r"scripts/stride_mesh_study\.py", text)
