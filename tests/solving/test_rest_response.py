"""The first increment from rest of a fibre-reinforced model is bounded by its linear response
(solving/rest_response.py): the soft-matrix GOH sets untwist at tiny loads, and a first step of the
whole first level stretched fibres to Ē = 0.44 and was cut back five times (docs/gait.md)."""
import numpy as np
import pytest

from helpers import build_problem, load_raw


def _snes(PETSc):
    snes = PETSc.SNES().create()
    ksp = snes.getKSP()
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    return snes


def test_the_first_increment_of_a_soft_matrix_goh_column_keeps_its_linear_response_in_range():
    from ancf_petsc.solving.rest_response import (REST_LINEAR_BOUND, bounded_first_increment,
                                                  linear_gradient_change)
    P, PETSc = build_problem(load_raw("achilles_type3_psi45_goh_alex.yaml"))
    snes = _snes(PETSc)
    full = linear_gradient_change(P, snes, 10.0)
    assert full > 10 * REST_LINEAR_BOUND            # measured 2.58: the sections turn by radians
    dlam = bounded_first_increment(P, snes, 10.0)
    assert dlam == pytest.approx(10.0 * REST_LINEAR_BOUND / full, rel=1e-12)
    # the response is linear in the load: the bounded increment's is the bound
    assert linear_gradient_change(P, snes, dlam) == pytest.approx(REST_LINEAR_BOUND, rel=1e-8)
    assert P.load_factor == 0.0 and not np.any(P.contact.status != P.contact._saved_status)


@pytest.mark.parametrize("name", ["achilles_type3_psi45_goh.yaml", "achilles_type3_psi45.yaml"])
def test_stiff_and_isotropic_columns_keep_their_first_level(name):
    """The stiff-matrix GOH column's linear response at 10 N moves the sections by 0.035: its
    first increment is the level; neo-Hookean models are not probed at all."""
    from ancf_petsc.solving.rest_response import bounded_first_increment
    P, PETSc = build_problem(load_raw(name))
    assert bounded_first_increment(P, _snes(PETSc), 10.0) == 10.0
