"""A model with a fibre-reinforced law starts each increment from the tangent load predictor
(config/parse.py ``default_predictor``): its path stiffens (the untwist of a soft-matrix set
saturates, the fibres' exponential law), and the secant of the last increment overshoots it
(docs/gait.md, "Fibre-reinforced (GOH) sets").  Measured over the GOH grid at twist 0/45/90°,
4 elements: 6899 → 5189 Newton iterations to 1.2 kN over the 54 columns.  A model with
frictionless contact (sliding, unilateral) starts from it too; one without contact or with a
tangential law (friction, elastic interfaces), from the secant."""
import pytest

from ancf_petsc.config.parse import parse_config
from ancf_petsc.workflows.envelope import GOH, EnvelopeCell, cell_config
from helpers import CONFIGS, load_raw, run_inline


@pytest.mark.parametrize("name,predictor", [("achilles_type3_psi45.yaml", "tangent"),      # sliding
                                            ("bundle_circle7.yaml", "tangent"),           # unilateral
                                            ("uniaxial_neohookean.yaml", "secant"),       # no contact
                                            ("friction_pressed_strips.yaml", "tangent"),  # friction
                                            ("achilles_type3_psi45_goh.yaml", "tangent"),
                                            ("achilles_type3_psi45_goh_alex.yaml", "tangent"),
                                            ("gait_stride_walking.yaml", "tangent")])
def test_default_predictor_by_material_and_history(name, predictor):
    assert parse_config(load_raw(name), CONFIGS).solver.predictor == predictor


def test_a_given_predictor_is_kept_for_a_fibre_model():
    raw = load_raw("achilles_type3_psi45_goh_alex.yaml")
    raw["solver"] = dict(raw.get("solver") or {}, predictor="secant")
    assert parse_config(raw, CONFIGS).solver.predictor == "secant"


def test_soft_matrix_goh_column_at_two_elements_within_its_newton_budget(tmp_path):
    """tendon_model (unilateral, matrix μ 15 kPa), twist 45°, uniform bias, 2 elements, to
    1.2 kN: 147 Newton iterations with the secant predictor, 114 with the tangent one; no
    cut-back either way."""
    base = next(g for g in GOH if g.endswith("_tendon_model.yaml"))
    cell = EnvelopeCell(base, 45.0, "uniform", elements=2,
                        levels=(30.0, 100.0, 200.0, 400.0, 600.0, 800.0, 1000.0, 1200.0))
    s = run_inline(cell_config(cell), tmp_path / cell.name, base_dir=CONFIGS)
    assert s["status"] == "completed"
    assert sum(st["cutbacks"] for st in s["steps"]) == 0
    assert s["newton_iterations"] <= 130


def test_tangent_predictor_solves_with_the_snes_factor_after_the_matrix_changed():
    """The tangent load predictor solves with the SNES's last factor even when the matrix was
    assembled again since (the complementarity predictor's held-phase Jacobian, when the solve
    after its step took no iteration): X − K⁻¹F with the factored K, not a factorisation of what
    the matrix holds now (which cost a factorisation in 40 of 98 unilateral stride frames)."""
    import numpy as np
    from helpers import build_problem
    from ancf_petsc.solving.predictor import TangentPredictor
    P, PETSc = build_problem(load_raw("achilles_type3_psi45.yaml"), "aij")
    X = P.q0.copy()
    P.load_factor = 1.0
    P.jacobian(None, X, P.J, P.J)
    K = P.J.duplicate(copy=True)
    solvers = []
    for A in (P.J, K):
        ksp = PETSc.KSP().create(comm=P.comm)
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
        ksp.setOperators(A)
        ksp.setUp()
        solvers.append(ksp)
    snes = PETSc.SNES().create(comm=P.comm)
    snes.setKSP(solvers[0])
    tangent = TangentPredictor(P, snes)
    tangent.valid = True
    P.J.scale(2.0)                       # assembled again: no longer the factored tangent
    expected, F, dX = X.copy(), X.duplicate(), X.duplicate()
    P.load_factor = 2.0
    P.impose(expected)
    P.contact.allow_update = False
    P.residual(None, expected, F)
    solvers[1].solve(F, dX)
    expected.axpy(-1.0, dX)
    got = X.copy()
    assert tangent.predict(got, 2.0)
    diff = (got - expected).norm() / (got - X).norm()
    assert diff < 1e-10, diff
    for obj in solvers + [snes, K]:
        obj.destroy()


def test_tangent_predictor_makes_no_prediction_once_the_contact_pattern_grew():
    """An assembly that grows the contact pattern (here the soleus moved 20 mm along its axis:
    its points project onto other elements) resets the SNES's SBAIJ preconditioner, also when
    the complementarity predictor assembled and the increment then converged with no Newton
    iteration: the next increment has no factor to predict with, so no prediction (it was a
    PETSc error and a traceback) and X stays at the converged state; a converged state's new
    factor predicts again."""
    from helpers import build_problem
    from ancf_petsc.solving.predictor import TangentPredictor
    P, PETSc = build_problem(load_raw("achilles_type3_psi45.yaml"), "sbaij")
    X = P.q0.copy()
    P.load_factor = 1.0
    snes = PETSc.SNES().create(comm=P.comm)
    ksp = snes.getKSP()
    ksp.setType("preonly")
    ksp.getPC().setType("cholesky")
    ksp.getPC().setFactorSolverType("mumps")
    P.jacobian(snes, X, P.J, P.J)
    ksp.setOperators(P.J)
    ksp.setUp()
    tangent = TangentPredictor(P, snes)
    tangent.valid = True
    assert tangent.predict(X.copy(), 2.0)            # with the factor
    moved = X.copy()
    soleus = P.layout.perm[:2 * P.model.beams[0].n_elements + 1]
    moved.getArray().reshape(-1, 18)[soleus, 0] += 0.02
    growths = P.pattern_growths
    P.jacobian(snes, moved, P.J, P.J)
    assert P.pattern_growths == growths + 1 and not tangent.valid
    got = X.copy()
    assert not tangent.predict(got, 2.0)
    assert (got - X).norm() == 0.0                   # no held DOF moves on this model
    tangent.valid = True                             # a sub-step accepted with no Newton iteration
    assert not tangent.predict(got, 2.0)             # (the stepper's accept): still no factor
    ksp.setOperators(P.J)                            # a later solve factors again
    ksp.setUp()
    tangent.valid = True
    assert tangent.predict(X.copy(), 2.0)
    snes.destroy()


@pytest.mark.parametrize("held", [True, False])
def test_the_complementarity_predictor_step_is_held_to_the_fibres_exponent_growth(tmp_path, monkeypatch, held):
    """solver_default_2025 (k2 = 524.6, unilateral), twist 0°, gastrocnemius-biased, 4 elements,
    the envelope's levels to 3 kN (the first increment is the whole first level, 30 N, only when
    the last level is far: contact/laws.py's share).  The complementarity predictor's
    Josephy–Newton step from rest is a whole linear step: it stretched the fibres to k2 Ē² ≈ 90
    and the first solve started at |F| ~ 1e38 N, from which Newton removes ~1 from the exponent
    per iteration (50 iterations, a saddle, a cut-back; 77 Newton iterations for the level).
    Held to the growth of k2 Ē² the Newton steps and load predictors are held to
    (step_limits.MAX_EXPONENT_GROWTH), the level takes 9, the column 49 instead of 117.
    Without the hold (``held`` False) the old start comes back."""
    from ancf_petsc.petsc import complementarity
    if not held:
        monkeypatch.setattr(complementarity, "MAX_EXPONENT_GROWTH", float("inf"))
    base = next(g for g in GOH if g.endswith("_solver_default.yaml"))
    cell = EnvelopeCell(base, 0.0, "gastrocnemius", elements=4)
    s = run_inline(cell_config(cell), tmp_path / cell.name, base_dir=CONFIGS)
    assert s["status"] == "completed"
    first = s["steps"][0]["newton_history"][0][0]          # |F| where the first solve starts
    if held:
        assert first < 1e4, first
        assert s["steps"][0]["cutbacks"] == 0
        assert s["steps"][0]["iterations"] <= 15, s["steps"][0]["iterations"]
    else:
        assert first > 1e20, first


@pytest.mark.mpi
@pytest.mark.slow
def test_the_held_complementarity_predictor_step_is_the_serial_one_on_2_and_3_ranks(tmp_path):
    """The same column to 100 N on 1, 2 and 3 ranks: the exponent growth is the largest over
    every rank's Gauss points, so every rank halves the predictor's step alike and the first
    solve starts from the serial |F| (not ~1e38 N), with the serial answer."""
    from helpers import assert_same_as_serial, probes_table, run_on_ranks
    base = next(g for g in GOH if g.endswith("_solver_default.yaml"))
    raw = cell_config(EnvelopeCell(base, 0.0, "gastrocnemius", elements=4))    # absolute section files
    raw["steps"] = [30.0, 100.0]
    runs = run_on_ranks(raw, tmp_path, ranks=(1, 2, 3))
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
    first = {n: s["steps"][0]["newton_history"][0][0] for n, (_, s) in runs.items()}
    assert first[1] < 1e4 and all(abs(f - first[1]) <= 1e-6 * first[1] for f in first.values()), first
