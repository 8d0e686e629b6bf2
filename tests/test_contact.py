"""Contact: consistent Jacobians (finite differences), energy gradient, reference state, modes."""
import copy

import numpy as np
import pytest

from helpers import load_raw, petsc_init
from test_solver import _problem


def achilles(psi=45.0, elements=2, contact=None):
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["geometry"]["twist_deg"] = psi
    for b in raw["beams"]:
        b["elements"] = elements
    if contact is not None:
        raw["contact"] = contact
    return raw


def perturbed_state(P, scale, seed):
    rng = np.random.default_rng(seed)
    X = P.X
    P.q0.copy(X)
    free = ~P.fixed_mask
    q = X.getArray().reshape(-1, 6, 3)
    noise = rng.standard_normal(q.shape)
    noise[:, 1:3] *= 20.0          # slopes are O(1), positions O(L)
    noise[:, 3:] *= 200.0
    X.setArray(X.getArray() + scale * noise.ravel() * free)
    return X, free


MODES = {
    "sliding-projected": {"mode": "sliding"},
    "sliding-pointwise": {"mode": "sliding", "projection": "pointwise"},
    "unilateral": {"mode": "unilateral"},                       # C2 penalty ramp (auto width)
    "unilateral-sharp": {"mode": "unilateral", "smoothing": 0.0},
}


@pytest.mark.parametrize("mode", list(MODES))
def test_contact_jacobian_matches_finite_differences(mode):
    P, PETSc = _problem(achilles(contact=MODES[mode]))
    P.load_factor = 50.0
    X, free = perturbed_state(P, 2e-6, 3)
    P.jacobian(None, X, P.J, P.J)
    rng = np.random.default_rng(7)
    # unilateral: the probe must not cross g = 0 anywhere (the active set must not change)
    h = 1e-6 if mode.startswith("unilateral") else 1e-4
    if mode == "unilateral":       # the state has points on the ramp and beyond it
        g = P.contact._evaluate(P._local_state(X).copy(), P.needed, False)["g"]
        dlt = P.contact.smoothing
        assert np.any((g < 0) & (g > -dlt)) and np.any(g < -dlt)
    for _ in range(3):
        v = X.duplicate()
        v.setArray(rng.standard_normal(X.getLocalSize()) * free * 1e-3)
        Jv = X.duplicate()
        P.J.mult(v, Jv)
        Fp, Fm, Xp, Xm = X.duplicate(), X.duplicate(), X.copy(), X.copy()
        Xp.axpy(h, v)
        Xm.axpy(-h, v)
        P.residual(None, Xp, Fp)
        P.residual(None, Xm, Fm)
        if mode.startswith("unilateral"):
            active = [P.contact._evaluate(P._local_state(Y).copy(), P.needed, False)["w"] > 0
                      for Y in (Xp, Xm)]
            assert np.array_equal(active[0], active[1]) and 0 < active[0].sum() < len(active[0])
        fd = (Fp.getArray() - Fm.getArray()) / (2 * h)
        jv = Jv.getArray()
        err = np.abs(jv - fd)[free].max() / np.abs(jv).max()
        assert err < 1e-6, err
    Jd = P.J.convert("dense", PETSc.Mat()).getDenseArray()
    assert np.abs(Jd - Jd.T).max() <= 1e-9 * np.abs(Jd).max()


@pytest.mark.parametrize("mode", list(MODES))
def test_contact_residual_is_energy_gradient(mode):
    P, PETSc = _problem(achilles(contact=MODES[mode]))
    P.load_factor = 20.0
    X, free = perturbed_state(P, 2e-6, 5)
    F = X.duplicate()
    P.residual(None, X, F)
    v = X.duplicate()
    v.setArray(np.random.default_rng(2).standard_normal(X.getLocalSize()) * free * 1e-3)
    h = 1e-6 if mode.startswith("unilateral") else 1e-4     # see the Jacobian test
    Xp, Xm = X.copy(), X.copy()
    Xp.axpy(h, v)
    Xm.axpy(-h, v)
    dPi = (P.objective(None, Xp) - P.objective(None, Xm)) / (2 * h)
    assert dPi == pytest.approx(F.dot(v), rel=1e-6)


def test_reference_state_is_gap_free_and_stress_free():
    P, PETSc = _problem(achilles())
    P.load_factor = 0.0
    X = P.q0.copy()
    F = X.duplicate()
    P.residual(None, X, F)
    # rounding only: penalty x contact area x position magnitude x machine epsilon
    floor = 2.2e-16 * P.contact.penalty * P.contact.pts["w"].sum() * P.model.spec.length
    assert F.norm() < floor, (F.norm(), floor)
    gaps = P.contact.gaps(P.model.q0)
    assert len(gaps) == 3 and all(g["max_gap"] < 1e-12 for g in gaps.values())


def test_unilateral_penalty_ramp_is_twice_differentiable():
    P, _ = _problem(achilles(contact={"mode": "unilateral", "smoothing": 2e-6}))
    c = P.contact
    dlt = c.smoothing
    g = np.linspace(-3 * dlt, 2 * dlt, 2001)
    phi, d1, d2 = c.penalty_function(g)
    h = 1e-3 * dlt
    plus, minus = c.penalty_function(g + h), c.penalty_function(g - h)
    for k in (0, 1):         # the slope and the stiffness agree with central differences
        fd = (plus[k] - minus[k]) / (2 * h)
        exact = (d1, d2)[k]
        # the third derivative jumps at the joints: there the difference is only O(h) accurate
        assert np.allclose(fd, exact, atol=(1e-6, 2e-3)[k] * np.abs(exact).max())
    for x in (-dlt, 0.0):                     # value, slope and stiffness continuous at the joints
        lo = np.array(c.penalty_function(np.array([x - 1e-9 * dlt])))
        hi = np.array(c.penalty_function(np.array([x + 1e-9 * dlt])))
        assert np.allclose(lo, hi, rtol=0, atol=1e-8)
    assert np.all(phi[g >= 0] == 0) and np.all(d2 >= 0) and np.all(d2 <= 1)
    deep = g < -dlt
    assert np.allclose(d2[deep], 1.0)         # the full penalty beyond the ramp


def test_mortar_blocks_skip_elements_no_point_projects_on():
    """A segment whose points project onto B elements e and e + 2 (none on e + 1) must not insert
    the middle node of e + 1: that coupling is not in the matrix pattern."""
    from ancf_petsc.assembly import _Collector
    P, _ = _problem(achilles(elements=4))
    c = P.contact
    xl = P._local_state(P.q0).copy()
    r = dict(c._evaluate(xl, P.needed, True))
    seg0 = c.pts["seg"] == c.pts["seg"][0]
    idx = np.flatnonzero(seg0)
    first = int(r["eB"][idx[0]])
    r["eB"] = r["eB"].copy()
    r["eB"][idx[: len(idx) // 2]] = first + 2          # half the points two elements further
    col = _Collector()
    c._mortar_jacobian(r, col, P.fixed_mask)
    middle = c._conn[first + 1][1]                      # the node only element e + 1 has
    wide = [rows for rows, _, _ in col.blocks if rows.shape[1] == 54 + 18 * 7]   # spans 3 elements
    assert len(wide) == 1 and wide[0].shape[0] == 1
    nodes = wide[0][0] // 18
    assert middle not in nodes[wide[0][0] >= 0]
    assert c._conn[first + 2][1] in nodes and c._conn[first][1] in nodes
