"""Friction's bounds held (issue 27; solving/newton.py, "Friction's bounds"): where Coulomb's
semi-smooth iteration fails, the increment is solved again as a fixed point of Tresca problems
(the bounds μ ẑ held per solve) and then by Coulomb's own iteration from there.  Checked: where
the plain iteration converges the detour gives its answer; the paper's tendon with the roots'
tangential functions folded (equal loading, μ = 0.3, 2 elements), whose plain iteration fails
at 80 N (a folded root function on the stick–slip boundary), reaches every level without a
cut-back, the same on 1, 2 and 3 ranks."""
import os

import numpy as np
import pytest
from petsc4py import PETSc

from helpers import CONFIGS, assert_same_as_serial, load_raw, probes_table, run_inline, run_on_ranks
from ancf_petsc.contact.reports import PATH_NOTE, made_at_the_end, path_notes
from ancf_petsc.solving import newton


def _equal_loading(steps: list, elements: int = 2) -> dict:
    """The paper's tendon loaded by the three muscles equally, Coulomb μ = 0.3 on the sliding
    law with the roots' tangential functions folded, no cut-backs allowed."""
    raw = load_raw("achilles_psi45_equal_muscles.yaml")
    for b in raw["beams"]:
        b["elements"] = elements
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    # the quadratic pressure along the beam, friction's default until 2026-12-07: on the linear
    # one (now the default) the plain iteration solves 80 N and the fixed point from rest fails
    raw["contact"] = {"mode": "sliding", "projection": {"axial": 2},
                      "tangential": {"law": "coulomb", "friction": 0.3, "supported_ends": "merge"}}
    raw["steps"] = steps
    raw["solver"] = {"max_cutbacks": 0}
    return raw


def _discard_first_solve(monkeypatch, calls: list) -> None:
    """Every increment's first (converged) solve reported failed, so that the increment is
    solved through the fixed point (``calls``: the fixed points run)."""
    phases, fixed_point = newton.PhasedNewton._phases, newton.PhasedNewton._bounds_fixed_point

    def first_fails(self, X, lam, todo):
        reason, its = phases(self, X, lam, todo)
        if not getattr(self, "discarded", False):
            self.discarded = True
            return PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT, its
        return reason, its

    def counted(self, X, lam, todo):
        out = fixed_point(self, X, lam, todo)
        calls.append(self.bound_updates)
        return out
    monkeypatch.setattr(newton.PhasedNewton, "_phases", first_fails)
    monkeypatch.setattr(newton.PhasedNewton, "_bounds_fixed_point", counted)


def test_fixed_point_gives_the_plain_answer(tmp_path, monkeypatch):
    """Where the semi-smooth iteration converges (60 and 80 N from rest), every increment solved
    again through the Tresca fixed point instead gives the same state (Coulomb's law at the
    same tolerance; the incremental problem's solution is unique there)."""
    raw = _equal_loading([60.0, 80.0])
    plain = run_inline(raw, tmp_path / "plain")
    calls = []
    _discard_first_solve(monkeypatch, calls)
    detour = run_inline(raw, tmp_path / "detour")
    assert plain["status"] == detour["status"] == "completed"
    assert len(calls) == 2 and min(calls) >= 2, calls
    assert [st["tresca_solves"] for st in detour["steps"]] == calls
    assert [st["tresca_solves"] for st in plain["steps"]] == [0, 0]
    assert_same_as_serial({1: probes_table(plain), 2: probes_table(detour)}, rtol=1e-8)
    # the detour's increments were the solver's choice: the run says its answer follows the path
    (note,) = [w for w in detour["warnings"] if w.startswith(PATH_NOTE)]
    assert "2 level(s) (60, 80) were reached through cut-backs or Tresca solves" in note, note
    assert not [w for w in plain["warnings"] if w.startswith(PATH_NOTE)]


def test_the_path_note_is_frictions_and_made_again_on_a_restart():
    """``path_notes``: only a contact with friction's bounds gets it, only for levels reached
    through cut-backs or Tresca solves; a restart drops the stopped run's (``made_at_the_end``)."""
    from types import SimpleNamespace
    steps = [{"load_factor": 1.0, "cutbacks": 0, "tresca_solves": 0},
             {"load_factor": 2.5, "cutbacks": 2, "tresca_solves": 0}]
    coulomb, frictionless = (SimpleNamespace(terms=[SimpleNamespace(bounded=b)]) for b in (True, False))
    (note,) = path_notes(coulomb, steps)
    assert note.startswith(PATH_NOTE) and "1 level(s) (2.5)" in note and made_at_the_end(note)
    assert path_notes(frictionless, steps) == [] and path_notes(coulomb, steps[:1]) == []


@pytest.mark.mpi
@pytest.mark.slow
def test_fold_failure_is_solved_on_1_2_and_3_ranks(tmp_path):
    """45, 60, 80 N: the plain iteration fails at 80 N (it cycles, one folded root function
    between stick and slip); through the fixed point every level is
    reached without a cut-back, with the same probes on 1, 2 and 3 ranks."""
    raw = _equal_loading([45.0, 60.0, 80.0])
    raw["petsc"] = {"snes_max_it": "60"}        # the failing iteration cycles: stop it sooner
    # the secant predictor's path (friction's default until 2026-12-03) meets the fold at 80 N;
    # the tangent one's solves that level plainly
    raw.setdefault("solver", {})["predictor"] = "secant"
    runs = run_on_ranks(raw, tmp_path, ranks=(1, 2, 3))
    for _, s in runs.values():
        assert [st["cutbacks"] for st in s["steps"]] == [0, 0, 0]
        solves = [st["tresca_solves"] for st in s["steps"]]
        assert solves[:2] == [0, 0] and solves[2] >= 2, solves
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
