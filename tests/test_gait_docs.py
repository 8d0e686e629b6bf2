"""docs/gait.md: its envelope tables are the committed CSVs' (docs/gait_envelope_*.csv, written by
scripts/bench_envelope.py --csv), rendered by workflows.envelope.render_docs."""
import os

from ancf_petsc.workflows.envelope import render_docs

DOCS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "docs")


def test_envelope_tables_match_their_csvs():
    text = open(os.path.join(DOCS, "gait.md")).read()
    assert text.count("<!-- envelope:") >= 2
    assert render_docs(text, DOCS) == text
