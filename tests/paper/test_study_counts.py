"""The contact study's and Table 2's counts of a run continued with --restart (a report stopped
by Ctrl-C and run again) or killed (summary.json still 'running', no totals)."""
import numpy as np

from ancf_petsc import paper as rp
from ancf_petsc.paper import contact_study as cs
from ancf_petsc.paper.tables import table2_row
from helpers import PAPER_INPUTS

PAPER = rp.read_paper(PAPER_INPUTS.table1_csv)


def _column(**extra) -> dict:
    """A column's summary.json: 13 levels, 4 Newton iterations each to 100 N, then 1."""
    probes = {k: {"displacement": [1e-3, 0.0, 0.0]} for k in ("soleus", "medial_gastrocnemius",
                                                             "lateral_gastrocnemius")}
    steps = [{"load_factor": float(f), "iterations": 4 if i < 9 else 1, "probes": probes,
              "contact": {"a": {"open_share": 0.0}}} for i, f in enumerate(PAPER["load_N"])]
    return dict({"status": "completed", "steps": steps, "newton_iterations": 40, "timings": {"total": 1.0}}, **extra)


def test_a_continued_or_killed_column_counts_its_whole_run():
    """A column continued from level 9 (its last process took 4 of the run's 40 Newton
    iterations): the contact-laws table and the scaling study gave 4, as the run-time table did
    before 08c9fa5; a killed Table 2 run (no 'timings', no 'newton_iterations') ended the report
    in a KeyError traceback."""
    whole = _column()
    continued = _column(newton_iterations=4, restarted_from={"step": 9, "load_factor": 100.0})
    t1 = rp.table1_from(PAPER_INPUTS, {0: whole, 15: whole, 45: continued})
    assert "ψ=45°: 40 / 40." in cs.laws_markdown(t1, t1)
    assert cs.scaling_row(continued, "sliding", 1.0, None, "completed")["iterations"] == 40
    killed = _column(status="running")
    del killed["timings"], killed["newton_iterations"]
    row = table2_row(killed, "crashed", "killed")
    assert np.isnan(row["time"]) and row["iterations"] == 40 and row["elong"] == 1.0
    assert table2_row(continued, "completed", "")["iterations"] == 40
