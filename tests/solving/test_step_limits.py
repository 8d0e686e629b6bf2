"""The Newton step limits of a strongly stiffening fibre law (petsc/step_limits.py): the growth of
k2 Ē² per Newton step and per load predictor is bounded (docs/fibres.md, "The published parameter
sets": the GOH set solver_default_2025, k2 = 524.6)."""
import os

import numpy as np
import pytest

from helpers import CONFIGS, build_problem, load_raw

#: solver_default_2025 (LUT-CoSmart/ANCF-Beam-based-Solver Materials.m, ed5e49d): c10, k1, k2
C10, K1, K2 = 7.64e3, 996.6e3, 524.6


def _lone_soleus():
    """The soleus of configs/achilles_type3_psi45_goh.yaml alone (no contact) with the set
    solver_default_2025 and K = 49.67 μ."""
    raw = load_raw("achilles_type3_psi45_goh.yaml")
    soleus = raw["beams"][0]
    soleus["section"]["file"] = os.path.join(CONFIGS, soleus["section"]["file"])
    soleus["material"].update(mu=2 * C10, bulk_modulus=49.67 * 2 * C10, k1=K1, k2=K2)
    raw["beams"], raw["boundary_conditions"], raw["probes"] = [soleus], raw["boundary_conditions"][:1], \
        raw["probes"][:1]
    raw.pop("contact")
    raw["steps"] = [10.0]
    return raw


def test_first_newton_step_of_a_strongly_stiffening_law_is_held_to_a_bounded_exponent_growth():
    """From rest at 10 N the full Newton step stretches fibres so far that e^(k2 Ē²) overflows
    (|F| = inf: measured Ē = 0.83 after the section-size limit); the pre-check halves it until
    no k2 Ē² grows by more than MAX_EXPONENT_GROWTH, and the residual there is finite."""
    from petsc4py import PETSc
    from ancf_petsc.petsc.step_limits import MAX_EXPONENT_GROWTH, fibre_exponents
    P, _ = build_problem(_lone_soleus(), matrix_type="aij")
    X = P.q0.copy()
    P.load_factor = 10.0
    F = X.duplicate()
    P.residual(None, X, F)
    P.jacobian(None, X, P.J, P.J)
    ksp = PETSc.KSP().create()
    ksp.setOperators(P.J)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    Y = X.duplicate()
    ksp.solve(F, Y)
    assert P.limits.fibres
    full = Y.copy()
    P.limits.sections = np.inf                  # the exponent alone (no section-size scaling)
    trial = X.copy()
    trial.axpy(-1.0, full)
    F1 = X.duplicate()
    with np.errstate(all="ignore"):             # the overflow is the point
        P.residual(None, trial, F1)
    assert not np.isfinite(F1.norm())           # the plain Newton step: overflow
    changed = P.limits.precheck(X, Y)
    assert changed and np.isfinite(Y.norm())
    X.axpy(-1.0, Y)
    growth = fibre_exponents(P, X).max() - fibre_exponents(P, P.q0).max()
    assert 0.0 < growth <= MAX_EXPONENT_GROWTH
    assert growth > MAX_EXPONENT_GROWTH / 8     # halved no further than needed (E² quarters per halving)
    P.residual(None, X, F1)
    assert np.isfinite(F1.norm())
    ksp.destroy()


def test_fibre_exponent_is_k2_times_the_clipped_fibre_strain_squared():
    """GOH.fibre_exponent against Ē from F directly: k2 Ē² in tension, 0 in compression."""
    from ancf_petsc.physics.goh import GOH
    a0 = np.array([[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])               # one family, two points
    law = GOH(1e4, 5e5, K1, K2, fibres={"follow": "axis", "extra_twist_deg": 0.0, "angles_deg": (0.0,)},
              directions=a0)
    F = np.array([np.diag([1.1, 0.95, 0.95]), np.diag([1.1, 0.95, 0.95])])
    E = np.array([1.1 ** 2 - 1.0, 0.0])                                 # along y: 0.95² − 1 < 0
    assert np.allclose(law.fibre_exponent(F), K2 * E * E, rtol=1e-14)


def test_the_exponent_limit_holds_under_locking_mixed(tmp_path):
    """``locking: mixed`` wraps the law (ProjectedDilatation), which had no fibre_exponent: the
    limit was off without a word (the lone soleus to 10 N: 75 Newton iterations, 3 cut-backs,
    against 47 and none with it; the same answer).  A neo-Hookean mixed beam has no fibre limit."""
    from ancf_petsc.petsc.step_limits import fibre_exponents
    raw = _lone_soleus()
    raw["beams"][0]["locking"] = "mixed"
    P, _ = build_problem(raw, matrix_type="aij")
    assert P.limits.fibres
    assert fibre_exponents(P, P.q0).shape[0] > 0
    raw["beams"][0]["material"] = {"model": "neo-hookean", "mu": 2 * C10, "bulk_modulus": 49.67 * 2 * C10}
    assert not build_problem(raw, matrix_type="aij")[0].limits.fibres


def test_a_fibre_law_with_k1_zero_solves_as_its_matrix(tmp_path):
    """k1: 0 (fibres off) on the lone soleus kept the fibres' step limits: 47 + 140 Newton
    iterations to 0.1, 0.2 N against the matrix's 10 + 26 (both with the tangent predictor, a
    fibre law's default).  Now the same run as the neo-Hookean matrix: iterations and answer."""
    from helpers import run_inline
    runs = []
    for material in ({"k1": 0.0}, {"model": "neo-hookean", "mu": 2 * C10, "bulk_modulus": 49.67 * 2 * C10}):
        raw = _lone_soleus()
        raw["beams"][0]["material"] = material if "model" in material else dict(raw["beams"][0]["material"], **material)
        raw["steps"], raw["output"], raw["solver"] = [0.1, 0.2], {"vtk": False}, {"predictor": "tangent"}
        runs.append(run_inline(raw, tmp_path / str(len(runs))))
    goh, nh = runs
    assert [s["iterations"] for s in goh["steps"]] == [s["iterations"] for s in nh["steps"]]
    assert goh["steps"][-1]["probes"] == nh["steps"][-1]["probes"]


@pytest.mark.mpi
def test_limited_steps_give_the_serial_answer_on_two_and_three_ranks(tmp_path):
    """The lone soleus with solver_default_2025 to 20 N: its first level is cut back and its
    Newton steps and predictors are held by the exponent limit, decided over every rank; 2 and 3
    ranks (2 + 2 and an uneven split of the 4 elements) take the same increments and iterations
    and reach the serial answer."""
    from helpers import assert_same_as_serial, probes_table, run_on_ranks
    raw = _lone_soleus()
    raw["steps"] = [10.0, 20.0]
    runs = run_on_ranks(raw, tmp_path, ranks=(1, 2, 3))
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
    steps = {n: [(st["cutbacks"], st["iterations"]) for st in s["steps"]] for n, (_, s) in runs.items()}
    assert steps[3] == steps[2] == steps[1] and steps[1][0][0] > 0


def test_lone_soleus_of_the_stiffest_published_set_reaches_400_newtons(tmp_path):
    """Table 1's 13 levels: every one converged on a stable state (no negative tangent
    eigenvalue), the fibres carrying the load (docs/fibres.md: before the exponent limit the run
    stopped at 99.5 N, where the continuous path from rest has a limit point; this path lands
    on a second stable branch in its first level).  The jump needs the whole first level as the
    first increment: the default bounds it by the linear response at rest (solving/
    rest_response.py: 10 N -> 0.08 N here), the path is then continuous and stops at the fold,
    99.501 N, with a message naming a limit or bifurcation point.  The jump is the secant
    predictor's (solving/predictor.py): with the tangent one, a fibre law's default since
    2026-11-28, the path is continuous too and stops at the fold."""
    from helpers import run_inline
    raw = _lone_soleus()
    raw["steps"] = [10, 20, 30, 40, 45, 60, 80, 90, 100, 150, 200, 300, 400]
    raw["solver"] = {"initial_increment": 10.0, "predictor": "secant"}
    raw["output"] = {"vtk": False}
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed" and [st["load_factor"] for st in s["steps"]] == raw["steps"]
    assert all(st["negative_eigenvalues"] == 0 for st in s["steps"])
    u = np.array([st["probes"]["soleus"]["displacement"][0] for st in s["steps"]])
    assert np.all(np.diff(u) > 0.0)                                  # stretches at every level
    area = s["sections"]["soleus"]["area"]
    assert u[-1] / raw["geometry"]["length"] < 400.0 / (area * 3.0 * 2 * C10)   # stiffer than the matrix


def test_band_ratio_on_its_grid():
    """The band limit's ratio is rounded up to 2^(k/16): never below the ratio (the step stays
    within the limit), at most one grid step above it, and the same for ratios 1e-10 apart (the
    ranks' rounding of one Newton step) unless a grid point falls between them."""
    from ancf_petsc.petsc.step_limits import BAND_GRID, quantised
    r = np.geomspace(1e-3, 1e3, 2001)
    q = np.array([quantised(x) for x in r])
    assert np.all(q >= r) and np.all(q <= r * 2.0 ** (1.0 / BAND_GRID) * (1 + 1e-15))
    assert np.allclose(np.log2(q) * BAND_GRID, np.round(np.log2(q) * BAND_GRID), atol=1e-9)
    same = [quantised(x) == quantised(x * (1 + 1e-10)) for x in r]
    assert sum(same) >= len(r) - 1
    assert quantised(0.0) == 0.0
