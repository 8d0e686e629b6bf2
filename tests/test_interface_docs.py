"""docs/interface.md states numbers that come from CSV files written by scripts/interface_study.py:
every row of its tables must say what its CSV says (issue 39: the page's Newton counts and
elongations had drifted from what was measured).  Per run (loading, law, elements): the status,
the Newton iterations, cut-backs and Tresca solves summed over the levels, the soleus's
elongation and soleus − medial gastrocnemius at 400 N."""
import csv
import os
import re

import pytest

from helpers import ROOT

DOCS = os.path.join(ROOT, "docs")
PAGE = os.path.join(DOCS, "interface.md")


def law_key(text: str) -> str:
    """A law's label in a table or a CSV, canonical: "sliding", "unilateral, coulomb mu=0.3", ..."""
    t = text.lower().replace("μ", "mu").replace("(the paper)", "").replace("pa/m", "")
    t = re.sub(r"\s*=\s*", "=", t).strip()
    parts = []
    for piece in [p.strip() for p in t.split(",")]:
        m = re.match(r"(elastic|bonded \()\s*k_t=([0-9.e+]+)\)?", piece)
        c = re.match(r"coulomb mu=([0-9.]+)", piece)
        if m:
            parts.append(f"{'bonded' if m.group(1).startswith('bonded') else 'elastic'} k_t={float(m.group(2)):.0e}")
        elif c:
            parts.append(f"coulomb mu={float(c.group(1)):g}")
        else:
            parts.append(piece)
    return ", ".join(parts)


def csv_runs(name: str, pair: str) -> dict:
    """(loading, law, elements) → the run's sums and its values at 400 N from docs/<name>;
    ``pair`` is the CSV column of u_soleus − u_medial at the end (``-col`` when stored negated)."""
    runs = {}
    with open(os.path.join(DOCS, name)) as fh:
        for row in csv.DictReader(fh):
            key = (row["loading"], law_key(row["law"]), int(row["elements"]))
            r = runs.setdefault(key, {"status": row["status"], "newton": 0, "cutbacks": 0, "tresca": 0,
                                      "soleus": None, "difference": None})
            r["newton"] += int(row["newton"])
            r["cutbacks"] += int(row["cutbacks"])
            r["tresca"] += int(float(row.get("tresca_solves") or 0))
            if float(row["load_N"]) == 400.0:
                sign = -1.0 if pair.startswith("-") else 1.0
                r["soleus"] = float(row["soleus_mm"])
                r["difference"] = sign * float(row[pair.lstrip("-")])
    return runs


def table(after: str, first_column: str) -> list[dict]:
    """The rows of the first markdown table after the line starting with ``after`` whose header
    starts with ``first_column``, as dicts by header."""
    lines = open(PAGE).read().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(after))
    head = next(i for i in range(start, len(lines)) if lines[i].startswith(f"| {first_column} |"))
    names = [c.strip() for c in lines[head].strip("|").split("|")]
    rows = []
    for line in lines[head + 2:]:
        if not line.startswith("|"):
            break
        rows.append(dict(zip(names, [c.strip().strip("*") for c in line.strip("|").split("|")])))
    return rows


def number(cell: str) -> float | None:
    return float(cell) if re.fullmatch(r"-?[0-9.]+", cell or "") else None


def check(rows: list[dict], runs: dict, columns: dict) -> int:
    """Every row against its run; ``columns`` maps the run's fields to the table's headers."""
    seen = 0
    for row in rows:
        loading = row.get("loading", "soleus")
        if "normal law" in row:                               # the merge table: law and mu apart
            law = law_key(f"coulomb mu={row['μ']}" if row["normal law"] == "sliding"
                          else f"unilateral, coulomb mu={row['μ']}")
        else:
            law = law_key(row["law"])
        key = (loading, law, int(row["el."]))
        if key not in runs:                                   # no level reached: no CSV row
            assert number(row.get("Newton")) in (0.0, None) and "400 N" not in str(row.get("status", "")), key
            seen += 1
            continue
        run = runs[key]
        for field, header in columns.items():
            cell = row[header]
            if field == "status":
                assert cell.startswith(run["status"]) or (run["status"] != "completed" and "400 N" not in cell), (key, cell)
                continue
            value = number(cell)
            if value is None:                                  # a run that did not reach 400 N
                assert run[field] is None or run["status"] != "completed", (key, field, cell)
                continue
            digits = len(cell.split(".")[1]) if "." in cell else 0
            assert abs(run[field] - value) <= 0.6 * 10.0 ** -digits, (key, field, run[field], cell)
        seen += 1
    return seen


def side(rows: list[dict], k: int, columns: dict) -> list[dict]:
    """The rows of a "before → after" table as one side reads them (k = 0 before, 1 after): a
    cell with one value holds for both; thousands written "1 137" read as 1137."""
    return [{h: (row[h].split(" → ")[k] if " → " in row[h] else row[h]).replace(" ", "")
             if h in columns.values() else row[h] for h in row} for row in rows]


def test_the_study_table_is_its_csv():
    rows = table("## The paper's tendon between sliding and bonded", "loading")
    runs = csv_runs("interface_study.csv", "end_soleus|medial_gastrocnemius_mm")
    n = check(rows, runs, {"status": "status", "newton": "Newton", "cutbacks": "cut-backs",
                           "tresca": "Tresca solves", "soleus": "soleus at 400 N [mm]",
                           "difference": "soleus − MG at 400 N [mm]"})
    assert n == len(runs) == 60


@pytest.mark.parametrize("after, first, name, columns", [
    ("### The study of 2026-11-26", "loading", "interface_study_2026-11-26.csv",
     {"newton": "Newton", "cutbacks": "cut-backs", "soleus": "soleus at 400 N [mm]",
      "difference": "soleus − MG at 400 N [mm]"}),
    ("### Friction's mesh convergence", "law", "interface_friction_mesh.csv",
     {"newton": "Newton", "cutbacks": "cut-backs", "soleus": "soleus at 400 N [mm]",
      "difference": "soleus − MG at 400 N [mm]"}),
    ("### The fold and the fixed point against keep", "loading", "interface_friction_merge.csv",
     {"newton": "Newton", "cutbacks": "cut-backs", "soleus": "soleus at 400 N [mm]"}),
])
def test_the_dated_tables_are_their_csvs(after, first, name, columns):
    """The appendix's tables of 2026-11-26 against the CSVs of that day (their differences column
    holds u_medial − u_soleus: the keys before issue 39)."""
    rows = table(after, first)
    assert check(rows, csv_runs(name, "-end_medial_gastrocnemius|soleus_mm"), columns) == len(rows) > 0


def test_the_augmentation_table_is_its_two_csvs():
    """"The augmentation's default": each cell "c = 1 → G/E" (one value: both the same) is the
    main study's CSV on the left and docs/interface_study_augmentation.csv on the right."""
    rows = table("### The augmentation's default", "loading")
    columns = {"newton": "Newton", "cutbacks": "cut-backs", "tresca": "Tresca solves", "soleus": "soleus at 400 N [mm]"}
    sides = [csv_runs(name, "end_soleus|medial_gastrocnemius_mm")
             for name in ("interface_study.csv", "interface_study_augmentation.csv")]
    for k, runs in enumerate(sides):
        assert check(side(rows, k, columns), runs, columns) == len(rows) == 20


def test_the_predictor_table_is_its_two_csvs():
    """"The load predictor's default": each cell "secant → tangent" is
    docs/interface_study_predictor_secant.csv on the left, ``…_tangent.csv`` on the right, and the
    page's totals (Newton iterations over the 52 columns) are theirs."""
    rows = table("### The load predictor's default", "loading")
    columns = {"newton": "Newton (secant → tangent)", "cutbacks": "cut-backs", "tresca": "Tresca solves",
               "soleus": "soleus at 400 N [mm]"}
    sides = [csv_runs(f"interface_study_predictor_{name}.csv", "end_soleus|medial_gastrocnemius_mm")
             for name in ("secant", "tangent")]
    for k, runs in enumerate(sides):
        assert check(side(rows, k, columns), runs, columns) == len(rows) == 4
    totals = [sum(r["newton"] for r in runs.values()) for runs in sides]
    assert all(len(runs) == 52 and all(r["status"] == "completed" for r in runs.values()) for runs in sides)
    assert f"{totals[0]:,} → {totals[1]:,} Newton iterations".replace(",", " ") in open(PAGE).read()
