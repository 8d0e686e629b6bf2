"""Unilateral contact on every mesh and step size (issue 24): the law's phases and pivoting, the
complementarity predictor, the end weights of contact points, and the hard cases at small size
(the runs that failed before: fine meshes, a bundle, fixed increments, a bulk-modulus sweep)."""
import itertools

import numpy as np
import pytest

from helpers import build_problem, load_raw, run_inline
from ancf_petsc.contact.laws import BANDS, PATIENCE, Phase, UnilateralLaw
from ancf_petsc.contact.fade import CURVE_FADE_END, CURVE_OVERHANG, END_FADE, end_weight


def _serial_reduce(values, op):
    return values


def test_banded_phase_ignores_small_violations_and_stops_a_cycle():
    law = UnilateralLaw()
    law.begin(Phase("band", band=1e-2))
    ids, owned = np.arange(4), np.ones(4, dtype=bool)
    gbar = np.array([-1e-4, -0.1, 1.0, 0.0])           # penetrations of 1e-4 and 0.1 of max |ḡ|
    z = np.array([0.0, 0.0, 0.0, -1.0])                 # a pull on the active one
    prev = np.array([False, False, False, True])
    new = law.update(gbar, z, prev, 1e-15, ids, owned, _serial_reduce)
    assert new.tolist() == [False, True, False, False]  # the 1e-4 penetration is inside the band
    # constraint 1 released on a pull (its second change), then penetrating again: it keeps
    # its status for the rest of the phase
    pull = np.array([0.0, -1.0, 0.0, 0.0])
    new = law.update(np.array([0.0, 1.0, 1.0, 0.0]), pull, new, 1e-15, ids, owned, _serial_reduce)
    assert not new[1]
    new = law.update(np.array([0.0, -0.5, 1.0, 0.0]), np.zeros(4), new, 1e-15, ids, owned,
                     _serial_reduce)
    assert law._flips[1] == 2 and not new[1]


def test_exact_phase_falls_back_to_the_least_index_pivot():
    """Block principal pivoting: every violation flips while their number falls; after
    PATIENCE non-improving steps only the lowest violated index changes."""
    law = UnilateralLaw()
    law.begin(Phase("exact", pivoting=True))
    ids, owned = np.arange(6) + 10, np.ones(6, dtype=bool)
    prev = np.zeros(6, dtype=bool)
    gbar = np.array([1.0, -1.0, -1.0, 1.0, -1.0, 1.0])       # three penetrations
    for step in range(PATIENCE + 1):                     # the count (3) never falls again
        new = law.update(gbar, np.zeros(6), prev, 1e-12, ids, owned, _serial_reduce)
        assert new.sum() == 3
    new = law.update(gbar, np.zeros(6), prev, 1e-12, ids, owned, _serial_reduce)
    assert new.tolist() == [False, True, False, False, False, False]
    assert law.single_pivots == 1


def test_phases_end_with_the_exact_rule():
    ph = UnilateralLaw().phases(from_rest=True)
    assert [p.band for p in ph[:-1]] == list(BANDS) and ph[-1].band == 0.0 and ph[-1].pivoting


def test_end_weight_is_one_on_the_surface_and_falls_smoothly_past_its_ends():
    T = 2.0
    t = np.array([0.0, 0.5 * T, T, (1 + CURVE_OVERHANG) * T, -CURVE_OVERHANG * T,
                  (1 + CURVE_FADE_END) * T, -CURVE_FADE_END * T])
    w = end_weight(np.zeros(len(t)), t, np.full(len(t), T), np.zeros(len(t), bool), np.zeros(len(t), bool))
    assert np.allclose(w, [1, 1, 1, 1, 1, 0, 0])
    # monotone and C¹ across the band (finite differences of the weight have no jump)
    s = np.linspace(1 + CURVE_OVERHANG - 0.02, 1 + CURVE_FADE_END + 0.02, 2001) * T
    ws = end_weight(np.zeros(len(s)), s, np.full(len(s), T), np.zeros(len(s), bool), np.zeros(len(s), bool))
    d = np.diff(ws) / np.diff(s)
    assert np.all(d <= 1e-12) and np.max(np.abs(np.diff(d))) < 0.01 * np.max(np.abs(d))
    # past the beam's last element: 1 at its end, 0 a quarter of an element beyond
    xi = np.array([0.0, 1.0, 1.0 + 4 * END_FADE, 1.0 + 2 * END_FADE])
    w = end_weight(xi, np.full(4, 0.5 * T), np.full(4, T), np.zeros(4, bool), np.ones(4, bool))
    assert np.allclose(w, [1, 1, 0, 0])


def test_lcp_solution_is_complementary():
    """The predictor's dense solve against enumeration of every active set (random SPD S)."""
    from ancf_petsc.petsc.lcp import solve_lcp
    rng = np.random.default_rng(3)
    for _ in range(5):
        A = rng.standard_normal((7, 7))
        S = A @ A.T + 0.1 * np.eye(7)
        d = rng.standard_normal(7)
        z = solve_lcp(S, d)
        w = d + S @ z
        assert z.min() >= 0 and w.min() > -1e-9 and abs(z @ w) < 1e-9
        # the unique solution of a P-matrix problem: the one complementary active set
        sols = []
        for act in itertools.product([0, 1], repeat=7):
            a = np.array(act, dtype=bool)
            zz = np.zeros(7)
            if a.any():
                zz[a] = np.linalg.solve(S[np.ix_(a, a)], -d[a])
            ww = d + S @ zz
            if zz.min() >= -1e-12 and ww.min() >= -1e-12:
                sols.append(zz)
        assert len(sols) == 1 and np.allclose(sols[0], z, atol=1e-9)


def test_an_ill_conditioned_active_set_is_judged_without_a_warning():
    """``exact_on_support`` on an S_AA with rcond below machine precision (scipy's LinAlgWarning,
    which printed mid-run on the 16-element 180° column): no warning, and its answer is judged as
    any other; here z_A has a negative entry, so the clipped z stands."""
    import warnings
    import scipy.linalg as la
    from ancf_petsc.petsc.lcp import exact_on_support
    S = np.array([[1.0, 1.0], [1.0, 1.0 + 4.5e-16]])
    d = np.array([-1.0, -1.0 - 9e-16])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert la.solve(S, -d).min() < 0.0                  # what the exact S gives: z_A < 0
        assert any(issubclass(w.category, la.LinAlgWarning) for w in caught)   # the test can tell
        caught.clear()
        z = np.array([0.5, 0.5])
        assert np.array_equal(exact_on_support(S, d, z), z)
        assert not caught


def test_lcp_with_a_nearly_semidefinite_schur_complement():
    """Away from rest S can be indefinite (the bodies' tangent without the constraints is):
    within INDEFINITE_SHARE of semidefinite the LCP of its nearest semidefinite matrix is
    solved, and its active set solved again with the exact S: complementary for S where that
    solves the exact LCP, else for the semidefinite matrix (both occur below); farther, there
    is no prediction."""
    import numpy.linalg as npl
    from ancf_petsc.petsc.lcp import INDEFINITE_SHARE, solve_lcp
    branches = set()
    for seed in (5, 6, 7, 8):
        rng = np.random.default_rng(seed)
        V, _ = npl.qr(rng.standard_normal((6, 6)))
        d = rng.standard_normal(6)
        lam = np.array([-2.0 * INDEFINITE_SHARE, 0.3, 0.5, 0.8, 0.9, 1.0])
        with pytest.raises(np.linalg.LinAlgError):
            solve_lcp((V * lam) @ V.T, d)
        lam[0] = -0.5 * INDEFINITE_SHARE
        S, Sp = (V * lam) @ V.T, (V * np.maximum(lam, 0.0)) @ V.T
        z = solve_lcp(S, d)
        exact = [(d + M @ z).min() > -1e-9 and abs(z @ (d + M @ z)) < 1e-9 for M in (S, Sp)]
        assert z.min() >= 0 and exact[0] != exact[1], exact            # one of the two, exactly
        zp = solve_lcp(Sp + 1e-9 * np.eye(6), d)   # Sp's own LCP
        a = zp > 1e-12
        za = np.zeros(6)
        za[a] = np.linalg.solve(S[np.ix_(a, a)], -d[a])
        assert exact[0] == (za.min() >= 0 and (d + S @ za).min() > -1e-9) and np.array_equal(z > 0, a)
        branches.add(exact[0])
    assert branches == {True, False}


def test_a_clipped_schur_complement_keeps_the_exact_step_of_its_active_set():
    """The bodies' tangent K without the constraints can be indefinite (a neighbour pressed by
    its contact forces buckles when free): S = G K⁻¹ Gᵀ is then indefinite, and within
    INDEFINITE_SHARE the clipped S chooses the active set.  Its pressures and the predicted
    step Δq = K⁻¹(−F + Gᵀ z) come from the exact S: the step is the saddle-point Newton step
    of that active set and closes its linearised gaps (w_A = 0).  The clipped S's own
    pressures left a linearised gap of −0.019 (a penetration) here and, on the
    solver_default_2025 GOH column at 90.72 N (docs/contact.md), a step of 4.4 against
    Newton's 0.028, from which the stepper's solves failed."""
    import scipy.linalg as la
    from ancf_petsc.petsc.lcp import INDEFINITE_SHARE, solve_lcp
    rng = np.random.default_rng(7)
    n, m = 6, 4
    V, _ = np.linalg.qr(rng.standard_normal((n, n)))
    K = (V * np.array([-1e-3, 1.0, 1.5, 2.0, 2.5, 3.0])) @ V.T          # one soft negative mode
    R = rng.standard_normal((m, n))
    R[3, 1:] = R[2, 1:] + 1e-2 * rng.standard_normal(n - 1)            # two nearly redundant constraints
    R[:, 0] = 3e-3 * rng.standard_normal(m)                            # that barely touch the soft mode
    G = R @ V.T
    Ki = np.linalg.inv(K)
    S = G @ Ki @ G.T
    lam = la.eigvalsh(S)
    assert 0.0 < -lam[0] < INDEFINITE_SHARE * lam[-1]                   # the clipped branch
    F = rng.standard_normal(n)
    c = -S @ rng.uniform(0.5, 1.0, m) + G @ Ki @ F                      # pressed gaps
    d = c - G @ Ki @ F
    z = solve_lcp(S, d)
    dq = Ki @ (-F + G.T @ z)
    w = c + G @ dq                                                     # the linearised gaps
    A = z > 0.0
    assert A.sum() >= 2 and z.min() >= 0.0 and w.min() > -1e-9 and abs(z @ w) < 1e-9
    saddle = np.linalg.solve(np.block([[K, -G[A].T], [G[A], np.zeros((A.sum(), A.sum()))]]),
                             np.concatenate([-F, -c[A]]))
    assert np.allclose(dq, saddle[:n], rtol=1e-9, atol=1e-9 * np.abs(saddle[:n]).max())
    assert np.allclose(z[A], saddle[n:], rtol=1e-9)

def test_an_indefinite_schur_complement_is_solved_with_the_pressing_constraints_held():
    """Far from semidefinite (a body that buckles when free of its pressed neighbour: K has a
    strong negative mode that one constraint holds) there is no clipped prediction; holding
    the pressing constraints as equalities leaves the Schur complement of the saddle-point
    system with them held, positive definite here, and its LCP gives a solution of the exact
    LCP(S, d): one of the complementary solutions that enumeration finds, with the held
    constraint closed (w = 0).  The plain solve has none (LinAlgError)."""
    from ancf_petsc.petsc.lcp import INDEFINITE_SHARE, held_lcp, solve_lcp
    rng = np.random.default_rng(11)
    n, m = 7, 5
    V, _ = np.linalg.qr(rng.standard_normal((n, n)))
    K = (V * np.array([-0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5])) @ V.T     # one strong negative mode
    R = rng.standard_normal((m, n))
    R[0, 0] = 4.0                                                     # constraint 0 holds it
    R[1:, 0] = 0.05 * rng.standard_normal(m - 1)
    G = R @ V.T
    Ki = np.linalg.inv(K)
    S = 0.5 * (G @ Ki @ G.T + (G @ Ki @ G.T).T)
    lam = np.linalg.eigvalsh(S)
    assert -lam[0] > INDEFINITE_SHARE * lam[-1]
    d = rng.standard_normal(m)
    d[0] = -abs(d[0]) - 1.0                                           # constraint 0 penetrates
    held = np.zeros(m, bool)
    held[0] = True
    with pytest.raises(np.linalg.LinAlgError):
        solve_lcp(S, d)
    z = held_lcp(S, d, held)
    w = d + S @ z
    assert z.min() >= 0 and w.min() > -1e-9 and abs(z @ w) < 1e-9 and abs(w[0]) < 1e-9
    sols = []
    for act in itertools.product([0, 1], repeat=m):
        a = np.array(act, dtype=bool)
        zz = np.zeros(m)
        if a.any():
            zz[a] = np.linalg.solve(S[np.ix_(a, a)], -d[a])
        if zz.min() >= -1e-12 and (d + S @ zz).min() >= -1e-12:
            sols.append(zz)
    assert any(np.allclose(zz, z, atol=1e-9) for zz in sols)
    # the held system's Schur complement is positive definite: K is, on the motions it allows
    E, Rr = held, ~held
    St = S[np.ix_(Rr, Rr)] - S[np.ix_(Rr, E)] @ np.linalg.solve(S[np.ix_(E, E)], S[np.ix_(E, Rr)])
    assert np.linalg.eigvalsh(St).min() > 0


def _achilles(psi, elements, axial, mode="unilateral", steps=None, solver=None, petsc=None):
    raw = load_raw(f"achilles_type3_psi{psi if psi in (0, 15, 45) else 45}.yaml")
    raw["geometry"]["twist_deg"] = psi
    for b in raw["beams"]:
        b["elements"], b["axial_points"] = elements, axial
    raw["contact"]["mode"] = mode
    if steps is not None:
        raw["steps"] = steps
    if solver:
        raw["solver"] = solver
    if petsc:
        raw["petsc"] = petsc
    return raw


def test_predictor_finds_the_contact_state_of_the_touching_start():
    """At a tiny load (linear regime) the predicted active set is the one Newton converges to,
    on a mesh where the plain rule needed 20+ iterations (8 elements, ψ = 45°)."""
    from ancf_petsc.petsc.complementarity import ComplementarityPredictor
    P, PETSc = build_problem(_achilles(45, 8, 3), "sbaij")
    pred = ComplementarityPredictor(P)
    P.load_factor = 0.01
    X = P.q0.copy()
    assert pred.predict(X)
    predicted = P.contact.status.copy()
    assert 0 < predicted.sum() < len(predicted)
    # the predicted state: every constraint the status holds is closed, every other is open
    F = P.F.duplicate()
    P.contact.begin_phase(Phase("exact", pivoting=True))
    changes = P.contact.status_changes
    P.residual(None, X, F)
    assert P.contact.status_changes == changes
    assert np.array_equal(P.contact.status, predicted)
    pred.destroy()


def test_an_evaluation_repeated_after_the_exchange_decides_no_status():
    """On several ranks an evaluation in which some rank's projection reached an element that
    rank does not hold is repeated after the exchange (petsc/exchange.py), every point from the
    place it started from.  Its gaps are not those one rank sees (the point waited at the
    boundary), so it neither decides nor records a status: the law decides on the repeated
    evaluation.  (Before, the law decided on the incomplete gaps and the repeat kept that status.)"""
    from ancf_petsc.petsc.complementarity import multiplier_dofs
    P, _ = build_problem(_achilles(45, 4, 2), "aij")
    c = P.contact
    X = P.q0.copy()
    lo, _ = X.getOwnershipRange()
    x = X.getArray()
    x[multiplier_dofs(P) - lo] = -1e-3                  # every multiplier pulls ...
    del x
    c.status[:] = True                                  # ... on an active constraint: release
    before = c.status_changes
    c.all_ranks = lambda flag: False                    # another rank lacks an element
    c.allow_update = True
    c.evaluate(P.exchange.local_state(X).copy(), P.exchange.needed)
    assert c.status.all() and c.allow_update and c.status_changes == before
    c.all_ranks = lambda flag: flag                     # the repeated, complete evaluation
    c.evaluate(P.exchange.local_state(X).copy(), P.exchange.needed)
    assert not c.status.any() and not c.allow_update
    assert c.status_changes == before + len(c.status)


@pytest.mark.parametrize("matrix", ["sbaij", "aij"])
def test_kept_operator_refactors_to_a_fresh_predictors_schur_complement(matrix):
    """The predictor keeps K between linearisations (complementarity.KeptOperator: its values
    copied in, MUMPS refactoring on the kept symbolic analysis): S and d at a second state equal
    a fresh predictor's there and differ from the first state's (no stale factor).  Equal to
    1e-12, not bitwise: two linearisations at one state by one predictor differ in the last bit
    already (5e-16, measured), their closest points found again from the last ones."""
    from ancf_petsc.petsc.complementarity import ComplementarityPredictor
    P, _ = build_problem(_achilles(45, 4, 2), matrix)
    pred = ComplementarityPredictor(P)
    P.load_factor = 5.0
    X = P.q0.copy()
    first = pred._linearised(X, [])
    assert pred._kept.K is not None
    X.axpy(1e-4, P.q0)                                  # another state, the same pattern
    kept_K = pred._kept.K
    second = pred._linearised(X, [])
    assert pred._kept.K is kept_K or P.pattern_growths != pred._kept.growths
    fresh = ComplementarityPredictor(P)
    again = fresh._linearised(X, [])
    rel = lambda a, b: np.abs(a - b).max() / np.abs(b).max()   # noqa: E731
    assert rel(second[0], again[0]) < 1e-12 and rel(second[1], again[1]) < 1e-12
    assert rel(first[0], second[0]) > 1e-6 or rel(first[1], second[1]) > 1e-6
    pred.destroy()
    fresh.destroy()


@pytest.mark.slow
@pytest.mark.parametrize("psi,elements,axial", [(45, 8, 3), (15, 8, 3), (45, 12, 2)])
def test_refined_unilateral_columns_converge_without_cut_backs(psi, elements, axial, tmp_path):
    """The first levels of the Table 1 columns that failed from 6–8 elements on (issue 24):
    no cut-back, the contact state found in the first level, in one increment from rest with
    the complementarity predictor at every increment (14–18 Newton iterations; 21–25 in three
    increments with it from rest only and the phases after)."""
    s = run_inline(_achilles(psi, elements, axial, steps=[10, 20, 30]), tmp_path)
    assert s["status"] == "completed"
    assert sum(st["cutbacks"] for st in s["steps"]) == 0
    assert [st["substeps"] for st in s["steps"]] == [1, 1, 1]
    assert s["newton_iterations"] <= 22


def test_indefinite_schur_complement_and_a_whole_column(tmp_path):
    """bundle_circle7 (touching circles, compressed: S strongly indefinite, no prediction; the
    status kept for the solve and checked) converges in a few iterations where the phases took
    390 with 2 cut-backs; the paper's ψ = 0° column at 6 elements, whose predictor assemblies
    grow the contact pattern after the SNES has factored (the SNES's factorisation must then
    start afresh: it crashed in MUMPS before), converges as the grid measured."""
    raw = load_raw("bundle_circle7.yaml")
    raw["contact"]["mode"] = "unilateral"
    s = run_inline(raw, tmp_path / "circle7")
    assert s["status"] == "completed"
    assert sum(st["cutbacks"] for st in s["steps"]) == 0
    assert s["newton_iterations"] <= 20
    s = run_inline(_achilles(0, 6, 2), tmp_path / "psi0")
    assert s["status"] == "completed"
    assert sum(st["cutbacks"] for st in s["steps"]) == 0
    assert s["newton_iterations"] <= 40


@pytest.mark.slow
def test_unilateral_bundle_and_fixed_increments(tmp_path):
    """bundle_hex7 with mode: unilateral (failed in its first increment) and the paper's tendon
    in fixed increments of 0.25 of 400 N without cut-backs (failed with every line search)."""
    raw = load_raw("bundle_hex7.yaml")
    raw["contact"]["mode"] = "unilateral"
    s = run_inline(raw, tmp_path / "hex7")
    assert s["status"] == "completed"
    for ls in ("basic", "bt"):
        s = run_inline(_achilles(45, 4, 3, steps=[400], solver={
            "initial_increment": 100, "max_increment": 100, "max_cutbacks": 0, "growth": 1.0},
            petsc={"snes_linesearch_type": ls, "snes_max_it": 50}), tmp_path / ls)
        assert s["status"] == "completed", ls


@pytest.mark.slow
def test_held_start_where_the_predictor_does_not_apply(tmp_path, monkeypatch):
    """Above the predictor's size (bundle_hex37: 5 940 multipliers) the first increment from rest
    is solved with every constraint held, then released by the phases (it failed in its first
    increment with every constraint starting open).  Shown on bundle_hex7 with the predictor
    switched off: it converges to the predictor's answer (with 2 cut-backs in the first level:
    the exactly touching start has many near-zero pressures; bundle_hex37 itself needs none)."""
    from ancf_petsc.petsc import complementarity
    raw = load_raw("bundle_hex7.yaml")
    raw["contact"]["mode"] = "unilateral"
    with_predictor = run_inline(raw, tmp_path / "predictor")
    monkeypatch.setattr(complementarity, "MAX_MULTIPLIERS", 0)
    held = run_inline(raw, tmp_path / "held")
    assert held["status"] == "completed"
    assert sum(st["cutbacks"] for st in held["steps"][1:]) == 0
    for name, p in with_predictor["steps"][-1]["probes"].items():
        u0, u1 = np.array(p["displacement"]), np.array(held["steps"][-1]["probes"][name]["displacement"])
        assert np.abs(u1 - u0).max() <= 1e-7 * np.abs(u0).max(), name


@pytest.mark.slow
@pytest.mark.parametrize("psi,K", [(0, 0.90e9), (45, 0.88e9), (0, 0.70e9), (45, 1.0e9)])
def test_bulk_modulus_sweep_does_not_make_newton_cycle(psi, K, tmp_path):
    """The sliding columns at K = 0.90 GPa (ψ = 0) and 0.88 GPa (ψ = 45) cycled forever between
    two states just short of 400 N: a contact point switched off where its partner passed 25 %
    beyond the end of the interface curve.  Its weight now falls smoothly and is updated between
    Newton solves: no cut-back, and the ends of the sweep too."""
    raw = load_raw(f"achilles_type3_psi{psi}.yaml")
    for b in raw["beams"]:
        b["material"]["bulk_modulus"] = K
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed"
    assert sum(st["cutbacks"] for st in s["steps"]) == 0
    assert s["newton_iterations"] <= 70


@pytest.mark.slow
@pytest.mark.parametrize("share", [0.25, 1.0])
def test_sliding_full_newton_from_rest_in_large_steps(share, tmp_path):
    """The paper's tendon (sliding) in fixed steps of 0.25 x 400 N and in one step, full Newton:
    the first steps from rest wandered to |F| ~ 1e8 and failed (NaN) before full Newton steps
    with contact were held to 2 section sizes; the answer is the adaptive path's."""
    adaptive = run_inline(_achilles(45, 4, 3, mode="sliding", steps=[400]), tmp_path / "adaptive")
    s = run_inline(_achilles(45, 4, 3, mode="sliding", steps=[400], solver={
        "initial_increment": 400 * share, "max_increment": 400 * share, "max_cutbacks": 0, "growth": 1.0},
        petsc={"snes_max_it": 50}), tmp_path / "fixed")
    assert s["status"] == "completed"
    u0 = np.array(adaptive["steps"][-1]["probes"]["soleus"]["displacement"])
    u1 = np.array(s["steps"][-1]["probes"]["soleus"]["displacement"])
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()


def test_unilateral_law_asks_for_more_newton_iterations_than_the_general_default(tmp_path):
    """The unilateral law's PETSc default -snes_max_it 60 (contact/laws.py: an active set that
    settles late needs more than 15 at any increment); sliding keeps the general 15, a tangential
    law's own default (200) and the user's option win over it."""
    cases = {"unilateral": ({}, {}, "max_it 60"), "sliding": ({}, {}, "max_it 15"),
             "user": ({}, {"snes_max_it": 20}, "max_it 20"),
             "friction": ({"law": "coulomb", "friction": 0.3}, {}, "max_it 200")}
    for name, (tangential, petsc, expected) in cases.items():
        raw = _achilles(45, 1, 2, mode="sliding" if name == "sliding" else "unilateral", steps=[1.0],
                        petsc=petsc or None)
        if tangential:
            raw["contact"]["tangential"] = tangential
        s = run_inline(raw, tmp_path / name)
        assert s["status"] == "completed", name
        assert expected in s["solver"], (name, s["solver"])


def _exact_solutions(S, d):
    """Every solution of LCP(S, d) by enumeration of the active sets (to 1e-10)."""
    M, out = len(d), []
    for act in itertools.product([0, 1], repeat=M):
        a = np.array(act, dtype=bool)
        z = np.zeros(M)
        if a.any():
            try:
                z[a] = np.linalg.solve(S[np.ix_(a, a)], -d[a])
            except np.linalg.LinAlgError:
                continue
        if z.min() >= -1e-10 and (d + S @ z).min() >= -1e-10:
            out.append(np.maximum(z, 0.0))
    return out


def test_an_indefinite_lcp_keeps_the_solution_of_the_status_it_starts_from():
    """An indefinite S can give LCP(S, d) several solutions (the bodies' tangent without the
    constraints is indefinite: a subtendon buckles free of its neighbours).  Started from the
    active set of any one of them, ``solve_lcp`` returns that one (``pivoted_from``: the
    continuation of the converged status), where the nearest semidefinite matrix's NNLS picks
    one regardless of the status, or a z that solves only the clipped problem.  Measured on the
    180° soleus-biased unilateral stride at frame 18.5 (tests/solving/test_load_history.py's
    stride test): the converged status was an exact solution; the clipped S changed 6 constraints."""
    import numpy.linalg as npl
    from ancf_petsc.petsc.lcp import INDEFINITE_SHARE, solve_lcp
    several = other = 0
    for seed in range(400):
        rng = np.random.default_rng(seed)
        V, _ = npl.qr(rng.standard_normal((6, 6)))
        lam = np.array([-0.5 * INDEFINITE_SHARE, 0.3, 0.5, 0.8, 0.9, 1.0])
        S, d = (V * lam) @ V.T, rng.standard_normal(6)
        solutions = _exact_solutions(S, d)
        if len(solutions) < 2:
            continue
        several += 1
        free = solve_lcp(S, d)
        for zs in solutions:
            z = solve_lcp(S, d, start=zs > 1e-12)
            assert np.allclose(z, zs, atol=1e-9), (seed, z, zs)
            other += not np.allclose(free, zs, atol=1e-9)
    assert several >= 3 and other >= 3, (several, other)        # the test can tell


def test_a_positive_definite_lcp_ignores_the_start():
    """Its solution is unique: the start changes nothing (the same NNLS solve)."""
    from ancf_petsc.petsc.lcp import solve_lcp
    rng = np.random.default_rng(11)
    A = rng.standard_normal((6, 6))
    S, d = A @ A.T + 0.1 * np.eye(6), rng.standard_normal(6)
    z = solve_lcp(S, d)
    for start in (np.zeros(6, bool), np.ones(6, bool), z == 0.0):
        assert np.array_equal(solve_lcp(S, d, start=start), z)


def test_unilateral_contact_holds_the_pressed_strips(tmp_path):
    """configs/friction_pressed_strips.yaml with contact.mode: unilateral (2 elements): the
    slider, free along z but for the contact, was refused ('nothing holds slider (free:
    translation along z, rotation about x, rotation about y)') though docs/running.md counts
    unilateral contact as holding: the check read the constraints under the law's status at rest,
    where none is active.  Now it runs, to the sliding law's grip force, and the check leaves the
    status as it found it."""
    from test_friction_oscillation import strips
    from ancf_petsc.solving.supports import free_rigid_motions
    raw = strips(2)
    raw["contact"] = {"mode": "unilateral", "tangential": raw["contact"]["tangential"]}
    raw["steps"] = [1, 1.05]
    P, _ = build_problem(raw)
    assert free_rigid_motions(P) == [] and not P.contact.status.any() and P.contact.status_changes == 0
    grip = {}
    for mode in ("unilateral", "sliding"):
        raw["contact"]["mode"] = mode
        s = run_inline(raw, tmp_path / mode)
        assert s["status"] == "completed"
        grip[mode] = s["steps"][-1]["reactions"]["grip"][0]
    assert abs(grip["unilateral"] - grip["sliding"]) <= 1e-6 * abs(grip["sliding"]), grip
