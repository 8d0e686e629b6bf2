"""Element 3363: shape functions against the paper's eq. (6), kernels against finite differences."""
import numpy as np
import pytest

from ancf_petsc.physics import element3363 as el
from ancf_petsc.physics import kernels
from ancf_petsc.physics.materials import NeoHookean, StVenantKirchhoff


def test_factorised_shape_functions_equal_papers_N1_to_N18():
    rng = np.random.default_rng(3)
    ly, lz = 0.7, 0.3
    xi, eta, zeta = rng.uniform(-1, 1, (3, 40))
    N, _ = el.shape_functions(xi, 0.5 * ly * eta, 0.5 * lz * zeta)
    Np = el.paper_shape_functions(xi, eta, zeta, ly, lz)
    for k in range(1, 19):
        assert np.allclose(N[:, el.slot_of_paper_function(k)], Np[:, k - 1], atol=1e-15), k


def test_shape_function_derivatives_by_finite_differences():
    rng = np.random.default_rng(4)
    xi, y, z = rng.uniform(-1, 1, (3, 10))
    _, dN = el.shape_functions(xi, y, z)
    h = 1e-6
    for d, (dx, dy, dz) in enumerate(np.eye(3) * h):
        fd = (el.shape_functions(xi + dx, y + dy, z + dz)[0]
              - el.shape_functions(xi - dx, y - dy, z - dz)[0]) / (2 * h)
        assert np.allclose(dN[:, :, d], fd, atol=1e-9)


def straight_element(length=0.1, width=0.02, height=0.01, n_ax=3, n_sec=3):
    """One straight element along x centred on y = z = 0, tensor Gauss rule."""
    g, gw = np.polynomial.legendre.leggauss(n_sec)
    yz = np.array([(a * width / 2, b * height / 2) for a in g for b in g])
    wyz = np.array([wa * wb for wa in gw for wb in gw]) * width * height / 4
    xa, wa = np.polynomial.legendre.leggauss(n_ax)
    xi, y, z = el.tensor_points(xa, yz)
    w = np.repeat(wa, len(wyz)) * np.tile(wyz, n_ax)
    _, dN = el.shape_functions(xi, y, z)
    q0 = np.zeros((18, 3))
    for a, x in enumerate(np.array([0.0, 0.5, 1.0]) * length):
        q0[6 * a + 0] = (x, 0, 0)
        q0[6 * a + 1] = (0, 1, 0)
        q0[6 * a + 2] = (0, 0, 1)
    G, det = el.reference_gradients(q0[None], dN)
    return q0, G, w[None] * det, length * width * height


def test_reference_configuration_is_stress_free_and_volume_exact():
    q0, G, w, vol = straight_element()
    F = kernels.deformation_gradient(q0[None], G)
    assert np.allclose(F, np.eye(3), atol=1e-14)
    assert np.isclose(w.sum(), vol, rtol=1e-13)


@pytest.mark.parametrize("mat", [NeoHookean(1.0e6, 20.0e6), StVenantKirchhoff(2.0e6, 0.3)],
                         ids=["neo-hookean", "svk"])
def test_element_force_and_tangent_by_finite_differences(mat):
    q0, G, w, _ = straight_element()
    rng = np.random.default_rng(5)
    q = (q0 + 0.03 * rng.standard_normal(q0.shape) * np.where(np.abs(q0) > 0, 1.0, 0.05))[None]
    f, K, Jmin = kernels.internal_force_and_tangent(q, G, w, mat)
    assert Jmin[0] > 0
    f2, _ = kernels.internal_force(q, G, w, mat)
    assert np.allclose(f, f2)
    # force = gradient of the energy
    h = 1e-7
    qf = q.reshape(1, 54)
    ffd = np.zeros(54)
    Kfd = np.zeros((54, 54))
    for j in range(54):
        dq = np.zeros(54); dq[j] = h
        ep = kernels.energy((qf + dq).reshape(1, 18, 3), G, w, mat)[0]
        em = kernels.energy((qf - dq).reshape(1, 18, 3), G, w, mat)[0]
        ffd[j] = (ep - em) / (2 * h)
        Kfd[:, j] = (kernels.internal_force((qf + dq).reshape(1, 18, 3), G, w, mat)[0][0]
                     - kernels.internal_force((qf - dq).reshape(1, 18, 3), G, w, mat)[0][0]) / (2 * h)
    assert np.abs(f[0] - ffd).max() <= 2e-6 * np.abs(f).max()
    assert np.abs(K[0] - Kfd).max() <= 2e-6 * np.abs(K).max()
    assert np.allclose(K[0], K[0].T, atol=1e-10 * np.abs(K).max())


def test_rigid_rotation_gives_zero_force():
    q0, G, w, _ = straight_element()
    c, s = np.cos(0.7), np.sin(0.7)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ np.array([[1, 0, 0], [0, c, s], [0, -s, c]])
    q = (q0 @ R.T)
    q[0::6] += (0.3, -0.2, 0.1)   # translate the position vectors only
    f, _ = kernels.internal_force(q[None], G, w, NeoHookean(1e6, 1e8))
    assert np.abs(f).max() < 1e-6
