"""docs/solid_contact.md is what scripts/verify_solid_contact.py makes of the committed
docs/solid_contact.csv: the tables are regenerated from the CSV and compared line by line.  Reads
the CSV only (no dolfinx, nothing is solved)."""
import os

import pytest

from ancf_verify.contact.report import render_md
from ancf_verify.contact.rows import SOLID, ancf_errors, read_csv
from helpers import ROOT

CSV = os.path.join(ROOT, "docs", "solid_contact.csv")
MD = os.path.join(ROOT, "docs", "solid_contact.md")

pytestmark = pytest.mark.skipif(not os.path.exists(CSV), reason="docs/solid_contact.csv not committed")


def _table_lines(text: str) -> list:
    return [ln for ln in text.splitlines() if ln.startswith("|")]


def test_tables_in_the_page_are_those_of_the_csv():
    rows = read_csv(CSV)
    regenerated = _table_lines(render_md(rows, {}))
    with open(MD, encoding="utf-8") as fh:
        page = _table_lines(fh.read())
    assert regenerated, "no tables regenerated from the CSV"
    missing = [ln for ln in regenerated if ln not in page]
    assert not missing, f"{len(missing)} table lines of docs/solid_contact.md differ from the CSV, e.g. {missing[:2]}"


def test_the_csv_covers_the_study():
    rows = read_csv(CSV)
    solid = {(float(r["psi_deg"]), float(r["h_m"])) for r in rows
             if r["model"] == SOLID and r["law"] == "sliding" and r["load_N"]}
    for psi in (0.0, 15.0, 45.0):
        assert len({h for p, h in solid if p == psi}) >= 2, f"psi {psi}: fewer than two solid meshes"
    errs = ancf_errors(rows)
    for psi in ("0", "15", "45"):
        els = {k[2] for k in errs if float(k[0]) == float(psi) and k[1] == "sliding"}
        assert {2, 4, 8, 16} <= els, f"psi {psi}: ANCF sliding columns missing ({sorted(els)})"
