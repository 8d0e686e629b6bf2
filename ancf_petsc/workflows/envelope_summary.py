"""The gait envelope's rows (workflows/envelope.py) against its targets, in one line per solver:
monotonic columns to 1.2 kN within 60 Newton iterations and no cut-back at twist <= 90 deg;
strides at a median of at most 8 per frame, cut-backs on under 1 % of frames; and the cells that
did not complete counted by what stopped them (summary.json ``failure_cause``,
solving/failure_cause.py); and the cells a grid's CSV records as not completed, to run again."""
from __future__ import annotations

import csv
from collections import Counter

import numpy as np

from .envelope import CellResult, EnvelopeCell


def row_key(row: dict) -> tuple:
    """What identifies a cell in a row of a grid (``CellResult.row``, or its CSV's strings)."""
    return (row["base"], row["law"], float(row["friction"]), float(row["twist"]), row["bias"],
            int(row["elements"]), str(row["stride"]) == "True")


def cell_key(cell: EnvelopeCell) -> tuple:
    """The ``row_key`` of ``cell``'s rows."""
    return row_key(CellResult(cell, "").row())


def not_completed(path: str) -> set[tuple]:
    """The ``row_key`` of every row of the CSV at ``path`` (bench_envelope.py --csv) whose cell
    did not complete."""
    with open(path, newline="") as fh:
        return {row_key(r) for r in csv.DictReader(fh)
                if r["status"] != "completed" and r.get("solver", "after") == "after"}


def failure_causes(rows: list[dict]) -> Counter:
    """The rows that did not complete, counted by cause (their status where they wrote none: a
    crash, a timeout, an interrupted or unstable run, or a row of an older CSV)."""
    return Counter((r.get("cause") or r["status"]) for r in rows if r["status"] != "completed")


def summary_line(rows: list[dict], tag: str) -> str:
    """The rows of one solver against the envelope's targets, in one line."""
    mine = [r for r in rows if r["solver"] == tag]
    bad = failure_causes(mine)
    columns = [r for r in mine if not r["stride"]]
    strides = [r for r in mine if r["stride"]]
    line = f"[{tag}] {len(mine)} cells: {sum(bad.values())} not completed"
    if bad:
        line += " (" + ", ".join(f"{cause} {n}" for cause, n in bad.most_common()) + ")"
    if columns:
        over = [r for r in columns if r["twist"] <= 90 and (r["iterations_to_1200"] > 60 or r["cutbacks_to_1200"])]
        line += f"; {len(over)} columns at twist <= 90 over 60 Newton iterations or with a cut-back to 1.2 kN"
    if strides:
        frames = sum(r["levels"] for r in strides)
        cut = sum(r["cutback_levels"] for r in strides)
        solve = sum(r["solve_time"] for r in strides)
        line += (f"; strides: {frames} frames, median of the strides' medians "
                 f"{np.median([r['median_iterations'] for r in strides]):g} Newton iterations per frame, "
                 f"cut-backs on {cut} frames ({100.0 * cut / max(frames, 1):.2f} %), "
                 f"{frames / max(solve, 1e-9):.1f} frames/s (solve)")
    return line
