"""Coulomb friction with the fade weights differentiated (``contact.fade: newton``, the default
with friction since issue 38's friction columns; contact/friction_blocks.py ``_weight_columns``):
the Jacobian against central differences of the residual at a state where points are partly
weighted, press, stick and slide; the weights' settle rule's extra solves it replaces."""
import numpy as np
import pytest

from contact.test_fade_newton import fade_state
from contact.test_contact import achilles
from helpers import build_problem, contact_evaluation, jacobian_and_difference

FRICTION = {"law": "coulomb", "friction": 0.3}


def _with_history(P, X, seed: int = 3):
    """An increment begun 0.1 µm of tangential slip away (anchor) and tangential multipliers of
    half or twice their bound μ ẑ, in the tangent plane of n̄: some functions stick, others slide
    (as tests/contact/test_interface_shear.py's ``_state``)."""
    rng = np.random.default_rng(seed)
    c, term = P.contact, P.contact.terms[0]
    ev = contact_evaluation(P, X).terms[term.name]
    n = contact_evaluation(P, X).pr.n
    s = rng.standard_normal(ev.d.shape)
    s -= np.einsum("pi,pi->p", s, n)[:, None] * n
    term.state["anchor"][c.local] = ev.d - 1e-7 * s / np.linalg.norm(s, axis=1)[:, None]
    u = rng.standard_normal(ev.y.shape)
    u -= np.einsum("ki,ki->k", u, ev.nbar)[:, None] * ev.nbar
    size = np.where(ev.bound > 0.0, ev.bound, 1e-9) * rng.choice([0.5, 2.0], len(ev.y))
    X.getArray()[term.tdof[c.mults].ravel()] = (size[:, None] * u / np.linalg.norm(u, axis=1)[:, None]).ravel()
    c._cache = None


def test_the_default_fade_rule_with_friction_is_newton():
    from ancf_petsc.config.parse import parse_config
    from helpers import CONFIGS
    raw = achilles(contact={"mode": "sliding", "tangential": dict(FRICTION)})
    assert parse_config(raw, base_dir=CONFIGS).contact.fade == "newton"


def test_friction_jacobian_with_partly_weighted_points_matches_finite_differences():
    """J v against central differences of F where ≥ 10 pressing points are partly weighted
    (0 < w < 1, ∇w ≠ 0) and functions both stick and slide: the weights enter the slips U_k,
    the mean normals m_k, the bounds μ ẑ_k and the forces k_s w P Y (friction_blocks.py)."""
    P, _ = build_problem(achilles(contact={"mode": "sliding", "tangential": dict(FRICTION)}))
    c = P.contact
    assert c.weights.rule == "newton"
    c.weights.differentiated = True       # as from the second solve of an increment on (weights.py)
    P.load_factor = 50.0
    X, free = fade_state(P)
    _with_history(P, X)
    st = contact_evaluation(P, X)
    ev = st.terms[c.terms[0].name]
    part = (st.weight > 0.0) & (st.weight < 1.0)
    assert part.sum() >= 10 and np.count_nonzero(st.pressure[part] * ev.positive[part]) >= 5
    assert ev.m_stick.sum() > 0 and ev.slide.sum() > 0
    P.jacobian(None, X, P.J, P.J)
    rng = np.random.default_rng(7)
    for _ in range(3):
        v = X.duplicate()
        v.setArray(rng.standard_normal(X.getLocalSize()) * free * 1e-3)
        # a sliding function's direction turns fast: its rows' central differences err as h²
        jv, fd, _, _ = jacobian_and_difference(P, X, v, 1e-8)
        err = np.abs(jv - fd)[free].max() / np.abs(jv).max()
        assert err < 1e-6, err


@pytest.mark.slow
def test_friction_column_levels_are_single_solves(tmp_path):
    """μ = 0.1, twist 90°, soleus-biased, 2 elements, to 1.2 kN (workflows/envelope.py's cell):
    with the weights differentiated each level is one Newton solve, 60 Newton iterations in all
    and at most 8 per level from 600 N on, no cut-back; with them settled between solves
    (``contact.fade: settle``, the default before) the points sliding into the fade bands cost
    2-4 re-solves per level: 87 iterations, 12-14 per level at 600-1000 N (measured).  The
    answers are the same equations' (the settled fixed point's, to its weight tolerance)."""
    from ancf_petsc.workflows.envelope import NEO, EnvelopeCell, cell_config
    from helpers import CONFIGS, run_inline
    levels = (30.0, 100.0, 200.0, 400.0, 600.0, 800.0, 1000.0, 1200.0)
    raw = cell_config(EnvelopeCell(NEO, 90, "soleus", "sliding", friction=0.1, elements=2, levels=levels))
    s = run_inline(raw, tmp_path / "newton", base_dir=CONFIGS)
    assert s["status"] == "completed" and s["steps"][-1]["load_factor"] == 1200.0
    assert sum(st["cutbacks"] for st in s["steps"]) == 0
    assert s["newton_iterations"] <= 66
    assert max(st["iterations"] for st in s["steps"][4:]) <= 8
    raw["contact"]["fade"] = "settle"
    settled = run_inline(raw, tmp_path / "settle", base_dir=CONFIGS)
    for a, b in zip(s["steps"], settled["steps"]):
        for name, u in a["probes"].items():
            u, v = np.asarray(u["displacement"]), np.asarray(b["probes"][name]["displacement"])
            assert np.abs(u - v).max() <= 1e-6 * np.abs(v).max()
