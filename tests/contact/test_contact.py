"""Contact with Lagrange multipliers: consistent saddle-point Jacobians (finite differences), the
gap Hessian against differences of the gap gradient, reference state, laws and the pressure space."""
import numpy as np
import pytest

from helpers import load_raw
from ancf_petsc.petsc.contact_reports import contact_gaps
from helpers import assert_contact_jacobian, build_problem as _problem, contact_evaluation, press_where_penetrating


def achilles(psi=45.0, elements=2, contact=None):
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["geometry"]["twist_deg"] = psi
    for b in raw["beams"]:
        b["elements"] = elements
    if contact is not None:
        raw["contact"] = contact
    return raw


def perturbed_state(P, scale, seed, multipliers=0.0):
    """q0 plus noise on the free nodal DOFs, and multipliers of size ``multipliers`` [m]."""
    rng = np.random.default_rng(seed)
    X = P.X
    P.q0.copy(X)
    free = ~P.fixed_mask
    q = X.getArray().reshape(-1, 6, 3)
    noise = rng.standard_normal(q.shape)
    noise[:, 1:3] *= 20.0          # slopes are O(1), positions O(L)
    noise[:, 3:] *= 200.0
    noise[~P.owned_physical] = multipliers / scale * rng.standard_normal(q[~P.owned_physical].shape)
    X.setArray(X.getArray() + scale * noise.ravel() * free)
    return X, free


MODES = {"sliding": {"mode": "sliding"},
         "sliding-linear": {"mode": "sliding", "curve_points": 2, "projection": {"axial": 2, "curve": 1}},
         "unilateral": {"mode": "unilateral"},
         # clamped roots: the supported ends' functions folded into their neighbours
         "sliding-clamped": {"mode": "sliding"},
         "unilateral-clamped": {"mode": "unilateral"}}


def clamped(raw):
    """The config with every support clamped (the 3D solid comparisons' supports)."""
    for bc in raw["boundary_conditions"]:
        bc["fix"] = "clamped"
    return raw


def _active(P, X):
    return contact_evaluation(P, X).active


@pytest.mark.parametrize("mode", list(MODES))
def test_contact_jacobian_matches_finite_differences(mode):
    """J v against central differences of F along random directions (nodal vectors and
    multipliers), at a deformed state with non-zero pressures; J is symmetric."""
    raw = achilles(contact=MODES[mode])
    P, PETSc = _problem(clamped(raw) if mode.endswith("clamped") else raw)
    assert P.contact.space.n_multipliers == 3 * (5 - mode.endswith("clamped")) * 2
    P.load_factor = 50.0
    X, free = perturbed_state(P, 2e-6, 3, multipliers=1e-5)
    act = _active(P, X)
    if mode.startswith("unilateral"):
        # a state the law keeps: pressure where the bodies penetrate, random pulls elsewhere
        # (released, and not penetrating: they stay released)
        press_where_penetrating(P, X, contact_evaluation(P, X))
        act = _active(P, X)
        assert 0 < act.sum() < len(act)         # both kinds of multiplier are present
        assert np.array_equal(_active(P, X), act)
    Jd = assert_contact_jacobian(P, X, free, act, h=1e-6)
    assert np.abs(Jd - Jd.T).max() <= 1e-9 * np.abs(Jd).max()


def test_gap_hessian_matches_differences_of_the_gradient():
    """∇²g (gap.py, no division by g) against central differences of ∇g = Dᵀn at a state
    where the bodies are apart and pressed together."""
    from ancf_petsc.contact.gap import gap_gradient, gap_hessian_factors
    P, _ = _problem(achilles())
    c = P.contact
    X, _ = perturbed_state(P, 5e-6, 11)
    xl = P.exchange.local_state(X).copy()
    st = c.evaluate(xl, P.exchange.needed)
    assert np.any(st.pr.g > 1e-7) and np.any(st.pr.g < -1e-7)
    W, C = gap_hessian_factors(st.pr)
    H = -np.einsum("pia,pab,pjb->pij", W, C, W)
    rng = np.random.default_rng(2)
    idx = st.pr.idx
    eA, eB = c.points.eA[idx], st.pr.eB.copy()
    pos = lambda e: np.searchsorted(P.exchange.needed, c.conn[e])           # noqa: E731
    dofs = np.concatenate([(18 * pos(eA)[:, :, None] + np.arange(18)).reshape(len(idx), 54),
                           (18 * pos(eB)[:, :, None] + np.arange(18)).reshape(len(idx), 54)], axis=1)
    v = rng.standard_normal(xl.size) * 1e-3
    h = 1e-6
    grads = []
    for sgn in (1.0, -1.0):
        c.restore()
        c.projector.eB[idx], c.projector.xiB[idx], c.projector.tB[idx] = st.pr.eB, st.pr.xiB, st.pr.tB
        stp = c.evaluate((xl.reshape(-1) + sgn * h * v).reshape(xl.shape), P.exchange.needed)
        assert np.array_equal(stp.pr.eB, eB)
        grads.append(gap_gradient(stp.pr))
    fd = (grads[0] - grads[1]) / (2 * h)
    hv = np.einsum("pij,pj->pi", H, v[dofs])
    assert np.abs(hv - fd).max() < 1e-5 * np.abs(hv).max()


def test_reference_state_is_gap_free_and_stress_free():
    P, _ = _problem(achilles())
    P.load_factor = 0.0
    X = P.q0.copy()
    F = X.duplicate()
    P.residual(None, X, F)
    assert F.norm() < 1e-9
    gaps = contact_gaps(P, X)
    assert len(gaps) == 3 and all(g["max_gap"] < 1e-12 for g in gaps.values())


def test_gap_report_after_the_exchange_is_rebuilt():
    """``contact_gaps`` evaluates with the exchange's node blocks as ``GhostExchange.evaluate``
    left them: it had taken them before, so when the exchange was rebuilt first (a projection
    that reached blocks the rank did not hold) it indexed past the local array (2 ranks, the 165°
    soleus-biased unilateral column after 2500 N: an IndexError on one rank).  Here the
    exchange starts without the contact's blocks (multipliers ~1e-5 m), so the report rebuilds it
    and must give what it gives with the exchange built."""
    P, _ = _problem(achilles(contact={"mode": "sliding"}))
    X, _ = perturbed_state(P, 1e-6, 4, multipliers=1e-5)
    built = contact_gaps(P, X)
    P.exchange.build(np.zeros(0, dtype=np.int64))
    rebuilt = contact_gaps(P, X)
    assert np.all(np.isin(P.contact.required_nodes(), P.exchange.needed))
    assert built.keys() == rebuilt.keys() and len(built) == 3
    for name in built:
        assert built[name]["max_pressure"] != 0.0
        assert rebuilt[name] == pytest.approx(built[name], rel=1e-12), name   # projections to rounding


@pytest.mark.parametrize("elements,projection", [(4, {"axial": 2, "curve": 0}),
                                                 (4, {"axial": 2, "curve": 1}),
                                                 (2, {"axial": 1, "curve": 1}),
                                                 (4, {"axial": 0, "curve": 0})])
def test_multiplier_space_is_the_trace_space_and_has_full_rank(elements, projection):
    """Continuous piecewise-Bernstein functions along A (one per node for degree 2) times
    Bernstein across: (degree·E + 1)(curve + 1) multipliers per interface (the paper's supports
    let the sections stretch: no end is folded), Φ's rows sum to one, and the constraint
    gradients are independent at the reference state (a per-element space would repeat what
    continuity says, and its multipliers would not be unique)."""
    P, PETSc = _problem(achilles(elements=elements, contact={"mode": "sliding", "curve_points": 2,
                                                             "projection": projection}))
    c, sp = P.contact, P.contact.space
    ka, kc = projection["axial"], projection["curve"]
    n_axial = ka * elements + 1 if ka > 0 else elements
    assert sp.n_multipliers == 3 * n_axial * (kc + 1)
    assert np.allclose(np.asarray(sp.Phi.sum(axis=1)).ravel(), 1.0)
    pts = c.points
    assert np.isclose(sp.area.sum(), pts.w.sum())                  # the functions sum to one
    assert np.all(sp.slot < 18) and np.all(sp.padding().sum(axis=1) < 18)
    P.jacobian(None, P.q0, P.J, P.J)
    Jd = P.J.convert("dense", PETSc.Mat()).getDenseArray()
    m = P.layout.petsc_dofs(c.multiplier_dofs())
    q = np.flatnonzero(~P.fixed_mask[:18 * P.model.n_nodes])
    sv = np.linalg.svd(Jd[np.ix_(m, q)], compute_uv=False)
    # a repeated constraint gives ~1e-16; linear across the interface is only weakly
    # controlled next to the supported sections (~5e-6), the mean across is better (~1e-4)
    assert sv[-1] > 1e-8 * sv[0], sv[-1] / sv[0]


def _constraint_conditioning(P, PETSc) -> float:
    """σ_min / σ_max of the constraint gradients over the free DOFs at the reference state."""
    P.jacobian(None, P.q0, P.J, P.J)
    Jd = P.J.convert("dense", PETSc.Mat()).getDenseArray()
    m = P.layout.petsc_dofs(P.contact.multiplier_dofs())
    q = np.flatnonzero(~P.fixed_mask[:18 * P.model.n_nodes])
    sv = np.linalg.svd(Jd[np.ix_(m, q)], compute_uv=False)
    return sv[-1] / sv[0]


@pytest.mark.parametrize("projection,keep_max,merge_min", [({"axial": 2, "curve": 1}, 3e-7, 1e-4),
                                                           ({"axial": 2, "curve": 0}, 1e-3, 3e-2)])
def test_clamped_ends_fold_the_function_that_repeats_the_supports(projection, keep_max, merge_min):
    """Both bodies clamped at x = 0: the trace space's end function nearly repeats the supports
    (σ_min/σ_max 1e-7 linear across, 2e-4 mean across); folded into its neighbour (φ₁ + φ₀ ≥ 0,
    the partition of unity kept) the constraints are independent (2e-4, 0.1): one function fewer
    per interface and function across at the clamped end, none at the free far end.  With the
    paper's supports (``reduced``: the sections may stretch) nothing is folded."""
    from ancf_petsc.contact.interfaces import supported_ends
    rates = {}
    for ends in ("keep", "merge"):
        raw = achilles(elements=4, contact={"mode": "sliding", "projection": dict(projection, supported_ends=ends)})
        reduced, _ = _problem(raw)
        assert supported_ends(reduced.model, reduced.contact.interfaces).sum() == 0
        for bc in raw["boundary_conditions"]:
            bc["fix"] = "clamped"
        P, PETSc = _problem(raw)
        assert supported_ends(P.model, P.contact.interfaces).tolist() == [[True, False]] * 3
        sp = P.contact.space
        assert sp.n_multipliers == 3 * (9 - (ends == "merge")) * (projection["curve"] + 1)
        assert np.allclose(np.asarray(sp.Phi.sum(axis=1)).ravel(), 1.0)
        assert np.isclose(sp.area.sum(), P.contact.points.w.sum())
        assert sp.Phi.data.min() > -1e-15                      # non-negative functions
        rates[ends] = _constraint_conditioning(P, PETSc)
    assert rates["keep"] < keep_max and rates["merge"] > merge_min, rates


def test_removed_penalty_keys_are_config_errors():
    from ancf_petsc.config.values import ConfigError
    from ancf_petsc.config.parse import parse_config
    from helpers import CONFIGS
    for key, value in (("penalty", 1e9), ("penalty_scale", 10), ("smoothing", 0.0), ("augmented", True)):
        raw = achilles(contact={"mode": "sliding", key: value})
        with pytest.raises(ConfigError, match=f"contact.{key}: contact is enforced exactly"):
            parse_config(raw, base_dir=CONFIGS)
    with pytest.raises(ConfigError, match="contact.projection: a multiplier per point"):
        parse_config(achilles(contact={"projection": "pointwise"}), base_dir=CONFIGS)


def test_one_contact_point_along_an_element_is_refused():
    """contact.axial_points: 1 holds the gap only at each element's middle: the pressed strips
    (2 elements, frictionless) sank 0.48 mm into the base at 80 % of the load with no
    penetration reported, then failed; at 4 elements they completed 8.2 x too deep."""
    from ancf_petsc.config.values import ConfigError
    from ancf_petsc.config.parse import parse_config
    from helpers import CONFIGS
    with pytest.raises(ConfigError) as err:
        parse_config(achilles(contact={"mode": "sliding", "axial_points": 1}), base_dir=CONFIGS)
    assert str(err.value) == ("contact.axial_points: must be >= 2: one contact point along each element "
                              "holds the gap only at its middle, and the beams interpenetrate unseen "
                              "between (give 2 or more; the default is 3); got 1"), str(err.value)


@pytest.mark.parametrize("case, key, words", [
    ("no shared curve", "contact", "no two beam outlines share a curve"),
    ("unknown curve", "contact.interfaces[0].curve", "share no outline curve named 'nosuch' .they share: "
     "mg_sol.; .*; got 'nosuch'"),
    # two curves, one missing: the key and the outline's curves name it (it said "no curve 'mg_sol'
    # in soleus's outline or 'lg_sol' in medial_gastrocnemius's", mg_sol being there)
    ("unknown curve_b", "contact.interfaces[0].curve_b", "no curve 'lg_sol' in medial_gastrocnemius's "
     "outline .its curves: lg_mg, mg_outer, mg_sol.; got 'lg_sol'"),
    ("elements differ", "beams[1].elements", "3 element.s. against 2 of soleus .beams.0..elements., its "
     "contact partner across curve mg_sol: the beams of an interface need the same number of elements "
     ".*give both 3"),
    # the same curve in either order of a and b: its constraints repeated (the tendon at 2 elements
    # failed at 312 of 400 N), or one copy's arbitrary share of the force reported (1613 N, not -189 N)
    # one point across a straight face for the two linear functions across: both held its middle
    # only (two bars side by side: their transverse end displacement 10 % off, no error)
    ("one point across", "contact.curve_points", "interface interface .base.slider.: 1 contact point.s. "
     "across .1 piece.s. of curve interface x 1. determine fewer than its 2 pressure functions across "
     ".*give contact.curve_points: 2 or more, or fewer functions; got 1"),
    ("listed twice", "contact.interfaces[1]", "interface mg_sol .soleus.medial_gastrocnemius. is listed "
     "twice .also contact.interfaces.0..: list each shared curve of two beams once.*; got .a: "
     "medial_gastrocnemius, b: soleus, curve: mg_sol."),
    # a gap or an overlap at rest named neither the interface nor its entry (key "contact")
    ("curves apart", "contact.interfaces[1]", "do not match in the reference configuration .interface "
     "upper_interface .core.top.: largest gap 2.000e-03 m."),
    ("overlap", "contact.interfaces[1]", "interpenetrate in the reference configuration .interface "
     "upper_interface .core.top.: gap -1.000e-04 m."),     # named by the first beam's curve (core's)
])
def test_contact_setup_errors_name_their_config_key(case, key, words, tmp_path):
    """The contact layer's setup errors reach the user as config errors naming the key
    (model/contact_setup.py is the one boundary that knows the keys)."""
    import ancf_petsc
    from helpers import CONFIGS, two_beam_twisted
    if case == "no shared curve":
        raw = dict(two_beam_twisted(), contact={})
    elif case == "one point across":
        raw = load_raw("friction_pressed_strips.yaml")
        raw["contact"]["curve_points"] = 1
    elif case == "listed twice":
        raw = achilles(contact={"interfaces": [{"a": "soleus", "b": "medial_gastrocnemius"},
                                               {"a": "medial_gastrocnemius", "b": "soleus", "curve": "mg_sol"}]})
    elif case == "unknown curve_b":
        raw = achilles(contact={"interfaces": [{"a": "soleus", "b": "medial_gastrocnemius", "curve": "mg_sol",
                                                "curve_b": "lg_sol"}]})
    elif case in ("curves apart", "overlap"):
        raw = load_raw("shear_lag_sandwich.yaml")
        top = raw["beams"][2]["section"]["curves"]
        top[0]["name"] = "top_low"                        # the top strip's lower face
        if case == "overlap":                             # the top strip 0.1 mm into the core
            for c in top:
                c["points"] = [[x, y - 1e-4] for x, y in c["points"]]
        faces = ("top_low", "upper_interface") if case == "overlap" else ("upper_interface", "top_face")
        raw["contact"] = {"mode": "unilateral" if case == "overlap" else "sliding", "interfaces": [
            {"a": "core", "b": "bottom", "curve": "lower_interface"},
            {"a": "top", "b": "core", "curve": faces[0], "curve_b": faces[1]} if case == "overlap" else
            {"a": "core", "b": "top", "curve": faces[0], "curve_b": faces[1]}]}
    elif case == "unknown curve":
        raw = achilles(contact={"interfaces": [{"a": "soleus", "b": "medial_gastrocnemius", "curve": "nosuch"}]})
    else:
        raw = achilles()
        raw["beams"][1]["elements"] = 3
    spec = ancf_petsc.parse_config(raw, base_dir=CONFIGS)
    spec.output.dir = str(tmp_path)          # not the config's results/<name>: the cases run side by side
    with pytest.raises(ancf_petsc.ConfigError, match=rf"^{key.replace('[', '.').replace(']', '.')}: .*{words}"):
        ancf_petsc.solve(spec, log=lambda *_: None)


def _axial_coordinate(points):
    """s ∈ [0, 1] along A of every contact point (its segment's place on its interface)."""
    s = np.empty(points.n_points)
    for k in np.unique(points.seg_itf):
        segs = np.flatnonzero(points.seg_itf == k)
        for e, sg in enumerate(segs):
            sl = points.seg_start[sg] + np.arange(points.seg_size[sg])
            s[sl] = (e + 0.5 * (points.xi[sl] + 1.0)) / len(segs)
    return s


def test_grouped_multiplier_space_is_the_coarse_meshs_space():
    """``build_space(group=G)`` on E·G elements spans the functions of the E-element space (the
    diagnostic of scripts/solid_contact_variants.py): the same multipliers with the same
    moments ∫φ_k s^i τ^j dA (s along A, τ across; exact quadrature on both meshes)."""
    from ancf_petsc.contact.multipliers import build_space
    # ψ = 0: the straight prisms are exact on both meshes (a pretwist is interpolated, and the
    # area weights of the two meshes then differ by ~1e-5)
    coarse, _ = _problem(achilles(psi=0.0, elements=2, contact={"mode": "sliding"}))
    fine, _ = _problem(achilles(psi=0.0, elements=8, contact={"mode": "sliding"}))
    cf, ff = coarse.contact, fine.contact
    from ancf_petsc.contact.interfaces import supported_ends
    grouped = build_space(ff.points, ff.interfaces, ff.spec.projection, ff.stiffness, group=4,
                          merged=supported_ends(fine.model, ff.interfaces))
    assert grouped.n_multipliers == cf.space.n_multipliers < ff.space.n_multipliers

    def moments(space, points):
        W = space.Phi.multiply(space.area[:, None]).tocsr()          # w_p φ_k(p)
        s = _axial_coordinate(points)
        return np.stack([W @ (s ** i * points.tau ** j) for i in range(3) for j in range(2)], axis=1)

    assert np.allclose(moments(grouped, ff.points), moments(cf.space, cf.points), rtol=1e-9, atol=0)
    with pytest.raises(ValueError):
        build_space(ff.points, ff.interfaces, ff.spec.projection, ff.stiffness, group=3)
