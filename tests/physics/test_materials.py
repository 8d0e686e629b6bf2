"""Materials: stresses and tangents against finite differences of the energy (paper §4)."""
import numpy as np
import pytest

from ancf_petsc.physics.materials import NeoHookean, StVenantKirchhoff, det_and_inverse_transpose


def random_F(n, scale=0.25, seed=0):
    rng = np.random.default_rng(seed)
    return np.eye(3) + scale * rng.standard_normal((n, 3, 3))


MATERIALS = [NeoHookean(mu=1.3e6, bulk_modulus=40e6), NeoHookean(mu=103.1e6, bulk_modulus=1.0e9),
             StVenantKirchhoff(E=2.1e6, nu=0.3), StVenantKirchhoff(E=1.0e6, nu=0.0)]


def test_cofactor_inverse():
    F = random_F(50)
    det, H = det_and_inverse_transpose(F)
    assert np.allclose(det, np.linalg.det(F), rtol=1e-13)
    assert np.allclose(H, np.linalg.inv(F).swapaxes(-1, -2), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("mat", MATERIALS, ids=lambda m: m.describe()[:30])
def test_stress_is_energy_gradient(mat):
    F = random_F(20)
    F = F[np.linalg.det(F) > 0.2]
    P, _ = mat.stress(F)
    h = 1e-6
    Pfd = np.zeros_like(P)
    for k in range(3):
        for l in range(3):
            dF = np.zeros((3, 3)); dF[k, l] = h
            Pfd[:, k, l] = (mat.energy(F + dF) - mat.energy(F - dF)) / (2 * h)
    assert np.abs(P - Pfd).max() <= 1e-6 * np.abs(P).max()


@pytest.mark.parametrize("mat", MATERIALS, ids=lambda m: m.describe()[:30])
def test_tangent_is_stress_derivative(mat):
    F = random_F(20, seed=1)
    F = F[np.linalg.det(F) > 0.2]
    P, J, terms = mat.stress_and_tangent(F)
    assert np.allclose(P, mat.stress(F)[0])
    A = terms.full()
    h = 1e-6
    Afd = np.zeros_like(A)
    for k in range(3):
        for l in range(3):
            dF = np.zeros((3, 3)); dF[k, l] = h
            Afd[:, :, :, k, l] = (mat.stress(F + dF)[0] - mat.stress(F - dF)[0]) / (2 * h)
    assert np.abs(A - Afd).max() <= 1e-6 * np.abs(A).max()
    # major symmetry of a hyperelastic tangent
    assert np.allclose(A, A.transpose(0, 3, 4, 1, 2), atol=1e-9 * np.abs(A).max())


def test_neo_hookean_reference_state_and_small_strain_moduli():
    mu, K = 2.0e6, 30.0e6
    mat = NeoHookean(mu, K)
    P, J = mat.stress(np.eye(3)[None])
    assert np.abs(P).max() < 1e-6 and J[0] == 1.0
    A = mat.stress_and_tangent(np.eye(3)[None])[2].full()[0]
    # linear isotropic elasticity: A_ijkl = λ δij δkl + μ (δik δjl + δil δjk)
    lam = K - 2 * mu / 3
    d = np.eye(3)
    A_lin = lam * np.einsum("ij,kl->ijkl", d, d) + mu * (np.einsum("ik,jl->ijkl", d, d)
                                                         + np.einsum("il,jk->ijkl", d, d))
    assert np.allclose(A, A_lin, rtol=1e-12, atol=1e-6)


def test_inverted_point_is_flagged_not_raised():
    F = np.diag([1.0, 1.0, -0.5])[None]
    P, J = NeoHookean(1.0, 10.0).stress(F)
    assert J[0] < 0 and not np.all(np.isfinite(P))
