"""``locking: mixed`` (physics/mixed.py): the volumetric term on the dilatation projected per axial
station onto {1, y, z}.  The projection against hand-made fields, the tangent against finite
differences of the residual (and the residual against the energy's), homogeneous states against
their exact solutions, the config's refusal of a law without a volumetric term, 1/2/3 ranks."""
import os

import numpy as np
import pytest

from ancf_petsc.physics import kernels
from ancf_petsc.physics.materials import NeoHookean
from ancf_petsc.physics.mixed import ProjectedDilatation, pressure_basis
from helpers import (assert_same_as_serial, build_problem, assert_jacobian_and_gradient, load_raw, perturbed_state,
                     probes_table, run_inline, run_on_ranks, solve_cli, two_beam_twisted, write_config)
from test_goh import goh_material, one_element_run, uniaxial_exact

GOH_TWISTED = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 30.0e6, "k1": 2.0e6, "k2": 5.0, "kappa": 0.1,
               "fibres": {"follow": "twist", "angle_deg": 30.0, "extra_twist_deg": 15.0}}


def _station_rule(rng, stations=2, n=12):
    yz = rng.uniform(-1e-3, 1e-3, (stations * n, 2)) + [2e-3, -1e-3]
    return yz, rng.uniform(0.5, 1.5, stations * n)


def test_the_projection_keeps_its_space_and_is_orthogonal_to_the_rest():
    """θ = Π J: a field linear in (y, z) per station comes back to rounding; for a ρ² field the
    remainder J − θ is orthogonal to every pressure mode (Σ w φ (J − θ) = 0), and θ ≠ J."""
    rng = np.random.default_rng(3)
    yz, wq = _station_rule(rng)
    Phi = pressure_basis(yz, wq, 2)
    assert Phi.shape == (24, 6) and np.all(Phi[:12, 3:] == 0) and np.all(Phi[12:, :3] == 0)
    w = wq[None] * rng.uniform(0.8, 1.2, (3, 24))          # three elements, det J0 varying
    law = ProjectedDilatation(NeoHookean(1.0, 10.0), Phi).on(w)
    station = np.repeat([0, 1], 12)
    a, b, c = rng.normal(size=(3, 3, 2))
    linear = 1.0 + a[:, station] + 40 * b[:, station] * yz[:, 0] + 70 * c[:, station] * yz[:, 1]
    F = np.zeros((3, 24, 3, 3))
    F[..., 0, 0] = linear
    F[..., 1, 1] = F[..., 2, 2] = 1.0
    assert np.allclose(law.dilatation(F), linear, rtol=0, atol=1e-13)
    rho2 = 1.0 + 1e5 * (yz ** 2).sum(axis=1)
    F[..., 0, 0] = rho2
    theta = law.dilatation(F)
    assert np.abs(theta - rho2).max() > 1e-2
    moments = np.einsum("ep,pm->em", w * (rho2 - theta), Phi)
    assert np.abs(moments).max() < 1e-14 * np.sum(w * rho2)


@pytest.mark.parametrize("material", ["neo-hookean", "goh"])
def test_jacobian_matches_finite_differences(material):
    """Two pretwisted 3363 beams with ``locking: mixed`` (neo-Hookean, or GOH with fibres at 30°
    to the material lines, extra twist, dispersion): the assembled Jacobian against central
    differences of the residual, and the residual against the energy's."""
    raw = two_beam_twisted()
    for b in raw["beams"]:
        b["locking"] = "mixed"
        b["material"] = {"model": "neo-hookean", "mu": 1.0e6, "bulk_modulus": 30.0e6} \
            if material == "neo-hookean" else dict(GOH_TWISTED)
    P, _ = build_problem(raw)
    assert all(isinstance(blk.parts[0][2], ProjectedDilatation) for blk in P.blocks)
    P.load_factor = 0.7
    rng = np.random.default_rng(1)
    X, free = perturbed_state(P, rng, 2e-3)
    P.jacobian(None, X, P.J, P.J)
    assert_jacobian_and_gradient(P, X, free, rng, gradient_rel=1e-6)


def test_element_tangent_on_sections_varying_along_x_matches_finite_differences():
    """Per-element section rules (configs/geometry_stations_demo.yaml): the pressure basis per
    element; two elements' tangents against central differences, and symmetric."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from helpers import CONFIGS
    raw = load_raw("geometry_stations_demo.yaml")
    for b in raw["beams"]:
        b["locking"] = "mixed"
    model = build_model(parse_config(raw, base_dir=CONFIGS))
    beam = next(b for b in model.beams if b.ring_at is not None)
    G, w, law = model.element_data(beam, np.arange(2))[0]
    assert law.basis.ndim == 3 and law.basis.shape[:2] == w.shape
    rng = np.random.default_rng(5)
    q0 = model.q0[beam.connectivity[:2]][:, :, list(beam.vectors)].reshape(2, -1, 3)
    q = q0 + 1e-4 * rng.standard_normal(q0.shape)
    f, K, _ = kernels.internal_force_and_tangent(q, G, w, law)
    assert np.abs(K - K.transpose(0, 2, 1)).max() <= 1e-12 * np.abs(K).max()      # an energy's Hessian
    h = 1e-8
    for _ in range(3):
        v = rng.standard_normal(q.shape)
        fp = kernels.internal_force(q + h * v, G, w, law)[0]
        fm = kernels.internal_force(q - h * v, G, w, law)[0]
        Kv = np.einsum("eij,ej->ei", K, v.reshape(2, -1))
        assert np.abs(Kv - (fp - fm) / (2 * h)).max() <= 1e-6 * np.abs(Kv).max()


@pytest.mark.parametrize("element", [3363, 33103])
def test_neo_hookean_uniaxial_tension_is_exact(tmp_path, element):
    """A homogeneous state has J constant, so θ = J and the law's own stress: one element in
    uniaxial tension is exact (3363 and 33103; 3333's J is linear across the section already,
    where mixed projects it, so 3333 refuses mixed: tests/config/test_config_errors.py)."""
    from ancf_petsc.physics.reference_solutions import uniaxial_stretches
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0].update({"element": element, "locking": "mixed"})
    raw["output"]["vtk"] = False
    s = run_inline(raw, tmp_path)
    mat = NeoHookean(1.0e6, 50.0e6)
    area = next(iter(s["sections"].values()))["area"]
    for step in s["steps"]:
        lam, _ = uniaxial_stretches(mat, step["load_factor"] * 45.0 / area)
        u = step["probes"]["tip"]["displacement"]
        assert u[0] == pytest.approx((lam - 1.0) * 0.1, rel=1e-9)


@pytest.mark.parametrize("kappa", [0.0, 0.2])
@pytest.mark.parametrize("direction", ["along", "across"])
def test_goh_uniaxial_tension_is_exact(tmp_path, kappa, direction):
    """GOH with ``locking: mixed``, fibres along x or across: the homogeneous exact solution to 1e-8
    (the root finding of tests/physics/test_goh.py, written from the energy by hand)."""
    fibre_axis, angle = (0, 0.0) if direction == "along" else (1, 90.0)
    summary, s, raw = one_element_run(tmp_path, goh_material(kappa, angle=angle), 1.12, fibre_axis, kappa,
                                      "run", locking="mixed")
    assert summary["status"] == "completed"
    for step in summary["steps"]:
        lam = uniaxial_exact(step["load_factor"] * s, fibre_axis, kappa)
        u = step["probes"]["tip"]["displacement"]
        assert abs(u[0] / ((lam[0] - 1.0) * raw["geometry"]["length"]) - 1.0) < 1e-8


def test_a_law_without_a_volumetric_term_is_refused(tmp_path):
    """SVK has no decoupled K/2 (J − 1)²: one line naming the key path and the fix, exit non-zero."""
    raw = load_raw("elastica_svk.yaml")
    raw["beams"][0]["locking"] = "mixed"
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), cwd=str(tmp_path))
    assert p.returncode != 0
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "beams[0].locking" in lines[0] and "'none'" in lines[0], p.stderr
    assert "Traceback" not in p.stderr


@pytest.mark.mpi
@pytest.mark.slow
def test_pretwisted_goh_bar_ranks_agree_with_serial(tmp_path):
    """configs/pretwisted_bar.yaml with a GOH law (two families, extra twist) and ``locking:
    mixed``: each rank binds its elements' weights; 1, 2 and 3 ranks give the same probes."""
    raw = load_raw("pretwisted_bar.yaml")
    raw["beams"][0]["material"] = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 50.0e6, "k1": 2.0e6,
                                   "k2": 5.0, "kappa": 0.1,
                                   "fibres": {"follow": "twist", "angle_deg": [15.0, -15.0],
                                              "extra_twist_deg": 20.0}}
    raw["beams"][0].update(elements=6, locking="mixed")
    runs = run_on_ranks(raw, tmp_path, ranks=(1, 2, 3))
    tables = {n: probes_table(s) for n, (_, s) in runs.items()}
    assert_same_as_serial(tables)
    assert abs(tables[1][-1]).max() > 1e-3


@pytest.mark.parametrize("case", ["tension", "bending", "pretwisted", "soleus"])
def test_the_solid_comparison_bars_stay_within_1_percent(tmp_path, case):
    """The bars of docs/solid_comparison.md (K/μ = 50 and the soleus' 8.34), 8 elements, with
    ``locking: mixed``: the end-centroid displacement within 1 % of the committed converged solid
    answer (docs/solid_comparison.csv; docs/locking.md has every element count)."""
    import csv
    from ancf_verify.bars.cases import CASES, ancf_config   # the bars' ANCF configs (no dolfinx)
    from helpers import ROOT
    with open(os.path.join(ROOT, "docs", "solid_comparison.csv"), newline="") as fh:
        ref = next(np.array([float(r[f"ref_u{c}_m"]) for c in "xyz"]) for r in csv.DictReader(fh) if r["case"] == case)
    raw = ancf_config(next(c for c in CASES if c.key == case), 8, 2, str(tmp_path))
    raw["beams"][0]["locking"] = "mixed"
    u = np.array(run_inline(raw, tmp_path)["steps"][-1]["probes"]["tip"]["displacement"])
    assert np.linalg.norm(u - ref) < 0.01 * np.linalg.norm(ref)


def test_a_point_force_on_a_mixed_beam_is_warned_about():
    """The paper's point force on r with ``locking: mixed``: one warning naming the load's key and
    the alternative (traction_force); none for a traction or without the remedy."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from helpers import CONFIGS
    raw = load_raw("achilles_type3_psi45.yaml")
    plain = build_model(parse_config(raw, base_dir=CONFIGS)).warnings
    raw["beams"][0]["locking"] = "mixed"
    mixed = build_model(parse_config(raw, base_dir=CONFIGS)).warnings
    assert [w for w in mixed if w not in plain] == [w for w in mixed if "locking: mixed" in w]
    new = [w for w in mixed if w not in plain]
    assert len(new) == 1 and new[0].startswith("warning: loads[0]") and "traction_force" in new[0]
    raw["loads"][0] = {"beam": "soleus", "node": "last", "traction_force": [1.0, 0.0, 0.0]}
    assert not [w for w in build_model(parse_config(raw, base_dir=CONFIGS)).warnings if "mixed" in w]


def test_grouped_pressure_columns_span_the_spaces_they_name():
    """``BeamSpec.pressure_columns`` (a locking diagnosis, scripts/locking_study.py space):
    [[0], [1], [2]] is ``locking: mixed``'s own {1, y, z} basis column for column; [[0], [1], [2],
    [3, 5]] adds y² + z² per station, the sum of the quadratic basis's columns 3 and 5."""
    from ancf_petsc.physics.cubature import ellipse_rule, gauss_legendre
    from ancf_petsc.physics.mixed import grouped_basis, pressure_basis
    pts, w = ellipse_rule(0.006, 0.004, 6)
    xa, wa = gauss_legendre(2)
    yz, wq = np.tile(pts, (2, 1)), np.repeat(wa, len(w)) * np.tile(w, 2)
    assert np.array_equal(grouped_basis(yz, wq, 2, [[0], [1], [2]]), pressure_basis(yz, wq, 2))
    B2 = pressure_basis(yz, wq, 2, degree=2)
    G = grouped_basis(yz, wq, 2, [[0], [1], [2], [3, 5]])
    assert G.shape == (len(yz), 8) and np.allclose(G[:, 7], B2[:, 9] + B2[:, 11])


def test_fibre_stress_under_locking_mixed_is_the_solved_stress(tmp_path):
    """The surface fibre_stress of a ``locking: mixed`` GOH beam took the matrix's pressure from
    the pointwise J, not the projected θ the solution has: on the pretwisted bar at 180 deg
    (4 elements, 30 N) up to 0.29 MPa (24 % of the largest) off at the Gauss points.  Now θ at
    each sampled station (J fitted over the section rule by weighted least squares in {1, y, z},
    here by hand) gives the stress: the first element's samples to single precision."""
    import glob

    import h5py
    import meshio
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from ancf_petsc.model.fibre_setup import directions_at
    from ancf_petsc.physics import element3363 as el
    from helpers import CONFIGS
    raw = load_raw("pretwisted_bar.yaml")
    raw["geometry"]["twist_deg"] = 180.0
    raw["beams"][0].update(locking="mixed", material=goh_material(0.15, follow="twist", angle=25.0))
    raw["loads"][0]["traction_force"] = [30.0, 0.0, 0.0]
    raw["steps"] = [1.0]
    raw["output"].update(vtk=True, vtk_samples=3)
    assert run_inline(raw, tmp_path)["status"] == "completed"
    data = meshio.read(sorted(glob.glob(str(tmp_path / "surface_*.vtu")))[-1]).point_data["fibre_stress"]
    model = build_model(parse_config(raw, base_dir=CONFIGS))
    beam = model.beams[0]
    with h5py.File(tmp_path / "results.h5") as h5:
        q = h5["steps"][sorted(h5["steps"])[-1]]["nodal_vectors"][()]
    qe, q0e = (a[beam.connectivity[0]].reshape(18, 3) for a in (q, model.q0))
    ring = beam.section.boundary_polyline(6)              # as the sampler (an open ring here)
    ring = ring[:-1] if np.allclose(ring[0], ring[-1]) else ring
    n = len(beam.yz) // beam.axial_points
    sec, w = beam.yz[:n], beam.wq[:n]
    law = model.element_data(beam, np.arange(1))[0][2].law
    for s, xi in enumerate(np.linspace(-1.0, 1.0, 4)):
        def at(pts):
            _, dN = model.block.shape_functions(np.full(len(pts), xi), pts[:, 0], pts[:, 1])
            G, det = el.reference_gradients(q0e[None], dN)
            return np.einsum("si,psj->pij", qe, G[0]), det[0]
        F, det = at(sec)
        A = np.column_stack([np.ones(n), sec]) * np.sqrt(det * w)[:, None]
        coef = np.linalg.lstsq(A, np.linalg.det(F) * np.sqrt(det * w), rcond=None)[0]
        Fr, _ = at(ring)
        theta = coef[0] + ring @ coef[1:]
        x = beam.x_nodes[0] + 0.5 * (xi + 1.0) * (beam.x_nodes[2] - beam.x_nodes[0])
        a0 = directions_at(beam, np.full(len(ring), x), ring, model.spec.length, model.spec.twist_deg,
                           model.spec.twist_axis)
        expect = law.with_directions(a0).fibre_cauchy_stress(Fr, theta)[0]
        got = data[s * len(ring):(s + 1) * len(ring)]
        assert np.allclose(got, expect, rtol=2e-6, atol=1e-6 * np.abs(expect).max()), (s, got, expect)
        pointwise = law.with_directions(a0).fibre_cauchy_stress(Fr)[0]
        assert np.abs(pointwise - expect).max() > 1e-3 * np.abs(expect).max()     # the test sees θ
