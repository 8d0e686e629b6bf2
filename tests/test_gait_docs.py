"""docs/gait.md: its envelope tables are the committed CSVs' (docs/gait_envelope_*.csv, written by
scripts/bench_envelope.py --csv), rendered by workflows.envelope.render_docs."""
import os

from ancf_petsc.workflows.envelope import render_docs

DOCS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "docs")


def test_envelope_tables_match_their_csvs():
    text = open(os.path.join(DOCS, "gait.md")).read()
    assert text.count("<!-- envelope:") >= 2
    assert render_docs(text, DOCS) == text


def test_a_block_filter_picks_its_rows(tmp_path):
    """Friction cells share twist and bias with the frictionless ones: ``:friction=0.3`` picks."""
    import csv
    head = ["base", "law", "friction", "twist", "bias", "elements", "stride", "status", "last_level",
            "iterations", "iterations_to_1200", "cutbacks", "cutbacks_to_1200", "levels",
            "median_iterations", "cutback_levels", "solve_time", "wall_time", "message", "solver"]
    rows = [dict(zip(head, ["a.yaml", "sliding", mu, 90.0, "uniform", 4, False, "completed", 3000,
                            its, its, 0, 0, 12, 3, 0, 1.0, 1.0, "", "after"])) for mu, its in ((0.0, 41), (0.3, 57))]
    with open(tmp_path / "gait_envelope_friction.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=head)
        w.writeheader()
        w.writerows(rows)
    text = "<!-- envelope:friction:sliding:friction=0.3 -->\n<!-- /envelope -->"
    out = render_docs(text, str(tmp_path))
    assert "| 90 | 57 |" in out and "41" not in out
    out = render_docs("<!-- envelope:friction:sliding:friction=0 -->\n<!-- /envelope -->", str(tmp_path))
    assert "| 90 | 41 |" in out and "57" not in out
