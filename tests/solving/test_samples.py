"""Many solves of one model in one process (solving/samples.py, issue 28): material parameters
changed in place give a fresh build's answers; warm starts change the cost, not the answer
(beyond the solver's tolerance); a warm start that does not converge falls back to load
stepping; other changes rebuild the run.  Table 1's psi = 0 column (sliding contact)."""
from __future__ import annotations

import copy
import os

import numpy as np
import pytest

from helpers import CONFIGS, petsc_init

petsc_init()

from ancf_petsc import yamlio  # noqa: E402
from ancf_petsc.config import parse_config  # noqa: E402
from ancf_petsc.solving.run import run_model, serial_comm  # noqa: E402
from ancf_petsc.solving.samples import SampleSolver, changed_paths  # noqa: E402

RAW = yamlio.load(open(os.path.join(CONFIGS, "achilles_type3_psi0.yaml")).read())
#: the secant load predictor, whose cold path docs/calibration.md's costs were measured on: with
#: the tangent one (frictionless contact's default, 2026-12-02) the cold column takes 37 Newton
#: iterations against 39 for the warm start from NEAR (2 % away)
RAW["solver"] = dict(RAW.get("solver") or {}, predictor="secant")


def spec_of(scale=(1.0, 1.0, 1.0), **top):
    raw = copy.deepcopy(RAW)
    for b, s in zip(raw["beams"], scale):
        b["material"]["mu"] = float(b["material"]["mu"]) * s
    raw.update(top)
    return parse_config(raw, base_dir=CONFIGS)


NEAR = (1.02, 0.99, 1.01)


@pytest.fixture(scope="module")
def solved():
    """One solver: the paper's moduli cold, then x (1.1, 0.9, 1.05) in place cold, then the
    moduli x NEAR cold and warm-started from the first column's states."""
    solver = SampleSolver()
    base = solver.solve(spec_of())
    cold = solver.solve(spec_of((1.1, 0.9, 1.05)))
    near_cold = solver.solve(spec_of(NEAR))
    warm = solver.solve(spec_of(NEAR), start=base.states)
    yield solver, base, cold, (near_cold, warm)
    solver.destroy()


def test_a_material_change_in_place_gives_a_fresh_builds_answer(solved, tmp_path):
    solver, base, cold, _ = solved
    assert solver.builds == 1 and not cold.rebuilt and base.rebuilt
    fresh = SampleSolver()
    ref = fresh.solve(spec_of((1.1, 0.9, 1.05)))
    fresh.destroy()
    for name in ref.displacements:
        assert np.abs(cold.displacements[name] - ref.displacements[name]).max() < 1e-13
    assert cold.newton_iterations == ref.newton_iterations
    spec = spec_of((1.1, 0.9, 1.05))
    spec.output.dir = str(tmp_path / "run")
    spec.output.vtk = False
    res = run_model(spec, serial_comm(), log=lambda *_: None)          # ancf-solve's path
    last = res.summary["steps"][-1]["probes"]["soleus"]["displacement"]
    assert np.abs(np.array(last) - cold.displacements["soleus"][-1]).max() < 1e-13


def test_warm_starts_change_the_cost_not_the_answer(solved):
    _, base, _, (cold, warm) = solved
    assert warm.status == "completed" and warm.warm_levels == 13 and warm.fallbacks == 0
    assert warm.newton_iterations < cold.newton_iterations
    # the tolerance |F| <= 4e-8 N over a stiffness of ~6e4 N/m: ~1e-12 m; allow 1e-10 m
    for name in cold.displacements:
        assert np.abs(warm.displacements[name] - cold.displacements[name]).max() < 1e-10
    assert np.abs(cold.displacements["soleus"] - base.displacements["soleus"]).max() > 5e-5


def test_a_warm_start_that_fails_falls_back_to_load_stepping(solved):
    solver, base, _, (cold, _) = solved
    bad = copy.deepcopy(base.states)
    for s in bad[6:]:
        s.x[:27, 0, 0] += 5e-3                  # every node moved 5 mm along the tendon
    out = solver.solve(spec_of(NEAR), start=bad)
    assert out.status == "completed" and out.fallbacks >= 1 and out.warm_levels >= 6
    for name in cold.displacements:
        assert np.abs(out.displacements[name] - cold.displacements[name]).max() < 1e-10


def test_other_changes_rebuild_the_run():
    solver = SampleSolver()
    try:
        a = solver.solve(spec_of(steps=[10, 20]))
        b = solver.solve(spec_of(steps=[10, 20], geometry=dict(RAW["geometry"], twist_deg=15)))
        assert a.rebuilt and b.rebuilt and solver.builds == 2
        assert a.load_factors == [10.0, 20.0] and a.displacements["soleus"].shape == (2, 3)
    finally:
        solver.destroy()


def test_changed_paths_of_config_trees():
    a = {"beams": [{"material": {"mu": 1.0}}, {"material": {"mu": 2.0}}], "steps": [1, 2]}
    b = copy.deepcopy(a)
    b["beams"][1]["material"]["mu"] = 3.0
    b["new"] = 1
    assert changed_paths(a, b) == [("beams", 1, "material", "mu"), ("new",)]
    b["steps"] = [1]
    assert ("steps",) in changed_paths(a, b)


def test_fibres_switched_on_in_place_get_the_fibre_step_limits():
    """A GOH bar built with k1 = 0 (fibres off: no fibre step limits) and sampled with k1 > 0
    in place: the run's limits see the fibres again, as a fresh build's (same answer and
    Newton iterations)."""
    raw = yamlio.load(open(os.path.join(CONFIGS, "uniaxial_neohookean.yaml")).read())
    raw["beams"][0]["material"] = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 5.0e7, "k1": 0.0, "k2": 5.0,
                                   "fibres": {"follow": "axis"}}
    raw["steps"] = [0.5, 1.0]
    on = copy.deepcopy(raw)
    on["beams"][0]["material"]["k1"] = 2.0e6
    solver, fresh = SampleSolver(), SampleSolver()
    try:
        solver.solve(parse_config(raw, base_dir=CONFIGS))
        assert not solver.run.problem.limits.fibres
        out = solver.solve(parse_config(on, base_dir=CONFIGS))
        assert solver.builds == 1 and solver.run.problem.limits.fibres
        ref = fresh.solve(parse_config(copy.deepcopy(on), base_dir=CONFIGS))
        assert fresh.run.problem.limits.fibres
        assert np.abs(out.displacements["tip"] - ref.displacements["tip"]).max() < 1e-13
        assert out.newton_iterations == ref.newton_iterations
    finally:
        solver.destroy()
        fresh.destroy()


def _strips(mu: float):
    """configs/friction_pressed_strips.yaml (Coulomb friction, out and back) at five levels,
    the slider's shear modulus ``mu``, its free end probed."""
    raw = yamlio.load(open(os.path.join(CONFIGS, "friction_pressed_strips.yaml")).read())
    raw["steps"] = [1.5, 2.0, 2.5, 3.0, 3.5]
    raw["beams"][1]["material"]["mu"] = mu
    raw["probes"].append({"name": "tail", "beam": "slider", "node": "first"})
    return parse_config(raw, base_dir=CONFIGS)


def test_friction_samples_start_from_the_reference_history_and_step_cold():
    """A Coulomb friction model in a calibration: every sample stopped with a TypeError (the
    reference contact state carried no friction history: restore_state(..., None)). A sample
    now starts from the reference history, whatever was solved before it, and is solved by load
    stepping even when offered a neighbour's states: warm from them its values moved by up to
    2.3e-3 (the friction answer follows its path), beyond the solver's tolerance."""
    one = SampleSolver()
    try:
        first = one.solve(_strips(0.5e6))
        offered = one.solve(_strips(0.55e6), start=first.states)
    finally:
        one.destroy()
    fresh = SampleSolver()
    try:
        cold = fresh.solve(_strips(0.55e6))
    finally:
        fresh.destroy()
    assert first.status == offered.status == cold.status == "completed"
    assert offered.warm_levels == 0
    u, ref = offered.displacements["tail"], cold.displacements["tail"]
    assert np.abs(u - ref).max() <= 1e-10 * np.abs(ref).max()


@pytest.mark.slow
def test_a_warm_sample_passes_over_a_gap_as_a_cold_one():
    """The second subject's sliding 180° gastrocnemius-biased column (a gap of the load path from
    ~1599.3 N; tests/solving/test_step_over.py): cold, its levels 1600 and 1600.3 N are both
    reported at 1640 N. A neighbour (moduli +1e-5) warm from those states solved the second
    level directly from the state past the gap and reported it there, on the far side's branch,
    not passed over (found on the 30° soleus-biased column, whose gap was at 2500 N before the
    outlines were started at their farthest vertex). Now a level the last one's step over passed
    is reported with it, as cold."""
    from ancf_petsc.workflows.envelope import SUBJECT2, EnvelopeCell, cell_config
    raw = cell_config(EnvelopeCell(SUBJECT2, 180.0, "gastrocnemius", "sliding", levels=(1000.0, 1200.0, 1600.0, 1600.3)))
    raw["output"] = {"vtk": False}
    raw["solver"] = dict(raw.get("solver") or {}, min_increment=0.05)

    def scaled(s):
        r = copy.deepcopy(raw)
        for b in r["beams"]:
            b["material"]["mu"] = float(b["material"]["mu"]) * s
        return parse_config(r, base_dir=CONFIGS)
    one, fresh = SampleSolver(), SampleSolver()
    try:
        first = one.solve(scaled(1.0))
        warm = one.solve(scaled(1.00001), start=first.states)
        cold = fresh.solve(scaled(1.00001))
    finally:
        one.destroy()
        fresh.destroy()
    assert [p[0] for p in cold.passed_over] == [1600.0, 1600.3] and warm.warm_levels > 0
    assert warm.load_factors == cold.load_factors and warm.passed_over == cold.passed_over
    for name, u in cold.displacements.items():
        assert np.abs(warm.displacements[name] - u).max() <= 1e-9 * np.abs(u).max(), name
