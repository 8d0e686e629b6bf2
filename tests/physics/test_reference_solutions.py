"""The closed forms the solver is checked against hold at any stress level."""
import pytest

from ancf_petsc.physics.materials import NeoHookean, StVenantKirchhoff
from ancf_petsc.physics.reference_solutions import uniaxial_stretches


@pytest.mark.parametrize("material,nu", [(NeoHookean(1.0e6, 50.0e6), NeoHookean(1.0e6, 50.0e6).poisson),
                                         (StVenantKirchhoff(1.2e9, 0.3), 0.3)])
@pytest.mark.parametrize("stress", [6.0, 60.0, 1.0e3])
def test_uniaxial_stretches_at_small_stress_match_linear_elasticity(material, nu, stress):
    """A fascicle-scale stress (Pa to kPa in a MPa material): strain s / E, contraction nu s / E."""
    lam, lt = uniaxial_stretches(material, stress)
    strain = stress / material.young
    assert (lam - 1.0) / strain == pytest.approx(1.0, abs=10 * strain + 1e-6)
    assert (1.0 - lt) / (nu * strain) == pytest.approx(1.0, abs=10 * strain + 1e-6)
