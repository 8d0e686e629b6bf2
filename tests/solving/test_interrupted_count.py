"""The Newton iterations of a run interrupted inside a solve are counted (summary.json)."""
from __future__ import annotations

import signal

from helpers import cantilever, run_inline


def test_an_interrupted_solve_counts_its_newton_iterations(tmp_path, monkeypatch):
    """A bar stopped mid-solve reported newton_iterations 0 after 1.57 s of solving (466
    residual evaluations): the stepper added a solve's iterations only when it returned, and
    RunInterrupted leaves from the SNES monitor.  The cantilever is stopped at the 3rd Newton
    iterate of its second level's first solve: its count is the first level's (as uninterrupted)
    and those 3."""
    from ancf_petsc.solving import snes_solver
    whole = run_inline(cantilever([0.5, 1.0], elements=2), tmp_path / "whole")
    first = whole["steps"][0]["iterations"]
    monitor, stop = snes_solver.SNESSolver._monitor, {"now": False}

    def watched(self, snes, its, fnorm):
        stop["now"] |= self.problem.load_factor > 0.5 and its == 3
        return monitor(self, snes, its, fnorm)
    monkeypatch.setattr(snes_solver.SNESSolver, "_monitor", watched)
    monkeypatch.setattr(snes_solver, "stop_requested", lambda comm: signal.SIGINT if stop["now"] else 0)
    cut = run_inline(cantilever([0.5, 1.0], elements=2), tmp_path / "cut")
    assert cut["status"] == "interrupted" and len(cut["steps"]) == 1
    assert cut["steps"][0]["iterations"] == first
    assert cut["newton_iterations"] == first + 3
