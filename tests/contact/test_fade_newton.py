"""``contact.fade: newton`` (contact/weights.py): the fade weights of points whose partners sit past
B's ends differentiated inside Newton's iteration.  The Jacobian, ∇w = (∂w/∂ζ) ∂ζ/∂q included,
against central differences of the residual at states with partly weighted points; the slope of
the weight against differences of ``end_weight``; the unsymmetric Jacobian's solver; config keys."""
import numpy as np
import pytest

from ancf_petsc.contact.projection import end_weight, end_weight_slope
from contact.test_contact import achilles, perturbed_state
from helpers import assert_contact_jacobian, build_problem, contact_evaluation, press_where_penetrating


def test_weight_slope_is_the_derivative_of_the_end_weight():
    """∂w/∂ζ against central differences of ``end_weight`` on both fade bands (curve and beam
    ends) and off them."""
    rng = np.random.default_rng(0)
    n, T = 4000, 2.0
    xi, t = rng.uniform(-1.6, 1.6, n), rng.uniform(-0.7, 2.7, n)
    first, last = rng.random(n) < 0.5, rng.random(n) < 0.5
    Tn = np.full(n, T)
    slope = end_weight_slope(xi, t, Tn, first, last)
    h = 1e-7
    d_xi = (end_weight(xi + h, t, Tn, first, last) - end_weight(xi - h, t, Tn, first, last)) / (2 * h)
    d_t = (end_weight(xi, t + h, Tn, first, last) - end_weight(xi, t - h, Tn, first, last)) / (2 * h)
    assert np.count_nonzero(slope[:, 0]) > 100 and np.count_nonzero(slope[:, 1]) > 100
    assert np.abs(slope[:, 0] - d_xi).max() < 1e-6 * np.abs(slope[:, 0]).max()
    assert np.abs(slope[:, 1] - d_t).max() < 1e-6 * np.abs(slope[:, 1]).max()


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


@pytest.mark.parametrize("mode", ["sliding", "unilateral"])
def test_jacobian_with_partly_weighted_points_matches_finite_differences(mode):
    """J v against central differences of F (nodal vectors and multipliers) at a state where
    17 points are partly weighted (0 < w < 1, ∇w ≠ 0, on both kinds of fade band) and carry
    pressure; J is unsymmetric there, and with the fade weights kept (settle) it is not exact."""
    P, PETSc = build_problem(achilles(contact={"mode": mode, "fade": "newton"}))
    c = P.contact
    assert not c.symmetric and not P.symmetric
    P.load_factor = 50.0
    X, free = fade_state(P)
    st = contact_evaluation(P, X)
    part = (st.weight > 0.0) & (st.weight < 1.0)
    T = c.projector.t_end[st.pr.idx]
    o_t = np.maximum(-st.pr.tB, st.pr.tB - T) / T
    assert part.sum() >= 15 and np.any(part & (o_t > 0.25)) and np.any(part & (o_t <= 0.25))
    assert np.count_nonzero(st.pressure[part]) >= 10
    if mode == "unilateral":
        press_where_penetrating(P, X, st)
    act = contact_evaluation(P, X).active
    if mode == "unilateral":
        assert 0 < act.sum() < len(act)
    Jd = assert_contact_jacobian(P, X, free, act, h=1e-7)
    assert np.abs(Jd - Jd.T).max() > 1e-3 * np.abs(Jd).max()


def test_fade_key_errors_name_the_key_path():
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.config.values import ConfigError
    from helpers import CONFIGS
    with pytest.raises(ConfigError, match="^contact.fade: must be one of settle, newton"):
        parse_config(achilles(contact={"mode": "sliding", "fade": "exact"}), base_dir=CONFIGS)
    raw = achilles(contact={"mode": "sliding", "fade": "newton",
                            "tangential": {"law": "coulomb", "friction": 0.3}})
    with pytest.raises(ConfigError, match="^contact.fade: newton differentiates .* use settle"):
        parse_config(raw, base_dir=CONFIGS)
    assert parse_config(achilles(contact={"mode": "sliding"}), base_dir=CONFIGS).contact.fade == "settle"


def test_the_unsymmetric_jacobian_takes_aij_and_lu_as_friction_does():
    from ancf_petsc.errors import InputError
    from ancf_petsc.linalg.choice import choose
    from ancf_petsc.linalg.options import default_options, matrix_type
    P, _ = build_problem(achilles(contact={"mode": "unilateral", "fade": "newton"}))
    assert matrix_type(P.model, "auto", {}, symmetric=P.symmetric) == "aij"
    assert default_options(P.symmetric)["pc_type"] == "lu"
    assert choose("auto", P.model, P.contact, {})[0] == "direct"
    with pytest.raises(InputError, match="fade: newton"):
        matrix_type(P.model, "auto", {"pc_type": "cholesky"}, symmetric=P.symmetric)
