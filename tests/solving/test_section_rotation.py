"""Newton steps that turn the sections (petsc/section_rotation.py, ``solver.section_update``):
the split of a step into a turn and the rest, exact for a rigid turn and second order beside the
plain step; on the paper's tendon the same answers in fewer Newton iterations."""
import os

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from helpers import CONFIGS, build_problem, load_raw, run_inline

from ancf_petsc.petsc.section_rotation import ROTATION_MAX, director_rotation, second_order_part


def _directors(n, seed=0):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, 2, 3)), rng.normal(size=(n, 3))


def test_the_rotation_of_a_linearised_turn_is_recovered():
    """Steps b_k = ω × a_k (a turn to first order) give back ω, to rounding."""
    a, w = _directors(50)
    w *= 0.01
    b = np.cross(w[:, None, :], a)
    assert np.allclose(director_rotation(a, b), w, rtol=0, atol=1e-15)


def test_the_turned_update_is_the_exact_rotation_and_a_second_order_change():
    """a + ω × a + (second-order part) is R(ω) a, lengths kept; the part shrinks as |ω|²."""
    a, w = _directors(20, seed=1)
    w *= 0.02
    turned = a + np.cross(w[:, None, :], a) + second_order_part(w, a)
    exact = np.einsum("nij,nkj->nki", Rotation.from_rotvec(w).as_matrix(), a)
    assert np.allclose(turned, exact, rtol=0, atol=1e-15)
    assert np.allclose(np.linalg.norm(turned, axis=2), np.linalg.norm(a, axis=2), rtol=1e-14)
    ratio = np.abs(second_order_part(w, a)).max() / np.abs(second_order_part(0.5 * w, a)).max()
    assert ratio == pytest.approx(4.0, rel=0.02)


def _column():
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["output"] = {"vtk": False}
    return raw


def _column_at_rest():
    """The paper's column at rest: its problem, vectors per node, state X, X's nodal vectors
    and the nodes whose directors are free."""
    P, _ = build_problem(_column())
    V = P.model.block.vectors_per_node
    X = P.q0.copy()
    x = X.getArray(readonly=True).reshape(-1, V, 3)
    held = P.fixed_mask.reshape(-1, V, 3)[:, 1:3].any(axis=(1, 2))
    return P, V, X, x, np.flatnonzero(P.owned_physical & ~held)


def test_a_step_is_turned_at_the_free_nodes_only_and_not_when_it_turns_too_far():
    """A step that is each free node's linearised turn by ω lands on the turned sections; nodes
    with a held director component keep the plain step; with |ω| above ROTATION_MAX nothing
    changes."""
    from ancf_petsc.petsc.section_rotation import SectionTurns
    P, V, X, x, free = _column_at_rest()
    assert 0 < len(free) < int(P.owned_physical.sum())        # the roots have held DOFs
    for size, turned in ((0.5 * ROTATION_MAX, True), (2.0 * ROTATION_MAX, False)):
        w = np.zeros((x.shape[0], 3))
        w[free] = size * np.array([0.6, 0.0, 0.8])
        step = np.zeros_like(x)
        step[:, 1:] = np.cross(w[:, None, :], x[:, 1:])         # the update is X − Y
        Y = X.duplicate()
        Y.setArray(-step.ravel())
        assert SectionTurns(P)(X, Y) is turned
        new = (X.getArray(readonly=True) - Y.getArray(readonly=True)).reshape(-1, V, 3)
        R = Rotation.from_rotvec(w[free]).as_matrix()
        if turned:
            assert np.allclose(new[free, 1:], np.einsum("nij,nkj->nki", R, x[free, 1:]), rtol=0, atol=1e-15)
        else:
            assert np.array_equal(new, x + step)
        plain = np.setdiff1d(np.arange(x.shape[0]), free)
        assert np.array_equal(new[plain], (x + step)[plain])


def test_the_paper_column_takes_fewer_newton_iterations_to_the_same_answer(tmp_path):
    """The ψ = 45° column to 400 N: the turned steps reach the plain steps' answers in fewer
    iterations (measured 44 against 47; 39 against 40 with the tangent predictor, 2026-12-04).
    Both stop within the Newton tolerance (|F| up to 1.6e-8 N against 4e-8), so the probes
    agree to its order: 1.5e-8 of the largest displacement."""
    runs = {}
    for update in ("linear", "rotation"):
        raw = _column()
        raw.setdefault("solver", {})["section_update"] = update
        runs[update] = run_inline(raw, tmp_path / update)
    plain, turned = runs["linear"], runs["rotation"]
    assert plain["status"] == turned["status"] == "completed"
    assert turned["newton_iterations"] < plain["newton_iterations"]
    for a, b in zip(plain["steps"], turned["steps"]):
        for name, probe in a["probes"].items():
            u, v = np.asarray(probe["displacement"]), np.asarray(b["probes"][name]["displacement"])
            assert np.abs(u - v).max() <= 1e-7 * np.abs(u).max(), name


@pytest.mark.mpi
def test_turned_steps_give_the_serial_answer_on_two_and_three_ranks(tmp_path):
    """Each rank turns its own nodes from their own values, and whether a step turns is decided
    over every rank: 2 and 3 ranks take the serial Newton iterations to the serial answer."""
    from helpers import assert_same_as_serial, probes_table, run_on_ranks
    raw = _column()
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["steps"] = [100.0, 400.0]
    raw.setdefault("solver", {})["section_update"] = "rotation"
    runs = run_on_ranks(raw, tmp_path, ranks=(1, 2, 3))
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
    its = {n: [st["iterations"] for st in s["steps"]] for n, (_, s) in runs.items()}
    assert its[1] == its[2] == its[3], its


def test_held_quadratic_vectors_of_3333_stay_zero_while_the_directors_turn(tmp_path, monkeypatch):
    """Element 3333 holds the quadratic section vectors at 0: the turned steps keep them there
    and reach the plain steps' answers (to the Newton tolerance's order)."""
    import h5py
    from ancf_petsc.petsc import section_rotation
    turned, call = [], section_rotation.SectionTurns.__call__
    monkeypatch.setattr(section_rotation.SectionTurns, "__call__",
                        lambda self, X, Y: turned.append(call(self, X, Y)) or turned[-1])
    runs = {}
    for update in ("linear", "rotation"):
        raw = _column()
        for b in raw["beams"]:
            b["element"] = 3333
        raw["steps"] = [100.0, 400.0]
        raw.setdefault("solver", {})["section_update"] = update
        runs[update] = run_inline(raw, tmp_path / update)
        assert runs[update]["status"] == "completed"
    assert sum(turned) >= 3                            # steps were turned
    a, b = runs["linear"]["steps"][-1]["probes"], runs["rotation"]["steps"][-1]["probes"]
    for name in a:
        u, v = np.asarray(a[name]["displacement"]), np.asarray(b[name]["displacement"])
        assert np.abs(u - v).max() <= 1e-7 * np.abs(u).max(), name
    with h5py.File(tmp_path / "rotation" / "results.h5", "r") as fh:
        q = fh["steps"][sorted(fh["steps"])[-1]]["nodal_vectors"][()]   # (nodes, vectors, 3)
    assert np.abs(q[:, 1:3]).max() > 0.5 and np.all(q[:, 3:] == 0.0)   # r, r_y, r_z, then quadratic


def test_steps_are_turned_only_where_the_line_search_takes_them_whole(tmp_path):
    """The turn adds the second-order part of the whole step's rotation, which a line search's
    shortened step would scale wrongly: with -snes_linesearch_type l2 no step is turned (the
    run is the plain update's, iteration for iteration) and the run's header says why."""
    from ancf_petsc.petsc.step_limits import StepLimits
    P, _ = build_problem(_column())
    limits = StepLimits(P)
    assert limits.configure(0.0, "rotation", "basic") and limits.turns is not None
    assert not limits.configure(0.0, "rotation", "l2") and limits.turns is None
    runs = {}
    for update in ("linear", "rotation"):
        raw = _column()
        raw["steps"] = [100.0, 400.0]
        raw.setdefault("solver", {})["section_update"] = update
        runs[update] = run_inline(raw, tmp_path / update, petsc={"snes_linesearch_type": "l2"})
    assert runs["linear"]["newton_iterations"] == runs["rotation"]["newton_iterations"]
    assert runs["linear"]["steps"][-1]["probes"] == runs["rotation"]["steps"][-1]["probes"]
    assert "not turned (solver.section_update: rotation needs full steps, line search l2)" in \
        runs["rotation"]["solver"]


def test_a_snes_type_without_a_line_search_says_its_steps_are_not_turned(tmp_path):
    """-snes_type newtontr takes no line search, so no pre-check: its header said "line search
    basic; Newton steps turn the sections" while no step was turned (203 Newton iterations on
    configs/bending_neohookean.yaml with rotation and linear alike)."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.5, 1.0]
    summary = run_inline(raw, tmp_path / "tr", petsc={"snes_type": "newtontr"})
    assert summary["status"] == "completed"
    assert "SNES newtontr line search none;" in summary["solver"], summary["solver"]
    assert "Newton steps not turned" in summary["solver"] and "turn the sections" not in summary["solver"]


def test_a_turned_step_is_held_to_a_direction_vector_change_of_max_step_turn():
    """A step that turns every free node by 0.5 rad (beyond the gate, ROTATION_MAX) is scaled
    to direction-vector changes of MAX_STEP_TURN and then turned, as a whole step would be;
    with plain steps (``linear``) the same step is left as it is (a node move of under 2 section
    sizes)."""
    from ancf_petsc.petsc.step_limits import MAX_STEP_TURN, StepLimits
    P, V, X, x, free = _column_at_rest()
    w = np.zeros((x.shape[0], 3))
    w[free] = 0.5 * np.array([0.6, 0.0, 0.8])
    assert 0.5 > ROTATION_MAX > MAX_STEP_TURN
    step = np.zeros_like(x)
    step[:, 1:] = np.cross(w[:, None, :], x[:, 1:])
    for update, turned in (("linear", False), ("rotation", True)):
        limits = StepLimits(P)
        limits.configure(0.0, update, "basic")
        Y = X.duplicate()
        Y.setArray(-step.ravel())
        assert limits.precheck(X, Y) is turned
        y = -Y.getArray(readonly=True).reshape(-1, V, 3)
        if not turned:
            assert np.array_equal(y, step)
            continue
        first = np.cross(w[:, None, :], x[:, 1:3]) * (MAX_STEP_TURN / np.linalg.norm(step[:, 1:3], axis=2).max())
        new = x[free, 1:3] + y[free, 1:3]           # the scaled step, turned: |r| kept
        assert np.allclose(np.linalg.norm(new, axis=2), np.linalg.norm(x[free, 1:3], axis=2), rtol=1e-13)
        assert np.abs(y[free, 1:3] - first[free]).max() <= 0.6 * MAX_STEP_TURN ** 2


@pytest.mark.parametrize("name,update", [("achilles_type3_psi45.yaml", "linear"),
                                         ("achilles_type3_psi45_goh.yaml", "rotation"),
                                         ("achilles_type3_psi45_goh_alex.yaml", "rotation"),
                                         ("gait_stride_walking.yaml", "linear"),
                                         ("pretwisted_bar.yaml", "rotation"),
                                         ("elastica_svk.yaml", "rotation"),
                                         ("bundle_hex7.yaml", "linear")])
def test_a_model_with_a_fibre_law_turns_its_sections_by_default(name, update):
    """config/parse.py ``default_section_update``: ``rotation`` with a GOH law or without
    contact, else ``linear``; a given value is kept."""
    from ancf_petsc.config.parse import parse_config
    assert parse_config(load_raw(name), CONFIGS).solver.section_update == update
    raw = load_raw(name)
    raw["solver"] = dict(raw.get("solver") or {}, section_update="linear")
    assert parse_config(raw, CONFIGS).solver.section_update == "linear"


def _alex_column(steps):
    """The fibre envelope's alex cell (soft matrix, stiff fibres) at twist 45°, uniform bias, its
    unilateral law, 4 elements, with the load levels ``steps``."""
    from ancf_petsc.workflows.envelope import GOH, EnvelopeCell, cell_config
    base = next(g for g in GOH if g.endswith("_alex.yaml"))
    raw = cell_config(EnvelopeCell(base, 45.0, "uniform", elements=4))
    raw["steps"] = steps
    return raw


def test_a_soft_goh_column_takes_fewer_newton_iterations_with_turned_sections(tmp_path):
    """alex (soft matrix, stiff fibres), twist 45°, uniform bias, its unilateral law, 4
    elements, to 1.2 kN: the linear update's turns stretch the directors by |ω|²/2, which the
    fibres answer with residual rises every other iteration (78 Newton iterations in 9 sub-steps
    to the first level, 30 N).  Turned (the default with fibres): 107 → 88 iterations to 1.2 kN,
    56 since the predictions turn too (the envelope, docs/gait.md), the same answer to the
    Newton tolerance."""
    runs = {}
    for update in ("linear", None):
        raw = _alex_column([30.0, 100.0, 200.0, 400.0, 600.0, 800.0, 1000.0, 1200.0])
        if update:
            raw.setdefault("solver", {})["section_update"] = update
        runs[update] = run_inline(raw, tmp_path / str(update), base_dir=CONFIGS)
    plain, turned = runs["linear"], runs[None]
    assert plain["status"] == turned["status"] == "completed"
    assert "Newton steps turn the sections" in turned["solver"]
    assert turned["newton_iterations"] <= 0.9 * plain["newton_iterations"], \
        (turned["newton_iterations"], plain["newton_iterations"])
    for name, probe in plain["steps"][-1]["probes"].items():
        u, v = np.asarray(probe["displacement"]), np.asarray(turned["steps"][-1]["probes"][name]["displacement"])
        assert np.abs(u - v).max() <= 1e-6 * np.abs(u).max(), name


def test_the_load_predictions_turn_the_sections_where_newton_steps_do(tmp_path, monkeypatch):
    """The alex column to 200 N: the tangent load predictor's and the complementarity
    predictor's steps turned as Newton's are (``StepLimits.turned``) start closer (the first
    sub-step from rest at |F| 0.60 N instead of 3.8 N; one of the first level's sub-steps needs
    a second prediction instead of three): measured 75 → 45 Newton iterations, the same answer to
    the Newton tolerance.  Linear predictions (``turned`` a no-op) are the path before 2026-12-04."""
    from ancf_petsc.petsc.step_limits import StepLimits
    turned = run_inline(_alex_column([30.0, 100.0, 200.0]), tmp_path / "turned", base_dir=CONFIGS)
    monkeypatch.setattr(StepLimits, "turned", lambda self, X, Y: False)
    plain = run_inline(_alex_column([30.0, 100.0, 200.0]), tmp_path / "plain", base_dir=CONFIGS)
    assert plain["status"] == turned["status"] == "completed"
    assert turned["newton_iterations"] <= 0.75 * plain["newton_iterations"], \
        (turned["newton_iterations"], plain["newton_iterations"])
    for name, probe in plain["steps"][-1]["probes"].items():
        u, v = np.asarray(probe["displacement"]), np.asarray(turned["steps"][-1]["probes"][name]["displacement"])
        assert np.abs(u - v).max() <= 1e-6 * np.abs(u).max(), name


@pytest.mark.mpi
def test_turned_predictions_give_the_serial_answer_on_two_and_three_ranks(tmp_path):
    """The alex column's first level (30 N from rest in 6 sub-steps whose predictions are
    turned) on 1, 2 and 3 ranks: whether a step is turned is decided over every rank, so each
    takes the serial Newton iterations to the serial answer."""
    from helpers import assert_same_as_serial, probes_table, run_on_ranks
    runs = run_on_ranks(_alex_column([30.0]), tmp_path, ranks=(1, 2, 3))
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
    its = {n: [st["iterations"] for st in s["steps"]] for n, (_, s) in runs.items()}
    assert its[1] == its[2] == its[3], its


def test_the_pretwisted_bar_reaches_its_first_level_without_a_cut_back(tmp_path):
    """configs/pretwisted_bar.yaml (no contact: turned sections by default): the unloaded helix is
    soft against its off-axis end force; with straight steps its first level (1 N) took 69 Newton
    iterations and three cut-backs, one for an inverted element, each step that turns a section by
    ω stretching it by ω²/2.  Turned: 8 iterations, no cut-back, the same tip to 1e-8 of it."""
    runs = {}
    for update in ("linear", None):
        raw = load_raw("pretwisted_bar.yaml")
        raw["steps"] = [0.25]
        if update:
            raw["solver"] = {"section_update": update}
        runs[update] = run_inline(raw, tmp_path / str(update), base_dir=CONFIGS)
    plain, turned = runs["linear"], runs[None]
    assert plain["steps"][0]["cutbacks"] >= 2 and turned["steps"][0]["cutbacks"] == 0
    assert turned["newton_iterations"] <= 12 < plain["newton_iterations"]
    u = np.asarray(plain["steps"][0]["probes"]["tip"]["displacement"])
    v = np.asarray(turned["steps"][0]["probes"]["tip"]["displacement"])
    assert np.abs(u - v).max() <= 1e-8 * np.abs(u).max()
