"""A run's converged step at a load level it was asked for (summary.json ``steps``).

A level that lay in a gap of the load path is reported just past it (solving/step_over.py,
docs/running.md "Levels in a gap of the load path"): its step has the load factor it was solved
at and ``passed_over: {level, last_converged, reported_at}``.  Every table that matches solved
levels to asked ones takes such a step as the level reached, at its reported load factor, and
says so (``gap_note``)."""
from __future__ import annotations

import math

#: relative tolerance of a step's load factor on an asked level
LEVEL_RTOL = 1e-9


def same_level(a: float, b: float) -> bool:
    """Whether two load factors are one level (``LEVEL_RTOL``)."""
    return math.isclose(a, b, rel_tol=LEVEL_RTOL, abs_tol=1e-12)


def step_at(steps: list[dict], level: float) -> dict | None:
    """The converged step of ``level``: the one solved at it, else the one that reports it past
    a gap of the load path; None when the run did not reach it."""
    for st in steps:
        if same_level(st["load_factor"], level):
            return st
    for st in steps:
        asked = (st.get("passed_over") or {}).get("level")
        if asked is not None and same_level(asked, level):
            return st
    return None


def reported_at(step: dict | None) -> float | None:
    """The load factor a level passed over was reported at (None for a level solved at itself)."""
    if not step or not step.get("passed_over"):
        return None
    return float(step["load_factor"])


def gap_note(at: float | None, unit: str = " N") -> str:
    """'reported at 2500.5 N, past a gap of the load path' for a level reported at ``at`` (from
    ``reported_at``), '' for None."""
    return "" if at is None else f"reported at {at:g}{unit}, past a gap of the load path"


def not_asked(summary: dict, level: float) -> bool:
    """Whether a run with no step at ``level`` (``step_at``) was never asked for it rather than
    stopped before it: it completed (its steps are the levels its config asked), or went on past
    it."""
    steps = summary.get("steps") or []
    return summary.get("status") == "completed" or any(st["load_factor"] > level for st in steps)


def ended_words(summary: dict) -> str:
    """'the run ended failed' (its summary's status), or for a summary still 'running' 'the run has
    no final status: still running, or killed'."""
    status = summary.get("status")
    return ("the run has no final status: still running, or killed" if status == "running"
            else f"the run ended {status}")
