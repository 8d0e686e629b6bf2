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


def test_a_soft_goh_history_reloaded_from_a_frame_of_zero_loads_starts_from_rest_again(tmp_path):
    """A history frame of zero loads is the rest state, but the reload after it kept the increment
    of the unloading frames: the soft-matrix GOH tendon (alex, 2 elements) pulled to 30 N, unloaded
    to 0 and pulled to 30 N again took 426 Newton iterations and 3 cut-backs for the reload against
    58 in 8 sub-steps from rest at the start.  Now the reload's first increment is bounded by the
    linear response as the first one is: no cut-back, the first frame's sub-steps and state."""
    from helpers import CONFIGS, run_inline
    raw = load_raw("achilles_type3_psi45_goh_alex.yaml")
    for b in raw["beams"]:
        b["elements"] = 2
    raw.pop("steps")
    raw["loads"][0]["column"] = "f"
    raw["history"] = {"table": {"time": [0.0, 0.1, 0.2], "f": [30.0, 0.0, 30.0]}}
    raw["output"] = {"vtk": False}
    s = run_inline(raw, tmp_path / "run", base_dir=CONFIGS)
    assert s["status"] == "completed"
    first, again = s["steps"][0], s["steps"][2]
    assert again["cutbacks"] == 0 and again["substeps"] == first["substeps"]
    assert again["iterations"] <= 1.25 * first["iterations"]
    a, b = (np.array(st["probes"]["soleus"]["displacement"]) for st in (first, again))
    assert np.abs(a - b).max() <= 1e-8 * np.abs(a).max()
