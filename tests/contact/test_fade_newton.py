"""``contact.fade: newton`` (contact/weights.py): the fade weights of points whose partners sit past
B's ends differentiated inside Newton's iteration, variationally (forces −Σ λ ∇ḡ with
ḡ = Φ (w g)).  The Jacobian, ∇w and ∇²w (the closest point's second-order sensitivity) included,
against central differences of the residual at states with partly weighted points, and its
symmetry; the slope and curvature of the weight against differences of ``end_weight``; ∇²(c·ζ)
against second differences of the projection; the default rule and config keys."""
import numpy as np
import pytest

from ancf_petsc.contact.fade import end_weight, end_weight_curvature, end_weight_slope
from contact.test_contact import achilles, perturbed_state
from helpers import assert_contact_jacobian, build_problem, contact_evaluation, press_where_penetrating


def band_samples(seed: int, t_range: tuple[float, float], n: int = 4000, T: float = 2.0):
    """Random partner places (ξ, t) over and around the fade bands of a curve of length ``T``,
    on first or last elements at random: (ξ, t, T per point, first, last)."""
    rng = np.random.default_rng(seed)
    xi, t = rng.uniform(-1.6, 1.6, n), rng.uniform(*t_range, n)
    first, last = rng.random(n) < 0.5, rng.random(n) < 0.5
    return xi, t, np.full(n, T), first, last


def test_weight_slope_is_the_derivative_of_the_end_weight():
    """∂w/∂ζ against central differences of ``end_weight`` on both fade bands (curve and beam
    ends) and off them."""
    xi, t, Tn, first, last = band_samples(0, (-0.7, 2.7))
    slope = end_weight_slope(xi, t, Tn, first, last)
    h = 1e-7
    d_xi = (end_weight(xi + h, t, Tn, first, last) - end_weight(xi - h, t, Tn, first, last)) / (2 * h)
    d_t = (end_weight(xi, t + h, Tn, first, last) - end_weight(xi, t - h, Tn, first, last)) / (2 * h)
    assert np.count_nonzero(slope[:, 0]) > 100 and np.count_nonzero(slope[:, 1]) > 100
    assert np.abs(slope[:, 0] - d_xi).max() < 1e-6 * np.abs(slope[:, 0]).max()
    assert np.abs(slope[:, 1] - d_t).max() < 1e-6 * np.abs(slope[:, 1]).max()


def test_weight_curvature_is_the_second_derivative_and_vanishes_at_the_band_edges():
    """∂²w/∂ζ² against central differences of ``end_weight_slope``; the quintic fade is C²: at
    both edges of a band (u = 0, 1) its slope and curvature are zero, so a partner place held
    at the end of a band has neither."""
    from ancf_petsc.contact.fade import fade, fade_curvature, fade_slope
    xi, t, Tn, first, last = band_samples(1, (-1.2, 3.2))
    curv = end_weight_curvature(xi, t, Tn, first, last)
    h = 1e-6
    for k, (dxi, dt) in enumerate(((h, 0.0), (0.0, h))):
        diff = (end_weight_slope(xi + dxi, t + dt, Tn, first, last)
                - end_weight_slope(xi - dxi, t - dt, Tn, first, last)) / (2 * h)
        assert np.abs(curv[:, k] - diff).max() < 1e-5 * np.abs(curv).max()
    assert np.count_nonzero(curv[:, 1, 1]) > 100 and np.count_nonzero(curv[:, 0, 0]) > 100
    for u in (0.0, 1.0):
        assert fade_slope(np.array([u]))[0] == 0.0 and fade_curvature(np.array([u]))[0] == 0.0
    assert fade(np.array([0.0, 1.0])).tolist() == [1.0, 0.0]


def test_second_order_sensitivity_of_the_closest_point():
    """vᵀ ∇²(c·ζ) v (gap.closest_point_hessian) against second differences of the partner places
    ζ(q ± h v) of every point, at a deformed state: the surface's third derivatives, ∂H/∂q and
    the bodies' mixed terms all enter."""
    from ancf_petsc.contact.blocks import state_nodes
    from ancf_petsc.contact.gap import closest_point_hessian
    P, _ = build_problem(achilles(contact={"mode": "sliding"}))
    c = P.contact
    X, free = fade_state(P)
    saved = c.projector.state().copy()

    def places(Y):
        c.projector.set_state(saved)
        c._cache = None
        st = contact_evaluation(P, Y)
        return st, np.column_stack([st.pr.xiB, st.pr.tB])

    st, z0 = places(X)
    keep = st.weight > 0.0                        # partner places not held at a band's end
    rng = np.random.default_rng(5)
    cw = rng.standard_normal((len(z0), 2))
    from ancf_petsc.contact.projection import surface_third
    NBzz, Yzzz = surface_third(c.projector, state_nodes(c, st), c.points.itf[st.pr.idx], st.pr.eB,
                               st.pr.xiB, st.pr.tB)
    hess = closest_point_hessian(st.pr, cw, NBzz, Yzzz)
    v = X.duplicate()
    v.setArray(rng.standard_normal(X.getLocalSize()) * free * 1e-6)
    h = 4e-2          # second differences: the projection's tolerance (1e-11) sets the floor
    vl = v.getArray()
    Xp, Xm = X.copy(), X.copy()
    Xp.axpy(h, v)
    Xm.axpy(-h, v)
    zp, zm = places(Xp)[1], places(Xm)[1]
    same = keep & (places(Xp)[0].pr.eB == st.pr.eB) & (places(Xm)[0].pr.eB == st.pr.eB)
    second = np.einsum("pa,pa->p", cw, zp - 2 * z0 + zm) / h ** 2
    conn = c.conn
    dofs = np.concatenate([(18 * conn[c.points.eA[st.pr.idx]][:, :, None] + np.arange(18)).reshape(-1, 54),
                           (18 * conn[st.pr.eB][:, :, None] + np.arange(18)).reshape(-1, 54)], axis=1)
    vv = vl[dofs]
    analytic = np.einsum("pj,pjk,pk->p", vv, hess, vv)
    assert same.sum() > 80
    scale = np.abs(analytic[same]).max()
    assert np.abs(analytic[same] - second[same]).max() < 1e-4 * scale


def fade_state(P, seed=3):
    """A deformed state (with multipliers ~1e-5 m) whose partner places sit in the fade bands:
    the soleus (B of two interfaces) shortened by 16 %, the medial gastrocnemius by 8 % (so that
    A's end points lie past B's beam ends) and the soleus moved across by 1 mm (some past the
    interface curves' ends)."""
    X, free = perturbed_state(P, 2e-6, seed, multipliers=1e-5)
    q = X.getArray().reshape(-1, 6, 3)
    for k, b in enumerate(P.model.beams):
        nodes = b.node_offset + np.arange(b.n_nodes)
        q[nodes, 0, 0] *= 1.0 - 0.08 * (2 - k)
        if k == 0:
            q[nodes, 0, :] += np.array([0.0, -7e-4, 7e-4])
    X.setArray(q.ravel())
    return X, free


@pytest.mark.parametrize("mode,forces", [("sliding", "variational"), ("unilateral", "variational"),
                                         ("unilateral", "pointwise")])
def test_jacobian_with_partly_weighted_points_matches_finite_differences(mode, forces):
    """J v against central differences of F (nodal vectors and multipliers) at a state where
    17 points are partly weighted (0 < w < 1, ∇w ≠ 0, on both kinds of fade band) and carry
    pressure; J is symmetric with variational forces (the Hessian of the Lagrangian) and not with
    pointwise ones (−Σ τ_p ∇g_p: the rows keep ∇(w g), the forces' columns only w ∇g)."""
    P, PETSc = build_problem(achilles(contact={"mode": mode, "fade": "newton", "fade_forces": forces}))
    c = P.contact
    assert c.symmetric == P.symmetric == (forces == "variational")
    c.weights.differentiated = True       # as from the second solve of an increment on (weights.py)
    P.load_factor = 50.0
    X, free = fade_state(P)
    st = contact_evaluation(P, X)
    part = (st.weight > 0.0) & (st.weight < 1.0)
    T = c.projector.t_end[st.pr.idx]
    o_t = np.maximum(-st.pr.tB, st.pr.tB - T) / T
    assert part.sum() >= 10 and np.any(part & (o_t > 0.25)) and np.any(part & (o_t <= 0.25))
    assert np.count_nonzero(st.pressure[part]) >= 10
    if mode == "unilateral":
        press_where_penetrating(P, X, st)
    act = contact_evaluation(P, X).active
    if mode == "unilateral":
        assert 0 < act.sum() < len(act)
    Jd = assert_contact_jacobian(P, X, free, act, h=1e-7)
    asymmetry = np.abs(Jd - Jd.T).max() / np.abs(Jd).max()
    assert asymmetry < 1e-12 if forces == "variational" else asymmetry > 1e-9


def test_weight_hessians_of_unpressed_points_are_left_out():
    """``FadeDerivatives(loaded=…)``: the ∇²w of a band point with no pressure (its stiffness
    p g ∇²w is zero) is not computed; the loaded points' are those of the whole band, to the
    last bit, and ``shape_third_on_curve``'s N_ζζ is ``shape_on_curve``'s."""
    from ancf_petsc.contact.blocks import state_nodes
    from ancf_petsc.contact.surface import shape_on_curve, shape_third_on_curve
    from ancf_petsc.contact.weights import FadeDerivatives
    P, _ = build_problem(achilles(contact={"mode": "sliding", "fade": "newton"}))
    c = P.contact
    X, _ = fade_state(P)
    st = contact_evaluation(P, X)
    nodes = state_nodes(c, st)
    whole = FadeDerivatives(c.projector, st.pr).hessians(nodes)
    loaded = np.random.default_rng(2).random(len(st.pr.idx)) < 0.5
    fd = FadeDerivatives(c.projector, st.pr, loaded=loaded)
    part = fd.hessians(nodes)
    on = loaded[fd.band]
    assert len(fd.band) >= 10 and 0 < on.sum() < len(on)
    assert np.array_equal(part[on], whole[on]) and not np.any(part[~on])
    assert np.abs(whole[on]).max() > 0.0
    rng = np.random.default_rng(4)
    xi, (S, S1, S2, S3) = rng.uniform(-1, 1, 50), (rng.standard_normal((50, 2)) * 1e-3 for _ in range(4))
    assert np.array_equal(shape_third_on_curve(xi, S, S1, S2, S3)[0], shape_on_curve(xi, S, S1, S2)[2])


def test_fade_key_errors_name_the_key_path():
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.config.values import ConfigError
    from helpers import CONFIGS

    def contact(**keys):
        return parse_config(achilles(contact=keys), base_dir=CONFIGS).contact

    elastic = {"law": "elastic", "stiffness": 1e10}
    coulomb = {"law": "coulomb", "friction": 0.3}
    for keys, message in [({"fade": "exact"}, "contact.fade: must be one of settle, newton"),
                          ({"fade": "newton", "tangential": elastic}, "contact.fade: newton differentiates .* use settle"),
                          ({"fade_forces": "exact"}, "contact.fade_forces: must be one of auto, variational, pointwise"),
                          ({"fade_forces": "variational", "tangential": coulomb},
                           "contact.fade_forces: a tangential law's forces are pointwise")]:
        with pytest.raises(ConfigError, match="^" + message):
            contact(mode="sliding", **keys)
    # auto: variational, pointwise from a level those cannot reach (solving/fade_switch.py)
    assert (contact(mode="sliding").fade, contact(mode="sliding").fade_forces) == ("newton", "auto")
    assert contact(mode="sliding", tangential=elastic).fade == "settle"
    # friction_blocks.py: Coulomb differentiates its weights, with pointwise forces
    assert (contact(mode="sliding", tangential=coulomb).fade, contact(mode="sliding", tangential=coulomb).fade_forces) \
        == ("newton", "pointwise")
    assert contact(mode="sliding", tangential=coulomb, fade_forces="auto").fade_forces == "pointwise"


def test_the_differentiated_weights_keep_sbaij_and_ldlt():
    """The variational weights leave the Jacobian symmetric: SBAIJ, MUMPS LDLᵀ and its inertia."""
    from ancf_petsc.linalg.choice import choose
    from ancf_petsc.linalg.options import default_options, matrix_type
    P, _ = build_problem(achilles(contact={"mode": "unilateral", "fade": "newton"}))
    assert matrix_type(P.model, "auto", {}, symmetric=P.symmetric) == "sbaij"
    assert default_options(P.symmetric)["pc_type"] == "cholesky"
    assert choose("auto", P.model, P.contact, {})[0] == "direct"


def test_weight_derivatives_fade_in_with_the_projection_conditioning():
    """``weights.conditioned``: the share of a point's ∇w and ∇²w in the forces and the
    Jacobian is 1 from WELL_POSED up (the derivatives whole, as before the share existed), 0 from
    ILL_POSED down, monotone and C¹ in between, so that a point crossing the old single threshold
    (0.5) no longer switches its −p g ∇w force on or off: the residual is continuous."""
    from ancf_petsc.contact.weights import ILL_POSED, WELL_POSED, conditioned
    width = WELL_POSED - ILL_POSED
    assert 0.0 < ILL_POSED < WELL_POSED <= 0.5
    kappa = np.linspace(-0.5, 1.5, 200001)
    s = conditioned(kappa)
    assert np.all(s[kappa >= WELL_POSED] == 1.0) and np.all(s[kappa <= ILL_POSED] == 0.0)
    assert np.all(np.diff(s) >= -1e-14)                            # monotone (to rounding)
    slope = np.gradient(s, kappa) * width                          # per band width
    assert np.abs(np.diff(s)).max() < 0.01                         # no jump anywhere
    for edge in (ILL_POSED, WELL_POSED):                           # C¹ at both edges
        assert np.abs(slope[np.abs(kappa - edge) < 0.01 * width]).max() < 0.01
    assert s[np.argmin(np.abs(kappa - 0.5 * (ILL_POSED + WELL_POSED)))] == pytest.approx(0.5, abs=1e-3)
