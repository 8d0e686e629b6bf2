"""The cause code of a failed run (solving/failure_cause.py): the most specific finding wins, in
the documented order; the envelope counts its failures by it (workflows/envelope_summary.py)."""
from types import SimpleNamespace

from ancf_petsc.solving.failure_cause import (CAUSES, JUMP_CAUSES, Detail, give_up_cause,
                                              with_critical_point)
from ancf_petsc.solving.records import LoadStepFailure
from ancf_petsc.workflows.envelope_summary import failure_causes, summary_line


def test_the_most_specific_finding_names_the_cause():
    kink = SimpleNamespace(kind="c0_kink")
    newton = Detail(" (Newton cycles ...)", "newton_cycle")
    unstable = (41.5, 1, 0)
    assert give_up_cause(False, False, None, None, newton) == "newton_cycle"
    assert give_up_cause(False, False, None, unstable, newton) == "unstable_state"
    assert give_up_cause(False, False, kink, unstable, newton) == "c0_kink"
    assert give_up_cause(False, True, kink, unstable, newton) == "projection_lost"
    assert give_up_cause(True, True, kink, unstable, newton) == "inverted_element"
    assert give_up_cause(False, False, None, None, " plain text") == ""      # the reason's code, below
    # a critical point of the tangent outranks what Newton did, not a jump or a lost projection
    assert with_critical_point("newton_linear") == with_critical_point("unstable_state") == "critical_point"
    assert with_critical_point("min_increment") == "critical_point"
    for cause in JUMP_CAUSES + ("inverted_element", "projection_lost"):     # the order, written out
        assert with_critical_point(cause) == cause
    assert set(JUMP_CAUSES) <= set(CAUSES)


def test_a_failure_without_a_finding_keeps_its_reason_as_cause():
    f = LoadStepFailure(100.0, 50.0, 40.0, "DIVERGED_FNORM_NAN", False)
    assert (f.code, f.cause) == ("DIVERGED_FNORM_NAN", "diverged_fnorm_nan")
    f = LoadStepFailure(100.0, 50.0, 40.0, "DIVERGED_MAX_IT", False, " (...)", "c0_kink")
    assert f.cause == "c0_kink" and str(f).endswith("with DIVERGED_MAX_IT (...)")
    detail = Detail(" (no cut-back was tried ...)", "min_increment")
    assert detail == " (no cut-back was tried ...)" and detail.kind == "min_increment"
    assert (detail + "; more").startswith(" (no cut-back")       # a plain str once joined


def test_the_envelope_counts_its_failures_by_cause():
    def row(status, cause="", stride=False):
        return dict(solver="after", status=status, cause=cause, stride=stride, twist=45.0, iterations_to_1200=40,
                    cutbacks_to_1200=0)
    rows = [row("completed"), row("failed", "c0_kink"), row("failed", "c0_kink"), row("failed", "critical_point"),
            row("crashed"), row("failed")]
    assert failure_causes(rows) == {"c0_kink": 2, "critical_point": 1, "crashed": 1, "failed": 1}
    line = summary_line(rows, "after")
    assert line.startswith("[after] 6 cells: 5 not completed (c0_kink 2, critical_point 1, crashed 1, failed 1); "
                           "0 columns at twist <= 90"), line


def test_a_grid_csv_names_the_cells_to_run_again(tmp_path):
    """bench_envelope.py --failed-in: the cells a grid's CSV records as not completed, matched by
    the row's key columns (a stride and a column of the same model are different cells)."""
    import csv
    from ancf_petsc.workflows.envelope import NEO, CellResult, EnvelopeCell
    from ancf_petsc.workflows.envelope_summary import cell_key, not_completed
    cells = [EnvelopeCell(NEO, 90.0, "soleus", "unilateral"), EnvelopeCell(NEO, 90.0, "soleus", "unilateral", stride=True),
             EnvelopeCell(NEO, 45.0, "uniform", "sliding", 0.3)]
    rows = [dict(CellResult(c, s, cause="c0_kink" if s == "failed" else "").row(), solver="after")
            for c, s in zip(cells, ("completed", "failed", "timeout"))]
    with open(tmp_path / "grid.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    assert not_completed(str(tmp_path / "grid.csv")) == {cell_key(cells[1]), cell_key(cells[2])}
    assert rows[1]["cause"] == "c0_kink"


def test_a_missing_failed_in_csv_is_one_line_not_a_traceback(tmp_path, capsys):
    import pytest
    from apps.envelope import main
    with pytest.raises(SystemExit) as exc:
        main(["--grid", "core", "--failed-in", str(tmp_path / "none.csv"), "--work", str(tmp_path)])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--failed-in" in err and "no such file" in err and "Traceback" not in err
