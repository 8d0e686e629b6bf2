"""Each committed 3D-solid reference re-solved on its coarsest mesh (ancf_verify.checks): today's
solid gives the CSV's numbers to 1e-6 (a change to ancf_petsc's sections or pretwist map, which
the solids share, or to the solids themselves shows here).  Seconds each."""
import pytest

from ancf_verify import checks
from ancf_verify.bars.cases import CASES
from ancf_verify.fibres.cases import LAWS


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.key)
def test_a_bar_solid_is_the_committed_one(solid_stack, case):
    c = checks.bar(case)
    assert c.ok and c.today > 0.0, c


def test_the_helical_fibre_solid_is_the_committed_one(solid_stack):
    c = checks.fibre_bar(LAWS[0])
    assert c.ok and c.today > 0.0, c


def test_the_soft_matrix_solid_is_the_committed_one(solid_stack):
    c = checks.soft_matrix_bar()
    assert c.ok and c.today > 0.0, c


def test_a_check_fails_when_the_numbers_differ():
    assert not checks.Check("x", 1.0, 1.0, 2e-6, 1e-6).ok and checks.Check("x", 1.0, 1.0, 0.0, 1e-6).ok


def test_a_bar_on_a_plane_root_is_the_closed_form(solid_stack):
    """The tension bar with its root face on a frictionless plane (ancf_verify.roots ``plane``:
    u_x = 0 over the face, the in-plane rigid motions held) is homogeneous uniaxial tension: at
    h = 4 mm its elongation is the closed form's under the mesh face's traction to 0.1 %, where
    the clamped root (u = 0) holds the section's contraction and is more than 1 % stiffer."""
    import dataclasses

    from ancf_petsc.physics.materials import NeoHookean
    from ancf_petsc.physics.reference_solutions import uniaxial_stretches
    from ancf_verify.bars.cases import ancf_section
    from ancf_verify.bars.solid import run_solid
    tension = next(c for c in CASES if c.key == "tension")
    sec = ancf_section(tension)
    law = NeoHookean(tension.material["mu"], tension.material["bulk_modulus"])
    for root, low, high in (("plane", -1e-3, 1e-3), ("clamped", -0.05, -0.01)):
        r = run_solid(dataclasses.replace(tension, root=root), sec, 4e-3, 1, 0.0)
        lam, _ = uniaxial_stretches(law, tension.force[0] / r["face_area"])
        assert low < r["u"][0] / ((lam - 1.0) * tension.length) - 1.0 < high, (root, r["u"])
