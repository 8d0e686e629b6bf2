"""The compiled element kernels (physics/element_kernels.pyx, issue 40) against the numpy kernels
they stand in for (kernels.py, materials.py, goh.py): force, tangent and min J on deformed
elements 3333, 3363, 33103 and 33153 for the neo-Hookean law and every GOH variant (dispersion, the
tension-only switch, two families), their tangent against their own residual by central
differences, the dispatch (which laws run compiled), and that they are built wherever Cython is.
The summation order differs from numpy's, so the answers agree to rounding, not bitwise."""
import os

import h5py
import numpy as np
import pytest

from ancf_petsc import native
from ancf_petsc.physics import element3363 as el, kernels
from ancf_petsc.physics.cubature import gauss_legendre
from ancf_petsc.physics.elements import ELEMENTS
from ancf_petsc.physics.goh import GOH
from ancf_petsc.physics.materials import NeoHookean, StVenantKirchhoff
from ancf_petsc.physics.mixed import ProjectedDilatation, pressure_basis

#: measured max relative difference (max |Δ| / max |numpy|) over the cases below: force 1.35e-15,
#: tangent 6.6e-16, min J 2.2e-16 (numpy 1.24, OpenBLAS 0.3.21)
RTOL = 1e-12
UNIT = {"r": (1.0, 0.0, 0.0), "r_y": (0.0, 1.0, 0.0), "r_z": (0.0, 0.0, 1.0)}


@pytest.fixture(scope="module")
def compiled():
    module = native.load(kernels.COMPILED)
    if module is None:
        pytest.skip(native.status(kernels.COMPILED))
    return module


def deformed_block(name: str, n_el: int = 3, seed: int = 0, stretch: float = 1.05, noise: float = 0.02):
    """qe (E, S, 3), G (E, P, S, 3) stored as Model.element_data stores it, w (E, P) and the
    points' axial positions (E, P) of a straight beam of element ``name`` stretched along x
    with random nodal noise (det F > 0)."""
    e = ELEMENTS[name]
    rng = np.random.default_rng(seed)
    xa, wa = gauss_legendre(3)
    yz = rng.uniform(-2e-3, 2e-3, (5, 2))
    xi, y, z = el.tensor_points(xa, yz)
    _, dN = e.shape_functions(xi, y, z)
    h = 0.01
    names = [e.block.names[v] for v in e.vectors]
    q0 = np.zeros((n_el, 3, len(names), 3))
    for k, nm in enumerate(names):
        q0[:, :, k] = UNIT.get(nm, (0.0, 0.0, 0.0))
    q0[:, :, names.index("r"), 0] = h * (np.arange(n_el)[:, None] + 0.5 * np.arange(3)[None, :])
    q0 = q0.reshape(n_el, -1, 3)
    G, det = el.reference_gradients(q0, dN)
    G = np.ascontiguousarray(G.transpose(0, 2, 1, 3)).transpose(0, 2, 1, 3)
    scale = np.where(np.array(names * 3) == "r", h, 1.0)[None, :, None]
    qe = q0 * np.array([stretch, 1.0, 1.0]) + noise * rng.standard_normal(q0.shape) * scale
    w = det * np.repeat(wa, len(yz))[None] * 1e-6
    return qe, G, w, np.broadcast_to(xi, w.shape)


def goh(kappa=0.1, angles=(0.0,), e_rounding=1e-12, shape=None, seed=1) -> GOH:
    """A GOH law bound to random unit fibres near the axis, one per point and family."""
    law = GOH(1e6, 5e7, 2e6, 5.0, kappa, {"follow": "twist", "extra_twist_deg": 0.0,
                                            "angles_deg": angles}, e_rounding=e_rounding)
    a0 = np.array([1.0, 0.0, 0.0]) + 0.3 * np.random.default_rng(seed).standard_normal((len(angles),) + shape + (3,))
    return law.with_directions(a0 / np.linalg.norm(a0, axis=-1, keepdims=True))


def laws(shape):
    return {"nh": NeoHookean(1e6, 5e7), "nh-no-mu": NeoHookean(0.0, 5e7), "nh-no-K": NeoHookean(1e6, 0.0),
            "goh-aligned": goh(0.0, shape=shape), "goh-dispersed": goh(0.1, shape=shape),
            "goh-two-families": goh(0.05, (30.0, -30.0), shape=shape),
            "goh-nine-families": goh(0.02, tuple(range(-40, 50, 10)), shape=shape),
            "goh-exact-switch": goh(0.1, e_rounding=0.0, shape=shape),
            "goh-isotropic-fibres": goh(1.0 / 3.0, shape=shape)}


def numpy_reference(monkeypatch, fn, *args):
    with monkeypatch.context() as m:
        m.setenv("ANCF_NATIVE", "0")
        return fn(*args)


def assert_close(a, b, what):
    scale = np.max(np.abs(b))
    assert np.max(np.abs(a - b)) <= RTOL * scale, (what, np.max(np.abs(a - b)) / scale)


@pytest.mark.parametrize("name", ["3333", "3363", "33103", "33153"])
@pytest.mark.parametrize("stretch", [1.05, 0.97])     # 0.97: fibres in compression, switched off
def test_compiled_equals_numpy(compiled, monkeypatch, name, stretch):
    qe, G, w, _ = deformed_block(name, stretch=stretch)
    for key, law in laws(w.shape).items():
        fast = kernels.compiled_law(law, w.shape)
        assert fast is not None, key
        f0, K0, J0 = numpy_reference(monkeypatch, kernels.internal_force_and_tangent, qe, G, w, law)
        r0, Jr0 = numpy_reference(monkeypatch, kernels.internal_force, qe, G, w, law)
        for chunk, Gx in ((1, G), (4, G), (0, G), (0, np.ascontiguousarray(G))):   # G in place, copied
            f, K, J = compiled.evaluate(qe, Gx, w, fast[1], fast[2], True, chunk)
            assert_close(f, f0, (key, "force"))
            assert_close(K, K0, (key, "tangent", chunk))
            assert_close(J, J0, (key, "J"))
        r, Jr = kernels.internal_force(qe, G, w, law)
        assert_close(r, r0, (key, "residual"))
        assert np.array_equal(Jr, compiled.evaluate(qe, G, w, fast[1], fast[2], True)[2])


def test_numpy_chunking_and_the_compiled_path_agree(compiled, monkeypatch):
    """The numpy path processes elements in chunks of CHUNK_POINTS points (GOH's fibres taken
    per chunk): every chunk size gives the compiled answer."""
    qe, G, w, _ = deformed_block("3363", n_el=7, seed=3)
    law = goh(0.1, (20.0, -20.0), shape=w.shape)
    f, K, J = kernels.internal_force_and_tangent(qe, G, w, law)
    for points in (1, 2 * w.shape[1], 400):
        monkeypatch.setattr(kernels, "CHUNK_POINTS", points)
        f0, K0, J0 = numpy_reference(monkeypatch, kernels.internal_force_and_tangent, qe, G, w, law)
        assert_close(f, f0, points)
        assert_close(K, K0, points)


def test_negative_weights_and_broadcast_fibres(compiled, monkeypatch):
    """``locking: ecm`` integrates a part with negative weights; a fibre field given once per
    section point broadcasts over the elements."""
    qe, G, w, _ = deformed_block("3363", seed=5)
    w = w * np.where(np.arange(w.shape[0]) % 2, -1.0, 1.0)[:, None]
    law = goh(0.1, shape=(1, w.shape[1]))
    out = kernels.internal_force_and_tangent(qe, G, w, law)
    ref = numpy_reference(monkeypatch, kernels.internal_force_and_tangent, qe, G, w, law)
    for a, b in zip(out, ref):
        assert_close(a, b, "ecm/broadcast")


def test_an_inverted_point_gives_what_numpy_gives(compiled, monkeypatch):
    """J <= 0 at a point: the element's min J is that J and its force is not finite (the
    residual's NaN makes the line search back off, petsc/problem.py)."""
    qe, G, w, _ = deformed_block("3363")
    qe[1, :, 0] *= -1.0                              # element 1 mirrored: J < 0 everywhere
    for law in (NeoHookean(1e6, 5e7), goh(0.1, shape=w.shape)):
        f, K, J = kernels.internal_force_and_tangent(qe, G, w, law)
        f0, K0, J0 = numpy_reference(monkeypatch, kernels.internal_force_and_tangent, qe, G, w, law)
        assert J[1] <= 0.0 and np.isclose(J[1], J0[1], rtol=1e-13)
        assert not np.any(np.isfinite(f[1])) and not np.any(np.isfinite(f0[1]))
        assert_close(f[[0, 2]], f0[[0, 2]], "the other elements")
        assert_close(K[[0, 2]], K0[[0, 2]], "the other elements")


@pytest.mark.parametrize("name", ["3333", "3363"])
def test_compiled_tangent_is_the_derivative_of_the_compiled_residual(compiled, name):
    """K v = (f(q + h v) − f(q − h v)) / 2h for random directions v (central differences)."""
    qe, G, w, _ = deformed_block(name, n_el=2, seed=7)
    rng = np.random.default_rng(8)
    for law in (NeoHookean(1e6, 5e7), goh(0.1, (25.0, -25.0), shape=w.shape)):
        _, K, _ = kernels.internal_force_and_tangent(qe, G, w, law)
        for _ in range(3):
            v = rng.standard_normal(qe.shape) * 1e-3
            h = 1e-4
            fp, _ = kernels.internal_force(qe + h * v, G, w, law)
            fm, _ = kernels.internal_force(qe - h * v, G, w, law)
            fd = (fp - fm) / (2 * h)
            Kv = np.einsum("eij,ej->ei", K, v.reshape(len(v), -1))
            assert np.max(np.abs(Kv - fd)) <= 1e-6 * np.max(np.abs(Kv))


def test_which_laws_run_compiled(compiled):
    """Neo-Hookean and GOH (with their fibres bound) pointwise; everything else numpy."""
    shape = (2, 45)
    assert kernels.compiled_law(NeoHookean(1e6, 5e7), shape) is not None
    assert kernels.compiled_law(goh(shape=shape), shape) is not None
    assert kernels.compiled_law(GOH(1e6, 5e7, 2e6, 5.0), shape) is None       # no fibres bound
    assert kernels.compiled_law(StVenantKirchhoff(3e6, 0.3), shape) is None
    qe, G, w, _ = deformed_block("3363")
    sec = pressure_basis(np.random.default_rng(0).uniform(-1e-3, 1e-3, (15, 2)), np.ones(15), 3)
    mixed = ProjectedDilatation(NeoHookean(1e6, 5e7), sec).on(w)
    assert kernels.compiled_law(mixed, w.shape) is None


def _column(raw: dict, out) -> tuple[dict, np.ndarray]:
    from helpers import run_inline
    summary = run_inline(raw, out)
    with h5py.File(os.path.join(out, "results.h5")) as fh:
        steps = sorted(fh["steps"])
        q = np.stack([fh["steps"][s]["nodal_vectors"][()] for s in steps])
    return summary, q


@pytest.mark.parametrize("config", ["achilles_type3_psi45.yaml", "achilles_type3_psi45_goh_amir.yaml"])
def test_the_columns_are_the_numpy_columns(compiled, monkeypatch, tmp_path, config):
    """The ψ = 45° Table 1 column (neo-Hookean) and a GOH column, compiled and ANCF_NATIVE=0:
    the same Newton iterations, the probes (the Table 1 values) of every step equal to 5e-12 of
    their largest (measured max 9.5e-14 and 4.3e-13) and the nodal vectors of every step to 1e-10
    (measured max 1.6e-12 and 3.8e-12: rounding moves the last Newton iterate within the solver's
    tolerance)."""
    from helpers import load_raw
    raw = load_raw(config)
    fast, q = _column(raw, tmp_path / "compiled")
    monkeypatch.setenv("ANCF_NATIVE", "0")
    ref, q0 = _column(raw, tmp_path / "numpy")
    assert fast["newton_iterations"] == ref["newton_iterations"]
    assert np.max(np.abs(q - q0)) <= 1e-10 * np.max(np.abs(q0))
    for s, s0 in zip(fast["steps"], ref["steps"]):
        for name, p in s0["probes"].items():
            for key, v in p.items():
                if isinstance(v, list):
                    x, x0 = np.array(s["probes"][name][key], float), np.array(v, float)
                    assert np.max(np.abs(x - x0)) <= 5e-12 * np.max(np.abs(x0)), (name, key)
