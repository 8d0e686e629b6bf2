"""The l2 line search with the whole step tried first (linalg/full_step_first.py), against PETSc's
own l2 on small nonlinear systems, and on a friction column."""
from __future__ import annotations

import numpy as np
import pytest
from petsc4py import PETSc

from helpers import CONFIGS, load_raw, read_summary, solve_cli, write_config

from ancf_petsc.linalg.full_step_first import FullStepFirst, secant_minimum


@pytest.mark.parametrize("a", [0.3, 0.7, 1.0, 1.3, 2.5])
def test_the_secant_step_is_the_minimum_of_a_parabola(a):
    """‖F(λ)‖² = (a − λ)² + c sampled at 0, λ/2, λ: l2's secant step lands on a exactly."""
    f = lambda lam: (a - lam) ** 2 + 0.1
    assert secant_minimum(f(0.0), f(0.5), f(1.0), 1.0) == pytest.approx(a, rel=1e-13)


def test_a_flat_line_is_a_breakdown():
    assert secant_minimum(1.0, 1.0, 1.0, 1.0) is None


class _System:
    """F(x) = arctan(x) + s x³ (componentwise), with a count of evaluations."""

    def __init__(self, s: float):
        self.s, self.calls = s, 0

    def residual(self, snes, X, F):
        self.calls += 1
        x = X.getArray(readonly=True)
        F.setArray(np.arctan(x) + self.s * x ** 3)

    def jacobian(self, snes, X, J, P):
        x = X.getArray(readonly=True)
        P.zeroEntries()
        P.setDiagonal(PETSc.Vec().createWithArray(1.0 / (1.0 + x ** 2) + 3 * self.s * x ** 2))
        P.assemble()


def _solve(x0, s: float, shell: bool, max_it: int = 50):
    system = _System(s)
    snes = PETSc.SNES().create(PETSc.COMM_SELF)
    n = len(x0)
    J = PETSc.Mat().createAIJ((n, n), nnz=1, comm=PETSc.COMM_SELF)
    F = PETSc.Vec().createSeq(n)
    snes.setFunction(system.residual, F)
    snes.setJacobian(system.jacobian, J, J)
    snes.setType("newtonls")
    snes.getKSP().setType("preonly")
    snes.getKSP().getPC().setType("lu")
    snes.setTolerances(rtol=1e-14, atol=1e-13, max_it=max_it)
    opts = PETSc.Options()
    opts["snes_linesearch_type"] = "l2"
    snes.setFromOptions()
    del opts["snes_linesearch_type"]
    search = FullStepFirst(snes) if shell else None
    X = PETSc.Vec().createWithArray(np.array(x0, dtype=float))
    snes.solve(None, X)
    out = X.getArray().copy(), snes.getConvergedReason(), system.calls, search
    snes.destroy()
    return out


def test_a_step_that_does_not_halve_the_residual_is_l2s():
    """From x = 1.6 Newton's whole step on arctan overshoots (|F| grows): the step taken is PETSc
    l2's to rounding (one iteration of each)."""
    x0 = [1.6, -1.7, 2.0]
    ours, _, _, search = _solve(x0, 0.0, True, max_it=1)
    theirs, _, _, _ = _solve(x0, 0.0, False, max_it=1)
    assert search.full_steps == 0 and search.steps == 1
    assert np.allclose(ours, theirs, rtol=1e-13, atol=1e-15)
    assert not np.allclose(ours, x0)


def test_the_same_root_in_fewer_residuals():
    """Converged to the same root as PETSc's l2, with about one residual per iteration where
    Newton contracts (l2: three)."""
    x0 = [0.4, -0.8, 1.2, 0.05]
    ours, reason, calls, search = _solve(x0, 0.2, True)
    theirs, reason_l2, calls_l2, _ = _solve(x0, 0.2, False)
    assert reason > 0 and reason_l2 > 0
    assert np.allclose(ours, theirs, atol=1e-12) and np.allclose(ours, 0.0, atol=1e-12)
    assert search.full_steps == search.steps > 0
    assert calls < calls_l2 / 2
    assert calls == 1 + search.evaluations


def test_a_friction_column_reaches_l2s_states_in_fewer_residuals(tmp_path):
    """ψ = 45°, Coulomb μ = 0.3, levels 1 … 100 N: with the whole step first
    (``solver.full_step_first``, the default) the probes are PETSc l2's within 1e-7 at every
    level, in at most 10 % more Newton iterations and a quarter fewer residuals; the header
    says which line search ran."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = f"{CONFIGS}/{b['section']['file']}"
    raw["steps"] = [1.0, 2.5, 5.0, 10.0, 25.0, 50.0, 100.0]
    raw["contact"] = {"mode": "sliding", "tangential": {"law": "coulomb", "friction": 0.3}}
    out = {}
    for first in (True, False):
        raw["solver"] = {"full_step_first": first}
        raw["output"] = {"dir": str(tmp_path / f"out_{first}"), "vtk": False}
        assert solve_cli(write_config(raw, tmp_path / f"c_{first}.yaml")).returncode == 0
        out[first] = read_summary(tmp_path / f"out_{first}")
    a, b = out[True], out[False]
    assert "line search l2 (the whole step first)" in a["solver"]
    assert "line search l2;" in b["solver"]
    assert a["newton_iterations"] <= 1.1 * b["newton_iterations"]
    assert a["residual_evaluations"] <= 0.75 * b["residual_evaluations"]
    assert len(a["steps"]) == len(b["steps"]) == 7
    for sa, sb in zip(a["steps"], b["steps"]):
        for name, pa in sa["probes"].items():
            d = np.asarray(pa["displacement"]) - np.asarray(sb["probes"][name]["displacement"])
            # 1.1e-8 at a level with friction's linear pressure (its default since 2026-12-07)
            assert np.abs(d).max() <= 1e-7 * np.abs(pa["displacement"]).max()
