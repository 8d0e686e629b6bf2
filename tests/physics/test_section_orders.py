"""Section fields of order 3 and 4 (issue 42, item 2): elements 33103 (complete cubic, 30 DOFs per
node) and 33153 (complete quartic, 45 DOFs per node).  Patch tests of the section field (uniaxial
tension exact, the section rule exact for the products the element integrates, FD tangents),
supports, tractions and probes read from the richer block, contact (sliding, unilateral,
Coulomb), GOH fibres, the fascicle solver, restart and MPI."""
import math
import os

import h5py
import numpy as np
import pytest

from ancf_petsc.config.values import ConfigError
from ancf_petsc.physics.elements import ELEMENTS, complete_monomials
from helpers import (CONFIGS, assert_jacobian_and_gradient, build_problem, load_raw, perturbed_state,
                     probes_table, read_summary, run_inline, solve_cli, two_beam_twisted, write_config)

ORDERS = {"33103": 3, "33153": 4}
GOH = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 30.0e6, "k1": 2.0e6, "k2": 5.0, "kappa": 0.1,
       "fibres": {"follow": "twist", "angle_deg": 30.0, "extra_twist_deg": 15.0}}


def _parse(raw):
    from ancf_petsc.config.parse import parse_config
    return parse_config(raw, base_dir=CONFIGS)


def _model(raw):
    from ancf_petsc.model.build import build_model
    return build_model(_parse(raw))


def _bar(name: str, **beam) -> dict:
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0].update(element=name, **beam)
    raw["output"]["vtk"] = False
    return raw


@pytest.mark.parametrize("name", ORDERS)
def test_the_elements_are_the_complete_fields_of_their_order(name):
    e = ELEMENTS[name]
    order = ORDERS[name]
    assert e.block.monomials == complete_monomials(order) and e.block.order == order
    assert e.block.vectors_per_node == (order + 1) * (order + 2) // 2 and e.block.axial_nodes == 3
    assert e.name == f"33{e.block.vectors_per_node}3" and e.held == ()
    assert e.section_degree == 2 * order and "ecm" not in e.remedies
    assert ELEMENTS["3363"].section_degree == 0 and "ecm" in ELEMENTS["3363"].remedies


# ------------------------------------------------------------------ section cubature
def _ellipse_moment(a: float, b: float, p: int, q: int) -> float:
    """∫∫ y^p z^q over the ellipse (y/a)² + (z/b)² ≤ 1, exactly."""
    if p % 2 or q % 2:
        return 0.0
    disk = 2.0 * math.gamma((p + 1) / 2) * math.gamma((q + 1) / 2) / ((p + q + 2) * math.gamma((p + q + 2) / 2))
    return a ** (p + 1) * b ** (q + 1) * disk


@pytest.mark.parametrize("name", ORDERS)
def test_the_section_rule_is_raised_to_twice_the_order_and_integrates_every_product(name):
    """A config's cubature_degree 4 becomes 2 × order; that rule integrates every product
    m_a m_b and ∂m_a ∂m_b of the field (degree ≤ 2·order) exactly on an ellipse, and the rule of
    the given degree would not (the check can fail)."""
    from ancf_petsc.physics.section import make_ellipse
    order = ORDERS[name]
    raw = _bar(name)
    raw["beams"][0]["section"]["cubature_degree"] = 4
    sec = _model(raw).beams[0].section
    assert sec.degree == 2 * order
    a, b = raw["beams"][0]["section"]["semi_axes"]
    pairs = [(i, j) for i in range(2 * order + 1) for j in range(2 * order + 1 - i)]
    exact = np.array([_ellipse_moment(a, b, p, q) for p, q in pairs])
    scale = np.array([a ** p * b ** q * math.pi * a * b for p, q in pairs])

    def moments(s):
        y, z = s.points.T
        return np.array([s.weights @ (y ** p * z ** q) for p, q in pairs])
    assert np.abs(moments(sec) - exact).max() <= 1e-12 * scale.max() and np.all(np.abs(moments(sec) - exact) <= 1e-12 * scale)
    low = moments(make_ellipse((a, b), degree=4))
    assert np.any(np.abs(low - exact) > 1e-6 * scale)
    block = ELEMENTS[name].block
    m = block.section_monomials(*sec.points.T)
    K = np.einsum("p,pa,pb->ab", sec.weights, m, m)
    want = np.array([[_ellipse_moment(a, b, i + k, j + l) / (math.factorial(i) * math.factorial(j)
                                                           * math.factorial(k) * math.factorial(l))
                      for k, l in block.monomials] for i, j in block.monomials])
    assert np.abs(K - want).max() <= 1e-12 * np.abs(want).max()


@pytest.mark.parametrize("name", ORDERS)
def test_the_gauss_green_outline_rule_keeps_its_moments_at_the_raised_degree(name):
    """The soleus outline (Gauss–Green cubature of eq. 11, compressed to positive weights): at the
    raised degree its compressed rule reproduces every moment of degree ≤ 2·order of the
    uncompressed Gauss–Green rule of a higher degree, in centroidal coordinates."""
    from ancf_petsc.physics.section import make_outline
    from ancf_petsc.physics.sections_file import load_sections_file
    order = ORDERS[name]
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["beams"][0]["element"] = name
    spec = _parse(raw)
    assert spec.beams[0].section.cubature_degree == max(6, 2 * order)
    loop = load_sections_file(os.path.join(CONFIGS, "data/achilles_type3_sections.yaml"), 3).loops["soleus"]
    rule = make_outline(loop, spec.beams[0].section.cubature_degree)
    ref = make_outline(loop, 2 * order + 6, compress=False)
    assert np.all(rule.weights > 0)
    c = ref.centroid - rule.centroid
    ext = float(np.abs(ref.points).max())
    for p in range(2 * order + 1):
        for q in range(2 * order + 1 - p):
            mine = rule.weights @ (rule.points[:, 0] ** p * rule.points[:, 1] ** q)
            theirs = ref.weights @ ((ref.points[:, 0] + c[0]) ** p * (ref.points[:, 1] + c[1]) ** q)
            assert abs(mine - theirs) <= 1e-10 * ref.area * ext ** (p + q), (p, q)


# ------------------------------------------------------------------ patch tests
@pytest.mark.parametrize("name", ORDERS)
@pytest.mark.parametrize("locking", ["none", "mixed"])
@pytest.mark.parametrize("fix", ["reduced", "plane"])
def test_uniaxial_tension_is_exact(tmp_path, name, locking, fix):
    """One element, the configs/uniaxial_neohookean.yaml bar, to 1e-9 of the homogeneous stretch
    on the paper's support and on the frictionless plane (the section contracts uniformly; the
    higher vectors stay 0)."""
    from ancf_petsc.physics.materials import NeoHookean
    from ancf_petsc.physics.reference_solutions import uniaxial_stretches
    raw = _bar(name, locking=locking)
    raw["boundary_conditions"][0]["fix"] = fix
    s = run_inline(raw, tmp_path)
    area = next(iter(s["sections"].values()))["area"]
    for step in s["steps"]:
        lam, _ = uniaxial_stretches(NeoHookean(1.0e6, 50.0e6), step["load_factor"] * 45.0 / area)
        assert step["probes"]["tip"]["displacement"][0] == pytest.approx((lam - 1.0) * 0.1, rel=1e-9)


@pytest.mark.parametrize("name", ORDERS)
def test_ecm_is_refused_with_the_measured_reason(name):
    """ecm's ν = 0 part over the section does work on the cubic modes (∫ y² dA ≠ 0) in a
    homogeneous state: uniaxial tension 65 % off (scripts/section_orders.py uniaxial): refused."""
    with pytest.raises(ConfigError) as err:
        _parse(_bar(name, locking="ecm"))
    msg = str(err.value)
    assert msg.startswith("beams[0].locking:") and "'none' or 'mixed'" in msg and "\n" not in msg


def test_beams_of_other_node_blocks_are_refused_with_the_fix():
    """33103 beside 3363 said 'element 3363 has another node block than 33103 (beams[0]); the
    beams of one model share their node layout', without the value to give or the one given."""
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["beams"][0]["element"] = "33103"
    with pytest.raises(ConfigError) as err:
        _model(raw)
    msg = str(err.value)
    assert msg.startswith("beams[1].element: has another node block than 33103") and "\n" not in msg
    assert msg.endswith("give '33103' here, or the same element to every beam; got '3363'")


@pytest.mark.parametrize("name", ORDERS)
@pytest.mark.parametrize("law", ["neo-hookean mixed", "goh none", "goh mixed"])
def test_jacobian_matches_finite_differences(name, law):
    """Two pretwisted beams (the second an SVK beam, clamped) of the element, the first with the
    law and remedy: the assembled Jacobian is the residual's derivative, the residual the energy's."""
    raw = two_beam_twisted()
    for b in raw["beams"]:
        b["element"] = name
    model, locking = law.split()
    raw["beams"][0]["locking"] = locking
    if model == "goh":
        raw["beams"][0]["material"] = dict(GOH)
    P, _ = build_problem(raw)
    assert P.model.dofs_per_node == 3 * len(complete_monomials(ORDERS[name]))
    if model == "goh":
        assert P.model.beams[0].fibres.shape[-1] == 3
    P.load_factor = 0.7
    rng = np.random.default_rng(4)
    X, free = perturbed_state(P, rng, 2e-3)
    P.jacobian(None, X, P.J, P.J)
    assert_jacobian_and_gradient(P, X, free, rng, gradient_rel=1e-5)


# ------------------------------------------------------------------ supports, loads, probes
@pytest.mark.parametrize("name", ORDERS)
def test_presets_tractions_and_probes_read_the_richer_block(name):
    """clamped holds every component; reduced all but r_y·e_y and r_z·e_z; plane r, r_y·e_z and
    every x-component (higher vectors' y, z free).  A traction F over an ellipse loads vector
    y^i z^j / (i! j!) with F ∫ m dA / A (exact moments) and the ``mean`` probe weighs the
    vectors with the same means; the centroid is r."""
    V = ELEMENTS[name].block.vectors_per_node
    names = ELEMENTS[name].block.names
    raw = _bar(name)
    raw["probes"].append({"name": "mean", "beam": "bar", "node": "last", "vector": "mean"})
    for fix, count in (("clamped", 3 * V), ("reduced", 3 * V - 2), ("plane", 6 + V - 3)):
        raw["boundary_conditions"][0]["fix"] = fix
        m = _model(raw)
        D = m.dofs_per_node
        fixed = m.fixed_dofs[m.fixed_dofs < D]
        assert len(fixed) == count
        if fix == "plane":
            assert set(fixed) == {0, 1, 2, 3, 5, 6} | {3 * v for v in range(3, V)}
    a, b = raw["beams"][0]["section"]["semi_axes"]
    area = math.pi * a * b
    means = np.array([_ellipse_moment(a, b, i, j) / (math.factorial(i) * math.factorial(j) * area)
                      for i, j in ELEMENTS[name].block.monomials])
    last = m.beams[0].n_nodes - 1
    f = m.f_ext.reshape(-1, V, 3)[last]
    assert np.allclose(f[:, 0], 45.0 * means, rtol=1e-12, atol=1e-15 * 45.0)
    assert np.all(f[:, 1:] == 0.0) and abs(f[names.index("r_yy"), 0]) > 0
    node, w = m.probes["mean"]
    assert node == last and np.allclose(w, means, rtol=1e-12, atol=1e-18)
    assert np.array_equal(m.probes["tip"][1], np.eye(V)[0])


# ------------------------------------------------------------------ contact, fascicles, restart, MPI
CONTACT = {"sliding": {"mode": "sliding"}, "unilateral": {"mode": "unilateral"},
           "coulomb": {"mode": "sliding", "tangential": {"law": "coulomb", "friction": 0.3}}}


def _column(name: str, contact: str, steps: list) -> dict:
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["element"] = name
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["contact"] = dict(CONTACT[contact])
    raw["steps"] = steps
    raw["probes"].append({"name": "mean", "beam": "soleus", "node": "last", "vector": "mean"})
    raw["output"] = {"vtk": False}
    return raw


#: Coulomb's first increments from rest: the incremental problem from rest has several solutions
#: (docs/interface.md, Limits), and which one a first increment of 10 N takes depends on its size
#: and the augmentation c (3363 at 40 N: 5.084e-4 m with G/E, 5.230e-4 with c = 1; 33153: 5.373e-4
#: and 5.426e-4).  From 0.25 N on both c take the same path (5.085e-4, 5.180e-4 for 33103, 5.425e-4
#: for 33153, measured 2026-12-02), so the comparison is made on it
FIRST_INCREMENTS = {"coulomb": [0.25, 0.5, 1.0, 2.0, 3.0, 5.0, 7.5]}
#: the soleus' elongation at 40 N within this of 3363's: 2.3 % apart sliding and 2.1 % unilateral
#: (33153), 6.7 % with Coulomb friction on the path above (its law per pressure function)
WITHIN = {"sliding": 0.05, "unilateral": 0.05, "coulomb": 0.08}


@pytest.mark.parametrize("name", ORDERS)
@pytest.mark.parametrize("contact", ["sliding", pytest.param("unilateral", marks=pytest.mark.slow),
                                     pytest.param("coulomb", marks=pytest.mark.slow)])
def test_the_achilles_column_solves_with_each_contact_law(tmp_path, name, contact):
    """Contact points, projection, the pressure (and tangential) multipliers of the 30/45-DOF
    blocks; the soleus elongates as 3363's at 40 N, a little more (the paper's point force on r:
    the richer field lets the loaded section bulge more, docs/locking.md)."""
    steps = FIRST_INCREMENTS.get(contact, []) + [10.0, 40.0]
    raw = _column(name, contact, steps)
    s = run_inline(raw, tmp_path / "hi")
    ref = run_inline(_column("3363", contact, steps), tmp_path / "q")
    assert s["status"] == "completed" and s["dofs"] == 27 * ELEMENTS[name].block.dofs_per_node
    u, u2 = (x["steps"][-1]["probes"]["soleus"]["displacement"][0] for x in (s, ref))
    assert u == pytest.approx(u2, rel=WITHIN[contact]) and u >= u2 > 0
    mean = s["steps"][-1]["probes"]["mean"]["displacement"][0]
    assert 0.5 * u < mean < 1.5 * u


@pytest.mark.parametrize("name", ORDERS)
def test_the_fascicle_schur_preconditioner_is_the_exact_inverse(name):
    """linalg/fascicles.py on bundle_hex7 of the element after one Newton step (multipliers,
    contact curvature): PC(r) = J_bd⁻¹ r, and its pivots count J_bd's negative eigenvalues."""
    from helpers import apply_fascicle_schur, beam_of_dofs, hex7_problem, without_cross_fascicle_blocks
    P, PETSc, F = hex7_problem(True, "sbaij", element=name)
    assert P.model.dofs_per_node == ELEMENTS[name].block.dofs_per_node
    J = P.J.convert("aij", PETSc.Mat()).convert("dense", PETSc.Mat()).getDenseArray().copy()
    Jbd = without_cross_fascicle_blocks(J, beam_of_dofs(P))
    ctx, pc, y = apply_fascicle_schur(P, PETSc, F)
    b, y = F.getArray(), y.getArray()
    # J_bd equilibrated, D J_bd D with D = |diag|^-1/2: the cubic and quartic modes' stiffness
    # (~ y^6, y^8: 1e-17 of r's and below) is then out of the round-off of numpy's dense solve and
    # eigvalsh (their signs are noise unscaled); Sylvester: D J_bd D has J_bd's inertia
    d = np.abs(np.diag(Jbd))
    D = np.where(d > 0, 1.0 / np.sqrt(np.where(d > 0, d, 1.0)), 1.0)
    A = D[:, None] * Jbd * D[None, :]
    ref = D * np.linalg.solve(A, D * b)
    assert np.linalg.norm(y - ref) <= 1e-6 * np.linalg.norm(ref)
    assert np.linalg.norm(Jbd @ y - b) <= 1e-8 * np.linalg.norm(b)
    neg, null = ctx.pivot_counts()
    assert neg == int(np.sum(np.linalg.eigvalsh(A) < 0)) and null == 0
    pc.destroy()


def _last_state(out) -> np.ndarray:
    with h5py.File(out / "results.h5", "r") as f:
        k = int(f["steps"].attrs["converged"])
        return f[f"steps/step_{k:04d}/nodal_vectors"][()]


@pytest.mark.slow
@pytest.mark.parametrize("name", ORDERS)
def test_a_restarted_column_is_the_uninterrupted_one(tmp_path, name):
    from ancf_petsc.api import solve
    raw = _column(name, "sliding", [10.0, 20.0, 30.0])
    run_inline(raw, tmp_path / "whole")
    run_inline(dict(raw, steps=[10.0]), tmp_path / "part")
    spec = _parse(dict(raw, output={"dir": str(tmp_path / "part"), "vtk": False}))
    assert solve(spec, log=lambda *_: None, restart=str(tmp_path / "part")).summary["status"] == "completed"
    whole, part = _last_state(tmp_path / "whole"), _last_state(tmp_path / "part")
    assert whole.shape[1] == ELEMENTS[name].block.vectors_per_node
    assert np.abs(part - whole).max() <= 1e-10 * np.abs(whole).max()


@pytest.mark.mpi
@pytest.mark.parametrize("name", ORDERS)
def test_two_ranks_equal_serial(tmp_path, name):
    """ancf-solve on 2 ranks (the registry's element, no in-test registration): the probes of
    the contact column with a Coulomb law equal the serial run's to 1e-9."""
    raw = _column(name, "coulomb", [10.0, 20.0])
    out = {}
    for n in (1, 2):
        raw["output"] = {"dir": str(tmp_path / f"n{n}"), "vtk": False}
        p = solve_cli(write_config(raw, tmp_path / f"c{n}.yaml"), ranks=n)
        assert p.returncode == 0, p.stdout + p.stderr
        out[n] = read_summary(tmp_path / f"n{n}")
    assert out[2]["ranks"] == 2
    a, b = probes_table(out[1]), probes_table(out[2])
    assert np.abs(a - b).max() <= 1e-9 * np.abs(a).max()


def _end_turn(element, hold=None, phi=0.01):
    """A 0.5 m NH bar (K/μ = 50, 10 mm square, 8 elements) on a plane root, bent by turning its
    last node's r_z by φ about y (r_z·e_x = −φ); ``hold``: its other components held there."""
    grip = {"beam": "bar", "node": "last", "name": "grip", "displacement": {"r_z": {"x": -phi}}}
    if hold:
        grip["fix"] = hold
    return {"name": "end_turn", "geometry": {"length": 0.5},
            "beams": [{"name": "bar", "section": {"shape": "rectangle", "size": [0.01, 0.01], "cubature_degree": 8},
                       "material": {"model": "neo-hookean", "mu": 1.0e6, "bulk_modulus": 50.0e6},
                       "elements": 8, "element": element}],
            "boundary_conditions": [{"beam": "bar", "node": "first", "fix": "plane"}, grip],
            "loads": [], "steps": [1.0], "output": {"vtk": False}}


@pytest.mark.parametrize("element", sorted(ORDERS))
def test_a_prescribed_slope_whose_face_can_warp_is_warned_about(tmp_path, element):
    """r_z of 33103 / 33153 is the coefficient of z in the section field, not the end face's
    turn: with the cubic vectors free the face warped around it and the bar carried 0.9945 / 0.974
    E I φ / L (3363: 1.00002), with no word.  Now the build names the support and the vectors to
    hold, and holding their x components gives beam theory's moment."""
    from ancf_petsc.model.build import build_model
    higher = [n for n, (i, j) in zip(ELEMENTS[element].block.names, ELEMENTS[element].block.monomials) if i + j >= 3]
    (w,) = [w for w in build_model(_parse(_end_turn(element))).warnings if "displacement" in w]
    assert w.startswith(f"warning: boundary_conditions[1].displacement.r_z.x: on element {element} r_z is the "
                        "coefficient of z") and w.endswith("fix: {" + ", ".join(f"{n}: x" for n in higher) + "}")
    held = _end_turn(element, {n: "x" for n in higher})
    assert [w for w in build_model(_parse(held)).warnings if "displacement" in w] == []
    assert [w for w in build_model(_parse(_end_turn("3363"))).warnings if "displacement" in w] == []
    E = 9.0 * 50.0e6 * 1.0e6 / (3.0 * 50.0e6 + 1.0e6)
    moment = -run_inline(held, tmp_path)["steps"][-1]["reaction_moments"]["grip"][1]
    assert moment == pytest.approx(E * 0.01 ** 4 / 12.0 * 0.01 / 0.5, rel=1e-3)      # measured: 2e-5
