"""The closest-point projection at large motion (docs/contact.md, "Closest points at large
motion"): the step's independence of the surface's parametrisation, and projections of points
moved far from their partners against an independent minimiser of the distance."""
import numpy as np
import pytest
from scipy.optimize import minimize

from helpers import load_raw
from ancf_petsc.contact.descent import newton_step
from ancf_petsc.config.parse import parse_config
from ancf_petsc.contact import build_contact
from ancf_petsc.model.build import build_model
from ancf_petsc.physics.element3363 import SLOTS


def _surface_data(seed, P=200):
    """Random surface tangents, second derivatives and distance vectors: ξ is ~100 times shorter
    on the surface than t (as on the Achilles beams: |Y_ξ|² ≈ 1e-4 m², |Y_t|² ≈ 1)."""
    rng = np.random.default_rng(seed)
    Yz = rng.standard_normal((P, 3, 2))
    Yz[:, :, 0] *= 1e-2
    Yzz = rng.standard_normal((P, 3, 2, 2)) * np.array([[1e-4, 1e-2], [1e-2, 1.0]])
    Yzz = 0.5 * (Yzz + Yzz.transpose(0, 1, 3, 2))
    d = rng.standard_normal((P, 3)) * rng.uniform(0.01, 30.0, (P, 1))   # near and far points
    return Yz, Yzz, d


@pytest.mark.parametrize("seed", [0, 1])
def test_step_is_that_of_the_surface_not_of_its_parameters(seed):
    """Stretching ξ by c (Y_ξ → c Y_ξ, Y_ξξ → c² Y_ξξ, Y_ξt → c Y_ξt) must shrink the ξ step by c
    and leave the t step alone: the same move on the surface.  Where H is positive definite the
    step is Newton's, elsewhere Gauss–Newton's, and it always lowers the distance to first order."""
    Yz, Yzz, d = _surface_data(seed)
    pinned = np.zeros(len(d), dtype=bool)
    dz, r = newton_step(Yz, Yzz, d, pinned)
    H = np.einsum("pik,pil->pkl", Yz, Yz) - np.einsum("pikl,pi->pkl", Yzz, d)
    pd = np.all(np.linalg.eigvalsh(H) > 0.0, axis=1)
    assert 0 < pd.sum() < len(d)                       # both cases are exercised
    assert np.allclose(dz[pd], -np.linalg.solve(H[pd], r[pd][..., None])[..., 0], rtol=1e-10, atol=0.0)
    G = np.einsum("pik,pil->pkl", Yz, Yz)
    assert np.allclose(dz[~pd], -np.linalg.solve(G[~pd], r[~pd][..., None])[..., 0], rtol=1e-10, atol=0.0)
    assert np.all(np.einsum("pk,pk->p", r, dz) < 0.0)
    c = 37.0
    Yz2, Yzz2 = Yz.copy(), Yzz.copy()
    Yz2[:, :, 0] *= c
    Yzz2[:, :, 0, 0] *= c * c
    Yzz2[:, :, 0, 1] *= c
    Yzz2[:, :, 1, 0] *= c
    dz2, _ = newton_step(Yz2, Yzz2, d, pinned)
    assert np.allclose(dz2[:, 0] * c, dz[:, 0], rtol=1e-9, atol=0.0)
    assert np.allclose(dz2[:, 1], dz[:, 1], rtol=1e-9, atol=0.0)


def _contact(elements=4):
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["elements"] = elements
    from helpers import CONFIGS
    model = build_model(parse_config(raw, base_dir=CONFIGS))
    return model, build_contact(model, parse_config(raw, base_dir=CONFIGS).contact, lambda *_: None)


def _nearest_on_b(projector, k, xA, x_of, samples=(21, 81)):
    """min |x_A − Y| over B's surface of interface k (every element, ξ ∈ [−1, 1], t ∈ [0, T]):
    sampled, then polished by scipy's bounded L-BFGS-B from the best samples of every element."""
    inter = projector.interfaces[k]
    b, T = inter.b, inter.curve_b.t_end
    xs, ts = np.meshgrid(np.linspace(-1, 1, samples[0]), np.linspace(0, T, samples[1]))
    xs, ts = xs.ravel(), ts.ravel()
    best = np.inf
    for e in range(b.element_offset, b.element_offset + b.n_elements):
        def dist(z, e=e):
            Y = projector.surface(x_of, np.array([k]), np.array([e]), np.array([z[0]]), np.array([z[1] * T]))[0]
            return float(np.linalg.norm(xA - Y[0]))
        Y = projector.surface(x_of, np.full(len(xs), k), np.full(len(xs), e), xs, ts)[0]
        j = np.argmin(np.linalg.norm(xA - Y, axis=1))
        res = minimize(dist, [xs[j], ts[j] / T], method="L-BFGS-B", bounds=[(-1, 1), (0, 1)],
                       options={"ftol": 1e-15, "gtol": 1e-14})
        best = min(best, res.fun, np.linalg.norm(xA - Y[j]))
    return best


def _moved(shift):
    """The projector and points of ``_contact``'s contact, the reference positions' reader,
    every point's index and A's contact points moved rigidly by ``shift`` [m]."""
    model, contact = _contact()
    pj, pts = contact.projector, contact.points
    conn = model.connectivity()

    def x_of(els):
        return model.q0[conn[els]].reshape(len(els), SLOTS, 3)
    idx = np.arange(pts.n_points)
    xA = np.einsum("pa,pai->pi", pts.NA, x_of(pts.eA)) + np.asarray(shift)
    return pj, pts, x_of, idx, xA


@pytest.mark.parametrize("shift", [(0.012, 0.0, 0.0), (0.004, 0.003, -0.002), (-0.009, -0.0035, 0.0)])
def test_points_moved_far_find_the_nearest_surface_point(shift):
    """A's contact points moved rigidly far from their partners (up to 0.7 element along the
    tendon and 3.5 mm across, i.e. outside and deep inside B, where the closest-point Hessian
    is indefinite), projected from their reference partners in one evaluation: every projection
    converges, and every partner place on B is as near as the nearest point an independent
    minimiser finds on B's surface (sampling + L-BFGS-B, every element).  With the Levenberg
    steps of a solve's iterates (``metric_steps`` off) two of the three moves do not converge,
    as with the former projector: the case ``Contact.refresh_weights`` re-solves."""
    pj, pts, x_of, idx, xA = _moved(shift)
    pj.metric_steps = True           # as after a converged solve left a projection unconverged
    pr = pj.project(idx, xA, x_of)
    assert pr.converged
    found = np.linalg.norm(pr.d, axis=1)
    on_surface = pr.valid & (np.abs(pr.xiB) <= 1.0) & (pr.tB >= 0.0) & (pr.tB <= pj.t_end)
    assert on_surface.sum() > 0.25 * len(idx)
    sample = np.flatnonzero(on_surface)[::7]
    for p in sample:
        ref = _nearest_on_b(pj, pts.itf[p], xA[p], x_of)
        assert found[p] <= ref + 1e-9, (p, found[p], ref)


def test_a_step_cut_to_one_element_stays_a_descent_direction():
    """A Gauss–Newton step longer than an element in ξ is cut to |dξ| = 1; cutting ξ alone turns
    it, and for points far from B (|d| of millimetres past the curve's end, measured on the
    solver_default_2025 column at 89.5 N) the turned step can raise φ = ½|d|² to first order:
    halving it then never lowered φ and the projection stopped unconverged.  Such a step is
    shortened as a whole instead (the direction of dζ kept), so every accepted step descends."""
    from ancf_petsc.contact.descent import Backtracking
    Yz, Yzz, d = _surface_data(3, P=400)
    pinned = np.zeros(len(d), dtype=bool)
    dz, r = newton_step(Yz, Yzz, d, pinned)
    long = np.abs(dz[:, 0]) > 1.0
    cut = np.column_stack([np.clip(dz[:, 0], -1.0, 1.0), dz[:, 1]])
    turned = long & (np.einsum("pk,pk->p", r, cut) >= 0.0)
    assert turned.sum() > 0 and (long & ~turned).sum() > 0          # both cases are exercised
    P = len(d)
    search = Backtracking(np.zeros(P, dtype=np.int64), np.zeros(P), np.zeros(P), np.ones(P),
                          keep_direction=True)     # Gauss–Newton (Projector.metric_steps)
    search.accept(np.ones(P, dtype=bool), np.zeros(P, dtype=np.int64), np.zeros(P), np.zeros(P), d, dz, r)
    step = search.dz
    assert np.all(np.einsum("pk,pk->p", r, step) < 0.0) and np.all(search.descent < 0.0)
    assert np.all(np.abs(step[:, 0]) <= 1.0)
    assert np.allclose(step[turned], dz[turned] / np.abs(dz[turned, :1]), rtol=1e-14, atol=0.0)
    assert np.array_equal(step[~turned], cut[~turned])             # other steps as before


@pytest.mark.parametrize("shift", [(0.004, 0.003, -0.002), (-0.009, -0.0035, 0.0)])
def test_a_points_projection_does_not_depend_on_the_points_beside_it(shift):
    """A rank projects its own points in one batch, so a point's partner place must not depend on
    which points share its batch (the partition).  The descent used to run every point until all
    of its batch were done: a point done early took further steps, and a point off B (counted done,
    weight 0) wandered for as long as the others took, landing elsewhere; with the fade
    weights kept in the first solve from rest its gap counted (the unilateral 33103 column with
    one mixed beam: 2 and 3 ranks 23 % from the serial answer).  Moved far (points deep inside B
    and past it, some unconverged with the Levenberg steps of a solve's iterates), every point
    projected in one batch lands exactly where it lands projected alone."""
    pj, pts, x_of, idx, xA = _moved(shift)
    start = pj.state()
    batch = pj.project(idx, xA, x_of)
    together = pj.state()
    assert not batch.converged or not np.all(batch.valid)     # the hard cases are exercised
    pj.resume(start)
    for p in idx:
        pj.project(idx[p:p + 1], xA[p:p + 1], x_of)
    assert np.array_equal(pj.state(), together)


@pytest.mark.parametrize("shift, end", [((0.004, 0.003, -0.002), "start"), ((-0.009, -0.0035, 0.0), "start"),
                                        ((-0.009, -0.0035, 0.0), "end")])
def test_a_descent_stopped_at_the_clamp_of_the_curve_is_retried_from_the_checkpoint(shift, end):
    """The continuation of B's interface curve is clamped (``Projector.wrap``), and a descent
    that arrives at the clamp stops there however far B is.  From an iterate of a solve a point
    ran there (the unilateral 135 deg uniform stride: 4.78 mm, weight 0, though its closest point
    on B was 1.51 mm away), so the residual had two values and Newton stalled.  Such a point
    descends again from its checkpoint place and the nearer result is kept: every point whose
    projection started at the clamp ends there no farther than its converged projection from the
    checkpoint.  Without the second start 79 points of the second move stay up to 24 mm farther."""
    from ancf_petsc.contact.fade import CURVE_FADE_END
    pj, pts, x_of, idx, xA = _moved(shift)
    ref = pj.project(idx, xA, x_of)                   # from the checkpoint (the reference partners)
    e0, xi0, t0 = pj.saved_places(idx)
    t_start = (-CURVE_FADE_END if end == "start" else 1.0 + CURVE_FADE_END) * pj.t_end
    pj.resume(np.column_stack([e0, xi0, t_start]))
    pr = pj.project(idx, xA, x_of)
    stopped = pj.at_clamp(pts.itf, pr.tB)
    f = pj.closest(pts.itf, pj.t_end, xA, x_of, e0.copy(), xi0.copy(), t0.copy())
    judged = stopped & f.done
    assert judged.sum() >= 5
    far = np.linalg.norm(pr.d, axis=1) - np.linalg.norm(ref.d, axis=1)
    assert np.all(far[judged] <= 1e-12), far[judged].max()


def test_a_point_on_the_first_boundary_of_its_search_window_is_in_it():
    """A point pinned on a B element boundary is kept on the lower element at ξ = +1
    (``descend``); on the window's first boundary that is element lo − 1, the same place as lo at
    ξ = −1, and it is in the window.  Counted as lost, it failed the first SNES evaluation of the
    12-element unilateral walking stride's first frame at the very state the predictor had just
    accepted (one of 576 points, partner 3 at ξ = +1, window [4, 8])."""
    from ancf_petsc.contact.projection import outside_window
    lo, hi = np.full(7, 4), np.full(7, 8)
    eB = np.array([3, 3, 4, 8, 9, 9, 2])
    xiB = np.array([1.0, 0.999, -1.0, 1.0, -1.0, -0.999, 1.0])
    assert outside_window(eB, xiB, lo, hi).tolist() == [False, True, False, False, False, True, True]
