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
