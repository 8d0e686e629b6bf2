"""docs/solid_comparison.md's tables are what ancf_verify.bars.report makes of the committed
docs/solid_comparison.csv (``python scripts/verify_solid.py`` writes both): the summary table and
every case's table, regenerated from the CSV and compared line by line, all but the wall-time
columns (the CSV keeps times to 4 digits, the page printed them from the run: 0.2285 s → 0.228 /
0.229, and the speed-ups are their ratios).  No dolfinx here."""
import os

from ancf_verify.bars.cases import CASES
from ancf_verify.bars.report import results_of_csv, summary_table, table
from helpers import ROOT

CSV = os.path.join(ROOT, "docs", "solid_comparison.csv")
MD = os.path.join(ROOT, "docs", "solid_comparison.md")


#: wall-time columns (0-based cells) of the summary table and of a case table
SUMMARY_TIMES, CASE_TIMES = (2, 4, 5, 6), (3,)


def _masked(line: str, columns) -> str:
    cells = line.split("|")[1:-1]
    return "|".join("" if i in columns else c for i, c in enumerate(cells))


def _page_rows(columns) -> set:
    with open(MD, encoding="utf-8") as fh:
        return {_masked(ln, columns) for ln in fh.read().splitlines() if ln.startswith("|")}


def test_the_summary_table_is_that_of_the_csv():
    lines = summary_table(results_of_csv(CSV))
    page = _page_rows(SUMMARY_TIMES)
    missing = [ln for ln in lines if _masked(ln, SUMMARY_TIMES) not in page]
    assert len(lines) == 2 + len(CASES) and not missing, missing


def test_every_case_table_is_that_of_the_csv():
    results, page = results_of_csv(CSV), _page_rows(CASE_TIMES)
    assert set(results) == {c.key for c in CASES}
    for case in CASES:
        _, rows, ref, unc, how, _ = results[case.key]
        lines = [ln for ln in table(case, rows, ref, unc, how) if ln.startswith("|")]
        missing = [ln for ln in lines if _masked(ln, CASE_TIMES) not in page]
        assert len(lines) > 10 and not missing, (case.key, missing[:2])
