"""Element 3333 (linear section) and its Poisson-locking remedy (``locking: ecm``)."""
import os

import numpy as np
import pytest

from ancf_petsc.physics import element3363 as el
from helpers import CONFIGS, load_raw, read_summary, run_inline, solve_cli, write_config
from helpers import build_problem as _problem, assert_jacobian_and_gradient, perturbed_state, two_beam_twisted


def test_3333_shape_functions_are_the_linear_section_subset_of_3363():
    rng = np.random.default_rng(7)
    xi, y, z = rng.uniform(-1, 1, (3, 20))
    N18, dN18 = el.shape_functions(xi, y, z)
    N9, dN9 = el.shape_functions(xi, y, z, el.ELEMENT_VECTORS["3333"])
    cols = [6 * node + v for node in range(3) for v in (0, 1, 2)]
    assert N9.shape == (20, 9) and np.array_equal(N9, N18[:, cols]) and np.array_equal(dN9, dN18[:, cols])


GOH_3333 = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 30.0e6, "k1": 2.0e6, "k2": 5.0, "kappa": 0.1,
            "fibres": {"follow": "twist", "angle_deg": 30.0, "extra_twist_deg": 15.0}}


@pytest.mark.parametrize("material", ["neo-hookean", "goh"])
@pytest.mark.parametrize("locking", ["none", "ecm"])
def test_mixed_3363_3333_jacobian_matches_finite_differences(locking, material):
    """With GOH (issue 26) too: under ecm its fibres sit on all three parts (the fibre energy
    cancels in the axis correction), directions on the axis from Beam.fibres_axis."""
    raw = two_beam_twisted()
    raw["beams"][1]["element"] = 3333
    raw["beams"][1]["locking"] = locking
    raw["beams"][1]["material"] = {"model": "neo-hookean", "mu": 1.0e6, "bulk_modulus": 30.0e6} \
        if material == "neo-hookean" else dict(GOH_3333)
    P, PETSc = _problem(raw)
    # ecm: Ψ₀ and its axial-shear part over the section, Ψ on the axis, both subtracted there
    assert P.blocks[1].rows.shape[1] == 27 and len(P.blocks[1].parts) == (5 if locking == "ecm" else 1)
    P.load_factor = 0.7
    rng = np.random.default_rng(1)
    X, free = perturbed_state(P, rng, 2e-3)
    P.jacobian(None, X, P.J, P.J)
    assert_jacobian_and_gradient(P, X, free, rng, gradient_rel=1e-5)
    # the 3333 beam's curvature vectors are held: identity rows, no coupling
    held = P.fixed_mask.reshape(-1, 6, 3)[P.model.beams[1].node_offset:, 3:]
    assert held.all()


@pytest.mark.parametrize("locking", ["none", "ecm"])
def test_3333_uniaxial_tension_is_exact(tmp_path, locking):
    """A linear section contracts uniformly, so one 3333 element is exact in uniaxial tension,
    and ecm leaves homogeneous states untouched (its two axis terms cancel the Ψ₀ integral)."""
    from ancf_petsc.physics.materials import NeoHookean
    from ancf_petsc.physics.reference_solutions import uniaxial_stretches
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0].update({"element": 3333, "locking": locking})
    raw["beams"][0]["section"]["cubature_degree"] = 2
    raw["output"]["vtk"] = False
    s = run_inline(raw, tmp_path)
    mat = NeoHookean(1.0e6, 50.0e6)
    area = next(iter(s["sections"].values()))["area"]
    for step in s["steps"]:
        lam, _ = uniaxial_stretches(mat, step["load_factor"] * 45.0 / area)
        u = step["probes"]["tip"]["displacement"]
        assert u[0] == pytest.approx((lam - 1.0) * 0.1, rel=1e-9)


def cantilever(element, locking, kappa, elements=8, axial_points=2, degree=4, load=0.002):
    """Clamped 0.2 m NH cantilever, 10 mm square, small tip load (linear range, w/L ~ 1 %)."""
    return {"name": "bend", "geometry": {"length": 0.2},
            "beams": [{"name": "b", "section": {"shape": "rectangle", "size": [0.01, 0.01],
                                                "cubature_degree": degree},
                       "material": {"model": "neo-hookean", "mu": 1.0e6, "bulk_modulus": kappa * 1.0e6},
                       "elements": elements, "axial_points": axial_points,
                       "element": element, "locking": locking}],
            "boundary_conditions": [{"beam": "b", "node": "first", "fix": "clamped"}],
            "loads": [{"beam": "b", "node": "last", "force": [0.0, 0.0, load]}],
            "steps": [1.0], "probes": [{"name": "tip", "beam": "b", "node": "last"}],
            "output": {"dir": "unused", "vtk": False}}


def timoshenko_tip(kappa, load=0.002, L=0.2, h=0.01, mu=1.0e6):
    E = 9.0 * kappa * mu / (3.0 * kappa + 1.0)
    return load * L ** 3 / (3.0 * E * h ** 4 / 12.0) + load * L / (5.0 / 6.0 * mu * h * h)


@pytest.mark.parametrize("kappa", [10.0, 100.0, 1000.0])
def test_3333_poisson_locking_and_its_remedy(tmp_path, kappa):
    """Without a remedy the linear section locks (bending stiffness E(1−ν)/((1+ν)(1−2ν)));
    with ecm the tip deflection matches Timoshenko beam theory within 0.2 % at K/μ up to 1000."""
    ref = timoshenko_tip(kappa)
    ecm = run_inline(cantilever("3333", "ecm", kappa), tmp_path / "ecm")["steps"][-1]["probes"]["tip"]
    locked = run_inline(cantilever("3333", "none", kappa), tmp_path / "none")["steps"][-1]["probes"]["tip"]
    assert ecm["displacement"][2] == pytest.approx(ref, rel=2e-3)
    assert locked["displacement"][2] < 0.3 * ref          # 74 % / 97 % / 99.5 % too stiff


def twisted_bar(element, locking, radius=0.005, theta=1.0e-4):
    """A neo-Hookean bar (K/μ = 50, ν = 0.49) on a circular section twisted by ``theta`` at its
    last node (r_y·e_z = θ, r_z·e_y = −θ), free to warp at both ends."""
    hold = {"r": "xyz", "r_y": "xz", "r_z": "xy"}
    return {"name": "torsion", "geometry": {"length": 0.1},
            "beams": [{"name": "bar", "section": {"shape": "circle", "radius": radius},
                       "material": {"model": "neo-hookean", "mu": 1.0e6, "bulk_modulus": 50.0e6},
                       "elements": 2, "element": element, "locking": locking}],
            "boundary_conditions": [{"beam": "bar", "node": "first", "fix": hold},
                                    {"beam": "bar", "node": "last", "name": "grip",
                                     "displacement": {"r_y": {"z": theta}, "r_z": {"y": -theta}}}],
            "loads": [], "steps": [1.0], "output": {"vtk": False}}


@pytest.mark.parametrize("element", ["3333", "3363"])
def test_ecm_twists_a_circular_bar_with_the_shear_modulus(tmp_path, element):
    """St Venant: a circular bar twisted by θ over L carries T = μ J θ / L, J = π r⁴ / 2.  ecm's
    ν = 0 law over the section shears with μ₀ = E/2 = μ (1 + ν), and torsion's shear vanishes on
    the axis where ecm corrects: the torque was 1.49 μ J θ / L (K/μ = 50), and 3363 + ecm ended
    'unstable'.  Its axial-shear part (physics/axial_shear.py) gives μ back."""
    s = run_inline(twisted_bar(element, "ecm"), tmp_path)
    assert s["status"] == "completed"
    torque = s["steps"][-1]["reaction_moments"]["grip"][0]
    exact = 1.0e6 * np.pi * 0.005 ** 4 / 2.0 * 1.0e-4 / 0.1
    assert torque == pytest.approx(exact, rel=1e-6)                  # measured: 1.5e-9


@pytest.mark.mpi
@pytest.mark.slow
def test_3333_achilles_contact_under_mpi_matches_serial(tmp_path):
    """Contact between 3333 beams (held curvature vectors) across 3 METIS ranks = serial."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["element"] = 3333
        b["section"]["cubature_degree"] = 3
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["steps"] = raw["steps"][:6]
    raw["partition"] = {"method": "metis"}
    out = {}
    for n in (1, 3):
        raw["output"] = {"dir": str(tmp_path / f"n{n}"), "vtk": False}
        p = solve_cli(write_config(raw, tmp_path / f"c{n}.yaml"), ranks=n)
        assert p.returncode == 0, p.stdout + p.stderr
        s = read_summary(tmp_path / f"n{n}")
        out[n] = np.array([st["probes"][k]["displacement"] for st in s["steps"] for k in sorted(st["probes"])])
    assert "3333" in p.stdout
    assert np.abs(out[3] - out[1]).max() <= 1e-8 * np.abs(out[1]).max()


def _fibre_cantilever(element, kappa, angles):
    """configs/bending_neohookean.yaml (its tip traction at load factor 0.2: a 7 % of L tip
    deflection) with a GOH law (K = 5 mu, k1 = mu) on element ``element``."""
    raw = load_raw("bending_neohookean.yaml")
    b = raw["beams"][0]
    b.update(element=element, elements=4)
    b["section"]["cubature_degree"] = 8                   # the fibres' tension-only kink, resolved
    b["material"] = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 5.0e6, "k1": 1.0e6, "k2": 5.0,
                     "kappa": kappa, "fibres": {"follow": "axis", "angle_deg": angles}}
    raw["steps"], raw["output"] = [0.2], {"vtk": False}
    return raw


def _warnings(raw):
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    return [w for w in build_model(parse_config(raw, base_dir=CONFIGS)).warnings if ".element: 3333" in w]


@pytest.mark.parametrize("kappa,angles,words", [(0.2, 0.0, "kappa 0.2"), (0.0, [30.0, -30.0], "fibres at 30, -30 deg")])
def test_3333_with_fibres_that_see_lateral_strains_is_warned_about(tmp_path, kappa, angles, words):
    """Dispersed fibres (kappa > 0) or fibres at an angle see the section's lateral strains, which
    3333's linear field cannot vary over the section and ecm frees only in the matrix: the
    cantilever bends 7-9 % stiffer than on 33103 (cubic section; 3363 within 0.5 % of it), where
    fibres along the axis stay within 2 % of it (+0.6 %).  That ran with no word;
    now the header names beams[0].element and the fibres, and the run still completes."""
    tip = {}
    for element, k, a in (("3333", kappa, angles), ("33103", kappa, angles), ("3333", 0.0, 0.0), ("33103", 0.0, 0.0)):
        s = run_inline(_fibre_cantilever(element, k, a), tmp_path / f"{element}_{k}_{len(str(a))}")
        assert s["status"] == "completed"
        tip[element, k, str(a)] = s["steps"][-1]["probes"]["tip"]["displacement"][2]
    assert tip["3333", kappa, str(angles)] / tip["33103", kappa, str(angles)] - 1.0 < -0.05
    assert abs(tip["3333", 0.0, "0.0"] / tip["33103", 0.0, "0.0"] - 1.0) < 0.02
    (w,) = _warnings(_fibre_cantilever("3333", kappa, angles))
    assert w.startswith("warning: beams[0].element: 3333") and words in w and "use element 3363" in w
    assert _warnings(_fibre_cantilever("3333", 0.0, 0.0)) == []          # aligned fibres: no word
    assert _warnings(_fibre_cantilever("3363", kappa, angles)) == []


@pytest.mark.parametrize("fibres", ["off", "along"])
def test_3333_fibre_stress_is_ecms_stress(tmp_path, fibres):
    """The VTU's fibre_stress on 3333 (locking: ecm) is the stress of the energy it solves,
    P0(F) + P(F_axis) - P0(F_axis), at the axial Gauss stations, interpolated along xi (io/vtk.py
    AxialRecovery): on the cantilever (K = 5 mu) its top and bottom at every sampled station but
    the loaded end's last 15 % are within 5 % of beam theory, -M z E / EI with the matrix alone
    (k1 = 0) and, with fibres along x (E_t = E + 4 k1 in tension only), of the bimodular section
    (neutral axis z_n): 0.976-1.006x.  The law's own P(F), of the locked lateral strains, was
    1.6-2.2x those at the stations xi = +-0.5; tension stays exact."""
    import glob

    import meshio
    raw = _fibre_cantilever("3333", 0.0, 0.0)
    mat = raw["beams"][0]["material"]
    if fibres == "off":
        mat["k1"] = 0.0
    raw["output"] = {"vtk": True}
    assert run_inline(raw, tmp_path)["status"] == "completed"
    mesh = meshio.read(sorted(glob.glob(str(tmp_path / "**" / "surface_*.vtu"), recursive=True))[-1])
    r0 = mesh.points - mesh.point_data["displacement"]
    h, L = 0.01, raw["geometry"]["length"]
    E = 9.0 * mat["bulk_modulus"] * mat["mu"] / (3.0 * mat["bulk_modulus"] + mat["mu"])
    Et = E + 4.0 * mat["k1"]
    # bimodular rectangle: neutral axis z_n with Et (h/2 + z_n)^2 = E (h/2 - z_n)^2, stiffness EI_n
    zn = 0.5 * h * (np.sqrt(E) - np.sqrt(Et)) / (np.sqrt(E) + np.sqrt(Et))
    EI = h * (Et * (0.5 * h + zn) ** 3 + E * (0.5 * h - zn) ** 3) / 3.0
    moment = raw["loads"][0]["traction_force"][2] * raw["steps"][0] * (L - r0[:, 0])
    pts = (np.abs(np.abs(r0[:, 2]) - 0.5 * h) < 1e-9) & (r0[:, 0] < 0.85 * L)
    z = r0[pts, 2]
    beam_theory = -moment[pts] * (z - zn) * np.where(z < zn, Et, E) / EI
    ratio = mesh.point_data["fibre_stress"][pts] / beam_theory
    assert pts.sum() >= 40 and np.all(np.abs(ratio - 1.0) < 0.05), ratio
