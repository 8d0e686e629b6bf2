"""The contact solid (three subtendons, exact multipliers) and its friction on coarse meshes:
with contact off each body is the bars' solid (an independent code path), and the assembled
tangents are the derivatives of the residuals (central differences).  Seconds each."""
import pytest


@pytest.fixture(scope="module")
def secs(solid_stack):
    from ancf_verify.contact.tendon import tendon_sections
    return tendon_sections()


def test_without_contact_each_body_is_the_bar_solid(secs):
    """(1) of the contact self-test: the three bodies in one mesh, each pulled at its end,
    against ancf_verify.bars' solid of that body meshed alone (same h): the same answer to the
    meshes' difference (the bodies' shared interfaces are meshed conformingly in one, apart in
    the other)."""
    from ancf_verify.checks import contact_off
    for c in contact_off(secs):
        assert c.ok and c.committed > 1e-5, c


def test_the_contact_tangent_is_the_residuals_derivative(secs):
    """(3) of the contact self-test: the sliding law's whole tangent, gap Hessian included, and
    both laws' weighted-gap derivatives against central differences.  The unilateral whole
    tangent is checked only where the active set stays put within ±ε (its random state puts
    constraints on the regularised switch: docs/solid_contact.md, "inconclusive")."""
    from ancf_verify.contact.selftest import selftest_fd
    eps = (1e-5, 1e-6, 1e-7)
    for rec in selftest_fd(secs, 4e-3, 45.0, log=lambda *_: None):
        assert rec["active"] > 0, rec["law"]
        assert min(rec[e]["gbar"] for e in eps) < 1e-7, rec
        same = [rec[e]["full"] for e in eps if rec[e]["same_set"]]
        if rec["law"] == "sliding":
            assert min(rec[e]["full"] for e in eps) < 1e-8, rec
        if same:
            assert min(same) < 1e-6, rec


def test_the_friction_tangent_is_the_residuals_derivative(secs):
    """The Coulomb solid's consistent tangent, both slip measures, sticking and sliding points."""
    from ancf_verify.friction.study import selftest_fd
    for rec in selftest_fd(secs, 4e-3, 45.0, log=lambda *_: None):
        assert rec["stick"] > 0 and rec["slide"] > 0, rec
        assert min(rec[eps]["full"] for eps in (1e-5, 1e-6, 1e-7, 1e-8)) < 1e-6, rec
        assert min(rec[eps]["friction"] for eps in (1e-5, 1e-6, 1e-7, 1e-8)) < 1e-5, rec


def test_a_pure_penalty_tends_to_the_multipliers(secs):
    """``penalty`` (the sensitivity study of docs/solid_contact.md, "The unilateral 10 N question on
    plane roots"): the sliding law by a pure penalty ε = κ μ/h is softer than with exact
    multipliers, by less the stiffer the penalty; rows of model PENALTY name ε."""
    from ancf_verify.contact.rows import PENALTY, SOLID, solid_rows
    from ancf_verify.contact.solid import run_solid
    kw = dict(loads=[10.0], max_increment=10.0, log=None, root="plane")
    exact = run_solid(secs, 45.0, "sliding", 4e-3, **kw)
    soft, stiff = (run_solid(secs, 45.0, "sliding", 4e-3, penalty=k, **kw) for k in (0.1, 10.0))
    u = [r["levels"][0]["u"]["soleus"][0] for r in (exact, soft, stiff)]
    assert exact["ok"] and soft["ok"] and stiff["ok"]
    assert u[1] > u[2] > u[0] and (u[2] - u[0]) < 0.5 * (u[1] - u[0]), u
    assert solid_rows(exact)[0]["model"] == SOLID and solid_rows(soft)[0]["model"] == PENALTY
    assert solid_rows(soft)[0]["resolution"] == "h 4.00 mm, penalty eps = 0.1 mu/h"
