"""``contact.fade_forces: auto`` (solving/fade_switch.py): a level the variational fade forces
cannot reach is solved on with the pointwise ones.  A run made to fail with variational forces
past a load factor switches there, completes, and ends on the pointwise equilibrium of a run
with pointwise forces from the start (frictionless hyperelastic equilibria do not depend on the
path), not on the variational one; a restart of it goes on with pointwise forces and repeats
the uninterrupted run; which configs may switch.  2 and 3 ranks: tests/parallel/test_mpi.py."""
import copy

import numpy as np
import pytest

from contact.test_contact import achilles
from helpers import fail_solves, petsc_init, probes_table

STEPS = [100.0, 250.0, 400.0]


def column(forces: str = "auto", steps=STEPS) -> dict:
    """The paper's ψ = 45° tendon, 2 elements, sliding contact with differentiated fade weights
    (the default rule): partner places sit in the fade bands, and at 400 N the two forms' soleus
    elongations differ by 5.5e-4 of it."""
    raw = achilles(elements=2, contact={"mode": "sliding", "fade_forces": forces})
    raw["steps"] = list(steps)
    raw["output"] = {"vtk": False}
    return raw


def fail_variational_past(above: float, put=setattr) -> None:
    """Every SNES solve with variational fade forces at a load factor above ``above`` fails
    (DIVERGED_FNORM_NAN, as a projection lost): a level those forces cannot reach (``put``:
    a monkeypatch's setattr, or setattr in a driver process, tests/parallel/test_mpi.py)."""
    def variational_past(solver, lam):
        return solver.problem.contact.weights.variational and lam > above * (1.0 + 1e-12)
    fail_solves(variational_past, put)


def run(raw: dict, out, restart=None, log=None):
    """``raw`` solved in this process: its RunResult."""
    petsc_init()
    from ancf_petsc.api import solve
    from ancf_petsc.config.parse import parse_config
    from helpers import CONFIGS
    raw = copy.deepcopy(raw)
    raw["output"]["dir"] = str(out)
    return solve(parse_config(raw, base_dir=CONFIGS), log=log or (lambda *_: None), restart=restart)


@pytest.fixture(scope="module")
def references(tmp_path_factory):
    """The column with variational and with pointwise forces from the start: {forces: summary}."""
    out = {}
    for forces in ("variational", "pointwise"):
        res = run(column(forces), tmp_path_factory.mktemp(forces))
        assert res.status == "completed", res.message
        out[forces] = res.summary
    return out


def test_a_level_the_variational_forces_cannot_reach_is_solved_with_pointwise_ones(
        tmp_path, monkeypatch, references):
    fail_variational_past(STEPS[0], monkeypatch.setattr)
    from ancf_petsc.solving import snes_solver
    floors = []             # the rebuilt SNES keeps the floor: no residual at q0 mid-run
    monkeypatch.setattr(snes_solver, "rounding_floor", lambda P, f=snes_solver.rounding_floor: floors.append(1) or f(P))
    lines = []
    res = run(column(), tmp_path, log=lines.append)
    assert len(floors) == 1
    assert res.status == "completed", res.message
    s = res.summary
    assert s["fade_forces_pointwise_from"] == STEPS[0]
    assert not s["stability_checked"]                      # LU from the switch on: no inertia
    assert "PC lu (mumps, of the Jacobian's structural nonzeros) on AIJ" in s["solver"]
    assert s["steps"][0]["negative_eigenvalues"] == 0 and s["steps"][1]["negative_eigenvalues"] is None
    assert any("on with the pointwise ones" in line and f"load factor {STEPS[0]:g}" in line for line in lines)
    # the first level is the variational run's; the last one the pointwise run's equilibrium
    first = probes_table(s)[0]
    assert np.allclose(first, probes_table(references["variational"])[0], rtol=1e-12, atol=0.0)
    last, pointwise, variational = (probes_table(x)[-1] for x in (s, *(references[k] for k in
                                                                          ("pointwise", "variational"))))
    assert np.abs(last - pointwise).max() < 1e-8 * np.abs(pointwise).max()
    assert np.abs(variational - pointwise).max() > 1e-4 * np.abs(pointwise).max()   # the test can tell


def test_a_restart_after_the_switch_goes_on_with_pointwise_forces(tmp_path, monkeypatch):
    fail_variational_past(STEPS[0], monkeypatch.setattr)
    whole = run(column(), tmp_path / "whole")
    part = run(column(steps=STEPS[:2]), tmp_path / "part")
    monkeypatch.undo()                          # the restart needs no forced failure to stay pointwise
    assert part.summary["fade_forces_pointwise_from"] == STEPS[0]
    res = run(column(), tmp_path / "part", restart=str(tmp_path / "part"))
    assert res.status == "completed", res.message
    assert res.summary["fade_forces_pointwise_from"] == STEPS[0]
    # to the solver's tolerance (the shorter run's is 1e-10 of its own largest load)
    assert np.abs(probes_table(res.summary) - probes_table(whole.summary)).max() \
        < 1e-8 * np.abs(probes_table(whole.summary)).max()
    from ancf_petsc.errors import InputError
    with pytest.raises(InputError, match=r"went on with pointwise fade forces from load factor 100 "
                                         r"\(contact.fade_forces: auto\); restart with auto or pointwise"):
        run(column("variational"), tmp_path / "part", restart=str(tmp_path / "part"))
    # the refused run took its solver's options out of PETSc's database too: MUMPS's null-pivot
    # options stayed, and a later run of the process that set its own factored with them
    from petsc4py import PETSc
    assert not [k for k in PETSc.Options().getAll() if k.startswith("mat_mumps")]


def test_a_level_no_last_resort_reaches_names_its_first_give_up_too(tmp_path, monkeypatch):
    """The final message names the level's first give-up (the variational forces') after the
    failure of the resort that went on from it (the pointwise forces): on a strongly twisted
    unilateral column that ends far from equilibrium, and its cause hid the first one (a C0 edge
    of B's surface, docs/gait.md)."""
    def pointwise_past(solver, lam):
        return not solver.problem.contact.weights.variational and lam > 1.5 * STEPS[0]
    fail_solves(pointwise_past, monkeypatch.setattr)
    fail_variational_past(STEPS[0], monkeypatch.setattr)                # wraps the one above
    res = run(column(), tmp_path)
    assert res.status == "failed"
    assert res.summary["fade_forces_pointwise_from"] == STEPS[0]
    assert res.summary["steps"][-1]["load_factor"] == STEPS[0]
    # the pointwise forces stop at 150 (their own give-up leads), the variational ones at 100
    head, tail = res.message.split("; before going on with the pointwise fade forces, the level's "
                                   "first give-up was from load factor 100, at ")
    assert "SNES failed at load factor 150 (last converged 150)" in head
    assert tail.startswith("100.") and "with DIVERGED_FNORM_NAN" in tail


def test_the_first_give_up_is_named_for_its_own_level_only():
    from types import SimpleNamespace

    from ancf_petsc.solving.records import LoadStepFailure
    from ancf_petsc.solving.stepper import _first_give_up, _went_on
    stepper = SimpleNamespace(first_give_up=None)
    first = LoadStepFailure(600.0, 596.902, 596.901, "DIVERGED_MAX_IT", False, " (Newton cycles)")
    _went_on(stepper, 596.901, first, "the pointwise fade forces")
    _went_on(stepper, 597.5, LoadStepFailure(600.0, 597.6, 597.5, "X", False), "whole windows")
    later = LoadStepFailure(600.0, 598.0, 597.9, "DIVERGED_MAX_IT", False)
    assert _first_give_up(stepper, later) == (
        "; before going on with the pointwise fade forces, then whole windows, the level's first "
        "give-up was from load factor 596.901, at 596.902 with DIVERGED_MAX_IT (Newton cycles)")
    assert _first_give_up(stepper, LoadStepFailure(800.0, 601.0, 600.0, "X", False)) == ""
    _went_on(stepper, 700.0, LoadStepFailure(800.0, 701.0, 700.0, "Y", False), "whole windows")
    assert "from load factor 700, at 701 with Y" in _first_give_up(
        stepper, LoadStepFailure(800.0, 702.0, 701.5, "Z", False))


@pytest.mark.parametrize("change, switches", [
    ({}, True),
    ({"contact": {"fade_forces": "variational"}}, False),
    ({"contact": {"fade": "settle"}}, False),                 # the two forms are one
    ({"petsc": {"pc_type": "cholesky"}}, False),               # LDLᵀ asked for
    ({"solver": {"matrix": "sbaij"}}, False),
    ({"solver": {"linear": "fieldsplit"}}, False),
])
def test_which_runs_may_switch(change, switches):
    petsc_init()
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from ancf_petsc.model.contact_setup import contact_for
    from ancf_petsc.solving.fade_switch import switchable
    from helpers import CONFIGS
    raw = column()
    for key, value in change.items():
        raw.setdefault(key, {}).update(value)
    spec = parse_config(raw, base_dir=CONFIGS)
    model = build_model(spec)

    class Problem:
        contact = contact_for(model, spec.contact, lambda *_: None)
    Problem.model = model
    assert switchable(Problem, spec.solver.matrix, spec.petsc, "", spec.solver.linear
                      if spec.solver.linear != "auto" else "direct") is switches
