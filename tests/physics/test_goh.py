"""GOH fibre-reinforced law (physics/goh.py) and its fibre field (physics/fibres.py): exact
homogeneous solutions written here from the strain energy by hand, finite differences of the
element residual, the fibre field's geometry, config errors."""
import copy

import numpy as np
import pytest
from scipy.optimize import root

from ancf_petsc.config.parse import parse_config
from ancf_petsc.config.values import ConfigError
from ancf_petsc.model.build import build_model
from ancf_petsc.physics import kernels
from ancf_petsc.physics.fibres import fibre_directions
from ancf_petsc.physics.goh import GOH
from ancf_petsc.physics.materials import NeoHookean
from helpers import CONFIGS, load_raw, run_inline

MU, K, K1, K2 = 1.0e6, 50.0e6, 2.0e6, 5.0


def goh_material(kappa=0.0, follow="axis", angle=0.0, extra=0.0):
    return {"model": "goh", "mu": MU, "bulk_modulus": K, "k1": K1, "k2": K2, "kappa": kappa,
            "fibres": {"follow": follow, "angle_deg": angle, "extra_twist_deg": extra}}


# ------------------------------------------------------------- exact homogeneous solutions
def principal_stress(lam, fibre_axis, kappa, split=False):
    """P_i = ∂W/∂λ_i of W(λ1, λ2, λ3) for F = diag(λ) and fibres along e_{fibre_axis}, written
    out by hand (independent of physics/goh.py).  ``split``: the isochoric fibre term (Ī1, Ī4)
    that the law does not use, for comparison."""
    lam = np.asarray(lam, dtype=float)
    J = np.prod(lam)
    I1 = np.sum(lam ** 2)
    Jm = J ** (-2.0 / 3.0)
    P = 0.5 * MU * (Jm * 2.0 * lam - (2.0 / 3.0) * I1 * Jm / lam) + K * (J - 1.0) * J / lam
    if split:     # Ē(Ī1, Ī4), Ī = J^(-2/3) I: ∂Ī/∂λ_i = J^(-2/3)(∂I/∂λ_i − (2/3) I/λ_i)
        I4 = lam[fibre_axis] ** 2
        E = kappa * (Jm * I1 - 3.0) + (1.0 - 3.0 * kappa) * (Jm * I4 - 1.0)
        dI4 = np.zeros(3)
        dI4[fibre_axis] = 2.0 * lam[fibre_axis]
        dE = kappa * Jm * (2.0 * lam - (2.0 / 3.0) * I1 / lam) \
            + (1.0 - 3.0 * kappa) * Jm * (dI4 - (2.0 / 3.0) * I4 / lam)
    else:
        E = kappa * (I1 - 3.0) + (1.0 - 3.0 * kappa) * (lam[fibre_axis] ** 2 - 1.0)
        dE = 2.0 * kappa * lam
        dE[fibre_axis] += 2.0 * (1.0 - 3.0 * kappa) * lam[fibre_axis]
    if E > 0.0:
        P = P + K1 * E * np.exp(K2 * E * E) * dE
    return P


def uniaxial_exact(axial_stress, fibre_axis, kappa):
    """Stretches (λ1, λ2, λ3) with P11 = s, P22 = P33 = 0 (root finding)."""
    def eqs(v):
        P = principal_stress(v, fibre_axis, kappa)
        return [(P[0] - axial_stress) / MU, P[1] / MU, P[2] / MU]
    sol = root(eqs, [1.0 + axial_stress / (3 * MU), 1.0, 1.0], method="hybr", tol=1e-15)
    assert np.max(np.abs(eqs(sol.x))) < 1e-12, sol.message
    return sol.x


def axial_stress_at(lam, fibre_axis, kappa):
    """P11 of uniaxial tension at axial stretch λ (lateral stress-free)."""
    sol = root(lambda v: principal_stress([lam, *v], fibre_axis, kappa)[1:] / MU, [1.0, 1.0],
               method="hybr", tol=1e-15)
    return principal_stress([lam, *sol.x], fibre_axis, kappa)[0]


def one_element_run(tmp_path, material, stretch, fibre_axis, kappa, name, element=3363, locking=None):
    """One element in uniaxial dead traction at the axial stress of ``stretch`` (exact solution)."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["material"] = material
    raw["beams"][0]["element"] = element
    if locking is not None:
        raw["beams"][0]["locking"] = locking
    raw["output"]["vtk"] = False
    raw["steps"] = [0.5, 1.0]
    area = np.pi * 0.006 * 0.004            # the degree-6 cubature of the ellipse is exact
    s = axial_stress_at(stretch, fibre_axis, kappa)
    raw["loads"][0]["traction_force"] = [float(s * area), 0.0, 0.0]
    return run_inline(raw, tmp_path / name), s, raw


@pytest.mark.parametrize("kappa,element", [(0.0, 3363), (0.2, 3363), (0.2, 3333)])
@pytest.mark.parametrize("direction", ["along", "across"])
def test_uniaxial_tension_matches_exact_solution(tmp_path, kappa, direction, element):
    """One element (3363, or 3333 with its default ``locking: ecm``), uniform dead traction,
    fibres along x (follow: axis) or across along the section's y (angle 90): the homogeneous
    exact solution to 1e-8."""
    fibre_axis, angle = (0, 0.0) if direction == "along" else (1, 90.0)
    summary, s, raw = one_element_run(tmp_path, goh_material(kappa, angle=angle), 1.12,
                                       fibre_axis, kappa, "run", element)
    assert summary["status"] == "completed"
    L = raw["geometry"]["length"]
    for step in summary["steps"]:
        lam = uniaxial_exact(step["load_factor"] * s, fibre_axis, kappa)
        u = step["probes"]["tip"]["displacement"]
        assert abs(u[0] / ((lam[0] - 1.0) * L) - 1.0) < 1e-8, (u, lam)
        assert abs(u[1]) < 1e-12 and abs(u[2]) < 1e-12


def test_vtu_carries_fibre_stretch_and_stress(tmp_path):
    """Uniaxial tension along the fibres: the surface VTU's fibre stretch is λ and its fibre
    stress the Cauchy σ11 = P11 λ / J of the exact solution (single-precision output)."""
    import glob

    import meshio
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["material"] = goh_material(0.2)
    raw["steps"] = [1.0]
    s = axial_stress_at(1.1, 0, 0.2)
    raw["loads"][0]["traction_force"] = [float(s * np.pi * 0.006 * 0.004), 0.0, 0.0]
    raw["output"]["vtk"] = True
    assert run_inline(raw, tmp_path)["status"] == "completed"
    last = sorted(glob.glob(str(tmp_path / "**" / "surface_*.vtu"), recursive=True))[-1]
    data = meshio.read(last).point_data
    lam = uniaxial_exact(s, 0, 0.2)
    assert np.allclose(data["fibre_stretch"], lam[0], rtol=1e-6)
    assert np.allclose(data["fibre_stress"], s * lam[0] / np.prod(lam), rtol=1e-5)


@pytest.mark.parametrize("kappa", [0.0, 0.2])
def test_fibres_carry_no_compression(tmp_path, kappa):
    """Compression along the fibres: exactly the matrix's (neo-Hookean) stress and tangent at the
    material, and the neo-Hookean run's answer to round-off (the tangent's form differs)."""
    rng = np.random.default_rng(7)
    F = np.diag([0.85, 1.08, 1.09]) + 0.01 * rng.standard_normal((40, 3, 3))
    law = GOH(MU, K, K1, K2, kappa).with_directions(np.array([[1.0, 0.0, 0.0]]))
    assert np.array_equal(law.stress(F)[0], NeoHookean(MU, K).stress(F)[0])
    P, _, terms = law.stress_and_tangent(F)
    _, _, nh = NeoHookean(MU, K).stress_and_tangent(F)
    assert np.array_equal(terms.full(), nh.full())

    raw = load_raw("uniaxial_neohookean.yaml")
    raw["output"]["vtk"] = False
    raw["loads"][0]["traction_force"] = [-20.0, 0.0, 0.0]
    raw["steps"] = [0.5, 1.0]
    runs = {}
    for name, mat in (("nh", {"model": "neo-hookean", "mu": MU, "bulk_modulus": K}),
                      ("goh", goh_material(kappa))):
        raw["beams"][0]["material"] = mat
        runs[name] = run_inline(copy.deepcopy(raw), tmp_path / name)
    for a, b in zip(runs["nh"]["steps"], runs["goh"]["steps"]):
        ua, ub = (np.array(s["probes"]["tip"]["displacement"]) for s in (a, b))
        assert np.abs(ua - ub).max() <= 1e-13 * np.abs(ua).max()
    assert runs["goh"]["steps"][-1]["probes"]["tip"]["displacement"][0] < -1e-3


def test_k1_zero_is_the_matrix_alone(tmp_path):
    """k1: 0 "switches the fibres off": with k2 524.6 the fibre term 0 e^(k2 Ē²) was NaN once the
    exponential overflowed (fibre stretch 1.47), so the one-element bar, which the matrix alone
    takes to 2.2x its length, failed at load factor 0.4989 (DIVERGED_FNORM_NAN).  Now the law
    (numpy and compiled kernels) is its neo-Hookean matrix's, the run the same to round-off
    (with the same predictor: the model's defaults are a fibre law's)."""
    F = np.diag([1.6, 0.8, 0.8])[None]
    law = GOH(MU, K, 0.0, 524.6).with_directions(np.array([[[1.0, 0.0, 0.0]]]))
    nh = NeoHookean(MU, K)
    assert np.array_equal(law.stress(F)[0], nh.stress(F)[0]) and law.energy(F) == nh.energy(F)
    assert np.array_equal(law.stress_and_tangent(F)[2].full(), nh.stress_and_tangent(F)[2].full())
    assert law.fibre_exponent(F) == 0.0 and law.fibre_stretch(F)[0, 0] == pytest.approx(1.6)
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["output"]["vtk"] = False
    raw["loads"][0]["traction_force"] = [150.0, 0.0, 0.0]        # 2 MPa: stretch 2.24
    raw["steps"], raw["solver"] = [0.25, 0.5, 1.0], {"predictor": "tangent"}     # a fibre law's default
    runs = {}
    for name, mat in (("nh", {"model": "neo-hookean", "mu": MU, "bulk_modulus": K}),
                      ("goh", dict(goh_material(), k1=0.0, k2=524.6))):
        raw["beams"][0]["material"] = mat
        runs[name] = run_inline(copy.deepcopy(raw), tmp_path / name)
        assert runs[name]["status"] == "completed", runs[name].get("message")
    for a, b in zip(runs["nh"]["steps"], runs["goh"]["steps"]):
        ua, ub = (np.array(s["probes"]["tip"]["displacement"]) for s in (a, b))
        assert np.abs(ua - ub).max() <= 1e-12 * np.abs(ua).max() and a["iterations"] == b["iterations"]


def test_the_reference_state_has_the_tension_sides_tangent_despite_rounding():
    """F of the reference state is I only to rounding, so Ē there is ±1e-15.  The tangent must
    still be the tension side's at every point (an exact Ē >= 0 test switched the fibres of
    40-50 % of a tendon's Gauss points off in the first Newton step: docs/fibres.md)."""
    rng = np.random.default_rng(3)
    a0 = rng.standard_normal((1, 64, 3))
    a0 /= np.linalg.norm(a0, axis=-1, keepdims=True)
    F = np.eye(3) + 2e-16 * rng.standard_normal((64, 3, 3))
    for kappa in (0.0, 0.2):
        law = GOH(MU, K, K1, K2, kappa).with_directions(a0)
        I4 = (np.einsum("pij,pj->pi", F, a0[0]) ** 2).sum(-1)
        E = kappa * (np.einsum("pij,pij->p", F, F) - 3) + (1 - 3 * kappa) * (I4 - 1)
        assert (E < 0).any() and np.abs(E).max() < 1e-14        # the rounding this is about
        eye = np.broadcast_to(np.eye(3), F.shape).copy()
        H = kappa * eye + (1 - 3 * kappa) * np.einsum("pi,pj->pij", a0[0], a0[0])
        expected = NeoHookean(MU, K).stress_and_tangent(eye)[2].full() \
            + 4 * K1 * np.einsum("pij,pkl->pijkl", H, H)        # ψ'(0) = 0, ψ''(0) = k1
        noisy = law.stress_and_tangent(F)[2].full()
        assert np.abs(noisy - expected).max() <= 1e-12 * np.abs(expected).max()
        assert np.abs(law.stress(F)[0]).max() < 1e-6 * MU                # and no fibre stress


def test_the_exact_switch_is_an_option_of_the_law_and_of_a_parsed_spec():
    """``e_rounding`` = 0 (the exact Ē >= 0 switch, a diagnosis of scripts/goh_published_sets.py)
    switches the fibres' tangent off where rounding makes Ē < 0; it survives binding the
    directions and ``poisson_free``, and a parsed spec's material mapping carries it to the law."""
    from ancf_petsc.physics.laws import make_material
    rng = np.random.default_rng(3)
    a0 = rng.standard_normal((1, 64, 3))
    a0 /= np.linalg.norm(a0, axis=-1, keepdims=True)
    F = np.eye(3) + 2e-16 * rng.standard_normal((64, 3, 3))
    exact = GOH(MU, K, K1, K2, 0.0, e_rounding=0.0).with_directions(a0)
    assert exact.poisson_free().e_rounding == 0.0 and exact.take(slice(0, 8)).e_rounding == 0.0
    today = GOH(MU, K, K1, K2, 0.0).with_directions(a0).stress_and_tangent(F)[2].full()
    before = exact.stress_and_tangent(F)[2].full()
    assert np.abs(today - before).max() > 1e-3 * np.abs(today).max()
    spec = {"model": "goh", "mu": MU, "bulk_modulus": K, "k1": K1, "k2": K2, "kappa": 0.0,
            "fibres": {"follow": "twist", "extra_twist_deg": 0.0, "angles_deg": (0.0,)}}
    assert make_material(spec).e_rounding == 1e-12
    assert make_material({**spec, "e_rounding": 0.0}).e_rounding == 0.0


def test_a_small_k2_keeps_the_energy_and_the_energy_line_search(tmp_path):
    """k2 -> 0 is the quadratic fibre k1/2 Ē² (the k2 hint suggests a small k2 for a nearly
    linear fibre): the energy is k1/(2 k2) expm1(k2 Ē²), not exp(...) − 1, which cancelled (k2 =
    1e-8: 4e-6 relative error) and made the bt line search's energy merit fail the uniaxial bar
    (DIVERGED_LINE_SEARCH at load factor 0.945 of 1)."""
    F = np.diag([1.05, 0.98, 0.98])[None]
    for k2 in (1e-8, 1e-14):
        law = GOH(MU, K, K1, k2, 0.0).with_directions(np.array([[[1.0, 0.0, 0.0]]]))
        E = 1.05 ** 2 - 1.0
        fibre = law.energy(F) - NeoHookean(MU, K).energy(F)
        assert abs(fibre[0] / (0.5 * K1 * E * E) - 1.0) < 1e-9
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["material"] = goh_material(0.0)
    raw["beams"][0]["material"]["k2"] = 1e-8
    raw["beams"][0]["elements"] = 2
    raw["output"]["vtk"] = False
    raw["steps"] = [0.5, 1.0]
    raw["loads"][0]["traction_force"] = [0.4 * MU * np.pi * 0.006 * 0.004, 0.0, 0.0]
    s = run_inline(raw, tmp_path / "run", petsc={"snes_linesearch_type": "bt"})
    assert s["status"] == "completed", s.get("message")


@pytest.mark.parametrize("kappa", [0.0, 0.1, 1.0 / 3.0])
@pytest.mark.parametrize("k2", [K2, 1e-8])
def test_law_tangent_matches_finite_differences_at_unusual_states(kappa, k2):
    """The law's 𝔸 against central differences of its P (and P against those of Ψ) where the
    element-level test does not go: shear of 2, det F = 0.11 (near solver.min_det_f = 0.1), two
    families with one in compression, the isotropic end κ = 1/3 and a nearly linear fibre (k2 →
    0); states away from the switch Ē = 0, where the tangent jumps on purpose."""
    states = [np.array([[1.0, 2.0, 0.3], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
              np.array([[0.5, 0.3, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.44]]),
              np.diag([1.2, 0.93, 0.93]), np.diag([0.8, 1.1, 1.1])]
    a0 = np.array([[0.6, 0.8, 0.0], [0.0, 0.6, 0.8]])[:, None, :]      # two families
    two = {"follow": "axis", "extra_twist_deg": 0.0, "angles_deg": (0.0, 0.0)}
    law = GOH(MU, K, K1, k2, kappa, two).with_directions(np.broadcast_to(a0, (2, len(states), 3)))
    F = np.array(states)
    E = np.stack([kappa * (np.einsum("pij,pij->p", F, F) - 3) + (1 - 3 * kappa)
                  * (np.einsum("pij,j->pi", F, a[0]) ** 2).sum(-1) - (1 - 3 * kappa) for a in a0])
    assert np.abs(E).min() > 1e-3 and (E < 0).any() and (E > 0).any()
    P, _, terms = law.stress_and_tangent(F)
    A, h = terms.full(), 1e-7
    Afd, Pfd = np.zeros_like(A), np.zeros_like(P)
    for k in range(3):
        for l in range(3):
            dF = np.zeros((3, 3))
            dF[k, l] = h
            Afd[..., k, l] = (law.stress(F + dF)[0] - law.stress(F - dF)[0]) / (2 * h)
            Pfd[:, k, l] = (law.energy(F + dF) - law.energy(F - dF)) / (2 * h)
    assert np.abs(A - Afd).max() <= 1e-6 * np.abs(A).max()
    assert np.abs(P - Pfd).max() <= 1e-6 * np.abs(P).max()
    assert np.allclose(A, A.transpose(0, 3, 4, 1, 2), atol=1e-10 * np.abs(A).max())


def test_hydrostatic_tension_is_not_isotropic_without_the_split():
    """All-round Cauchy tension σ = p I on a fibre-reinforced cube: the law (fibre term not split)
    stretches less along the fibres, a sphere becomes an ellipsoid; the split form (Ī4) would
    keep F = λI, Ī4 = 1, and the fibres would not notice (checked with the hand-written energy).
    Under all-round compression the fibres are off (Ē < 0): isotropic, as tension-only fibres are."""
    law = GOH(MU, K, K1, K2, 0.1).with_directions(np.array([[1.0, 0.0, 0.0]]))
    p = 0.3 * MU

    def eqs(v, split=None):
        lam = np.array([v[0], v[1], v[1]])
        Jl = np.prod(lam)
        P = principal_stress(lam, 0, 0.1, split) if split is not None \
            else np.diag(law.stress(np.diag(lam)[None])[0][0])
        return [(P[0] - p * Jl / lam[0]) / MU, (P[1] - p * Jl / lam[1]) / MU]

    ours = root(eqs, [1.0, 1.0], tol=1e-14).x
    hand = root(lambda v: eqs(v, False), [1.0, 1.0], tol=1e-14).x
    split = root(lambda v: eqs(v, True), [1.0, 1.0], tol=1e-14).x
    assert np.allclose(ours, hand, rtol=1e-10)
    assert ours[1] / ours[0] > 1.001            # fibres resist: stretched less along them
    assert abs(split[1] / split[0] - 1.0) < 1e-12
    p = -0.3 * MU
    comp = root(eqs, [1.0, 1.0], tol=1e-14).x
    assert abs(comp[1] / comp[0] - 1.0) < 1e-12 and comp[0] < 1.0


# ------------------------------------------------------------------------ fibre field
def test_fibre_direction_is_the_material_line_tangent():
    """follow: twist gives d place(x, P)/dx normalised: inclined by atan(ρψ/L)."""
    from ancf_petsc.physics.geometry import place
    rng = np.random.default_rng(2)
    L, psi, axis = 0.07, 45.0, np.array([0.002, -0.001])
    x = rng.uniform(0, L, 20)
    P = rng.uniform(-0.01, 0.01, (20, 2))
    a0 = fibre_directions(x, P, L, psi, axis, centroid=(0.0, 0.0))[0]
    h = 1e-6
    t = (place(x + h, P, L, psi, axis) - place(x - h, P, L, psi, axis)) / (2 * h)
    assert np.allclose(a0, t / np.linalg.norm(t, axis=1, keepdims=True), atol=1e-9)
    rho = np.linalg.norm(P - axis, axis=1)
    assert np.allclose(np.arccos(a0[:, 0]), np.arctan(rho * np.deg2rad(psi) / L), atol=1e-12)
    axial = fibre_directions(x, P, L, psi, axis, (0.0, 0.0), follow="axis")[0]
    assert np.allclose(axial, [1.0, 0.0, 0.0])
    # extra twist about the centroid c: the helix angle grows with the distance from c
    c = np.array([0.004, 0.0])
    extra = fibre_directions(x, P, L, 0.0, axis, c, follow="axis", extra_twist_deg=30.0)[0]
    assert np.allclose(np.arccos(extra[:, 0]),
                       np.arctan(np.linalg.norm(P - c, axis=1) * np.deg2rad(30.0) / L), atol=1e-12)
    # a fixed angle: 90 deg without twist is the section's y axis, 30 deg is 30 deg off x
    turned = fibre_directions(x, P, L, 0.0, axis, c, follow="axis", angles_deg=(90.0, 30.0))
    assert np.allclose(turned[0], [0.0, 1.0, 0.0]) and np.allclose(turned[1, :, 0], np.cos(np.pi / 6))


# -------------------------------------------------------------------- FD of the residual
def _model(twist_deg, angle, kappa):
    raw = load_raw("pretwisted_bar.yaml")
    raw["geometry"]["twist_deg"] = twist_deg
    raw["beams"][0]["elements"] = 3
    raw["beams"][0]["material"] = goh_material(kappa, follow="twist", angle=angle)
    return build_model(parse_config(raw, base_dir=CONFIGS))


@pytest.mark.parametrize("twist_deg", [0.0, 60.0])
@pytest.mark.parametrize("angle", [0.0, 30.0, 90.0])
def test_tangent_matches_finite_differences_of_the_residual(monkeypatch, twist_deg, angle):
    """Element tangents (three elements, processed in chunks of one) against central differences
    of the element residual ≤ 1e-6, in a stretched state where every fibre is in tension."""
    monkeypatch.setattr(kernels, "CHUNK_POINTS", 1)
    model = _model(twist_deg, angle, 0.15)
    beam = model.beams[0]
    (G, w, mat), = model.element_data(beam, np.arange(beam.n_elements))
    assert mat.a0.shape == (1,) + w.shape + (3,)
    q0e = model.q0[beam.connectivity].reshape(beam.n_elements, 18, 3)
    rng = np.random.default_rng(11)
    q = q0e * np.array([1.06, 1.05, 1.04]) + 2e-3 * rng.standard_normal(q0e.shape) \
        * np.abs(q0e).max(axis=(0, 1))
    Fg = kernels.deformation_gradient(q, G)
    assert np.all(mat._fibres(Fg)[0][4])           # all fibres on: no kink inside the differences
    f, Kt, _ = kernels.internal_force_and_tangent(q, G, w, mat)
    assert np.allclose(f, kernels.internal_force(q, G, w, mat)[0], rtol=1e-13, atol=1e-13 * np.abs(f).max())
    h = 1e-7 * np.abs(q0e).max()
    Kfd = np.zeros_like(Kt)
    flat = q.reshape(len(q), 54)
    for j in range(54):
        dq = np.zeros(54)
        dq[j] = h
        fp = kernels.internal_force((flat + dq).reshape(-1, 18, 3), G, w, mat)[0]
        fm = kernels.internal_force((flat - dq).reshape(-1, 18, 3), G, w, mat)[0]
        Kfd[:, :, j] = (fp - fm) / (2 * h)
    err = np.abs(Kt - Kfd).max() / np.abs(Kt).max()
    assert err <= 1e-6, err
    assert np.allclose(Kt, np.swapaxes(Kt, 1, 2), atol=1e-11 * np.abs(Kt).max())


def test_model_fibres_follow_the_pretwist_at_the_gauss_points():
    model = _model(60.0, 0.0, 0.0)
    beam = model.beams[0]
    a0 = beam.fibres[0]                                            # (E, P, 3)
    P = beam.section.centroid + beam.yz                            # tendon frame, at x = 0
    rho = np.linalg.norm(P - np.asarray(model.spec.twist_axis), axis=1)
    assert np.allclose(np.arccos(a0[..., 0]), np.arctan(rho * np.deg2rad(60.0) / 0.1)[None, :])


def test_fibres_on_imported_sections_that_vary_along_x(tmp_path):
    """configs/geometry_stations_demo.yaml (three outlines from two NIfTI slices, the far one
    smaller and turned: per-element section rules) with GOH and a pretwist: every Gauss point's
    fibre is the material line's tangent at that point (a central difference of
    ``geometry.place``), and the model runs.  The sections' measured turn changes the integration
    domain, not the material lines (docs/geometry.md), so the fibres follow the pretwist only."""
    from ancf_petsc.physics.fibres import gauss_point_stations
    from ancf_petsc.physics.geometry import place
    raw = load_raw("geometry_stations_demo.yaml")
    raw["geometry"]["twist_deg"] = 30.0
    for b in raw["beams"]:
        b["material"] = dict(goh_material(0.0, follow="twist", extra=10.0), mu=float(b["material"]["mu"]),
                             bulk_modulus=float(b["material"]["bulk_modulus"]), k1=50.0e6)
    model = build_model(parse_config(copy.deepcopy(raw), base_dir=CONFIGS))
    L, psi, axis = model.spec.length, 30.0, np.asarray(model.spec.twist_axis)
    for beam in model.beams:
        assert beam.yz.ndim == 3                                   # per-element rules
        x = gauss_point_stations(beam.x_nodes, beam.xi)            # (E, P)
        P = beam.section.centroid + beam.yz                        # tendon frame at x = 0
        h, pts, xs = 1e-6 * L, P.reshape(-1, 2), x.ravel()
        t = (place(xs + h, pts, L, psi, axis) - place(xs - h, pts, L, psi, axis)) / (2 * h)
        # plus the extra twist: rate 10°/L about the beam's axis (its centroid c), turned by ψx/L
        lever = np.deg2rad(10.0) / L * (pts - beam.section.centroid)
        th = np.deg2rad(psi) * xs / L
        Rl = np.stack([np.cos(th) * lever[:, 0] - np.sin(th) * lever[:, 1],
                       np.sin(th) * lever[:, 0] + np.cos(th) * lever[:, 1]], -1)
        t += np.column_stack([np.zeros(len(xs)), -Rl[:, 1], Rl[:, 0]])
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        assert np.abs(beam.fibres[0].reshape(-1, 3) - t).max() < 1e-8
    raw["output"] = {"vtk": False}
    raw["steps"] = [0.5, 1.0]
    s = run_inline(raw, tmp_path / "run")
    assert s["status"] == "completed" and s["steps"][-1]["probes"]["soleus"]["displacement"][0] > 0


# ------------------------------------------------------------------------ config errors
@pytest.mark.parametrize("change,path,words", [
    ({"k1": -1.0}, "beams[0].material.k1", ">= 0"),
    ({"k2": 0.0}, "beams[0].material.k2", "> 0"),
    ({"kappa": 0.4}, "beams[0].material.kappa", "<= 0.333333"),
    ({"kappa": -0.1}, "beams[0].material.kappa", ">= 0"),
    ({"fibres": {"follow": "helix"}}, "beams[0].material.fibres.follow", "twist, axis"),
    ({"fibres": {"angle_deg": 120}}, "beams[0].material.fibres.angle_deg", "<= 90"),
    ({"fibres": {"pitch": 3}}, "beams[0].material.fibres.pitch", "allowed here"),
    # the allowed range with a NaN (was 'must be finite'), the value's digits where %g rounds it
    # onto the bound (was 'must be <= 0.333333 ...; got 0.333333'), a missing k1 by its key path
    ({"kappa": float("nan")}, "beams[0].material.kappa", "finite number >= 0 and <= 0.333333 (fibre"),
    ({"kappa": 0.33333334}, "beams[0].material.kappa", "<= 0.333333 (fibre dispersion: 0 aligned, "
                                                       "1/3 isotropic); got 0.33333334"),
    ({"k1": None}, "beams[0].material.k1", "missing value"),
    # one family twice (accepted: k1 doubled along it, no word); +90 and -90 are one line
    ({"fibres": {"angle_deg": [10, 10]}}, "beams[0].material.fibres.angle_deg[1]",
     "the same fibre family as angle_deg[0] (10 deg)"),
    ({"fibres": {"angle_deg": [90, 30, -90]}}, "beams[0].material.fibres.angle_deg[2]",
     "angle_deg[0] (90 deg; +90 and -90 are one line)"),
])
def test_bad_goh_values_are_refused_with_key_path(change, path, words):
    raw = load_raw("pretwisted_bar.yaml")
    raw["beams"][0]["material"] = dict(goh_material(0.1, follow="twist"), **change)
    with pytest.raises(ConfigError) as exc:
        parse_config(raw, base_dir=CONFIGS)
    assert exc.value.path == path and words in str(exc.value)


def test_a_fibre_family_given_twice_in_a_bundle_names_the_bundles_keys():
    """The bundle's error names bundle.material..., and its message no generated beams[0] key."""
    raw = load_raw("bundle_hex7.yaml")
    raw["bundle"]["material"] = dict(goh_material(0.1, follow="twist", angle=[5.0, 5.0]))
    with pytest.raises(ConfigError) as exc:
        parse_config(raw, base_dir=CONFIGS)
    assert exc.value.path == "bundle.material.fibres.angle_deg[1]" and "beams[" not in str(exc.value)


def test_fibre_keys_on_an_isotropic_law_are_refused():
    raw = load_raw("pretwisted_bar.yaml")
    raw["beams"][0]["material"]["k1"] = 1.0e6
    with pytest.raises(ConfigError, match="model: goh") as exc:
        parse_config(raw, base_dir=CONFIGS)
    assert exc.value.path == "beams[0].material.k1"         # the key, not its mapping


@pytest.mark.parametrize("material,key,words", [
    (dict(goh_material(0.1), E=1e6), "E", "for model: goh (a key of model: svk); allowed here: bulk_modulus, "
                                          "c10, d, fibres, k1, k2, kappa, model, mu"),
    ({"model": "neo-hookean", "E": 1e6, "nu": 0.3}, "E", "for model: neo-hookean (a key of model: svk)"),
    ({"model": "svk", "E": 1e6, "nu": 0.3, "bulk_modulus": 1e7}, "bulk_modulus", "allowed here: E, model, nu"),
    ({"model": "neo-hookean", "mu": 1e6, "bulk_modulus": 1e7, "mue": 1}, "mue", "allowed here: bulk_modulus, c10"),
])
def test_a_key_of_another_model_is_named_with_the_keys_of_this_one(material, key, words):
    """A goh material's unknown key listed 'allowed here: bulk_modulus, model, mu' (its matrix's
    keys, as if k1, k2, kappa and fibres were not allowed); the keys of each model now, and whose
    key it is."""
    raw = load_raw("pretwisted_bar.yaml")
    raw["beams"][0]["material"] = material
    with pytest.raises(ConfigError) as exc:
        parse_config(raw, base_dir=CONFIGS)
    assert exc.value.path == f"beams[0].material.{key}" and words in exc.value.message
    assert exc.value.kind == "unknown_key"


@pytest.mark.parametrize("ratio,tol", [(5.0, 0.05), (50.0, 0.2)])
def test_surface_fibre_stress_is_recovered_from_the_axial_gauss_stations(tmp_path, ratio, tol):
    """The VTU's fibre stress took the law's stress at each sample, whose F between and beyond the
    axial Gauss stations the solve does not hold: on configs/bending_neohookean.yaml's cantilever
    (3363, 2 axial points, 4 elements, load factor 0.2; GOH with k1 = 0, fibres along x: the
    matrix's sigma_xx) the top and bottom stress was 0.22-3.3x beam theory's -M z / I at
    K = 5 mu and -10 to +34x at K = 50 mu, largest at the element ends.  Now the Cauchy stress of
    the Gauss stations is interpolated along xi (io/vtk.py AxialRecovery): within 5 % and 20 %
    (3363's own volumetric locking at K = 50 mu: 0.88-1.08x at the Gauss points) everywhere but
    the loaded end's last 15 %."""
    import glob

    import meshio
    raw = load_raw("bending_neohookean.yaml")
    raw["beams"][0].update(elements=4, material=dict(goh_material(), k1=0.0, bulk_modulus=ratio * MU))
    raw["steps"], raw["output"] = [0.2], {"vtk": True}
    assert run_inline(raw, tmp_path)["status"] == "completed"
    mesh = meshio.read(sorted(glob.glob(str(tmp_path / "**" / "surface_*.vtu"), recursive=True))[-1])
    r0 = mesh.points - mesh.point_data["displacement"]
    h, L = 0.01, raw["geometry"]["length"]
    pts = (np.abs(np.abs(r0[:, 2]) - 0.5 * h) < 1e-9) & (r0[:, 0] < 0.85 * L)
    moment = raw["loads"][0]["traction_force"][2] * raw["steps"][0] * (L - r0[pts, 0])
    beam_theory = -moment * r0[pts, 2] / (h ** 4 / 12.0)
    err = mesh.point_data["fibre_stress"][pts] / beam_theory - 1.0
    assert pts.sum() >= 100 and np.all(np.abs(err) < tol), (err.min(), err.max())
