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


def _cubic_goh_bar(s: float) -> dict:
    """configs/pretwisted_bar.yaml as the soft-matrix GOH set (alex) on cubic sections (33103),
    every length x ``s`` and the load x s² (the same stresses)."""
    raw = load_raw("pretwisted_bar.yaml")
    beam = raw["beams"][0]
    beam["element"] = "33103"
    beam["material"] = {"model": "goh", "mu": 107.2e3, "bulk_modulus": 5.324624e6, "k1": 75.351e6,
                        "k2": 23.926, "kappa": 0.0, "fibres": {"follow": "twist"}}
    raw["geometry"]["length"] *= s
    beam["section"]["semi_axes"] = [s * a for a in beam["section"]["semi_axes"]]
    beam["section"]["center"] = [s * c for c in beam["section"]["center"]]
    raw["loads"][0]["traction_force"] = [s * s * f for f in raw["loads"][0]["traction_force"]]
    return raw


def test_the_linear_response_at_rest_is_measured_alike_at_every_size():
    """Before: a cubic element's r_yyy ... (per square metre) counted times the section size like
    r_yy, so the same bar 1/16 the size moved 'by' 16 times more and its first increment was cut
    16-fold (the alex tendon on 33103 at 0.7 mm: 22 sub-steps and 135 Newton iterations to 10 N
    against 15 and 118 at 70 mm).  Now times the size^(k - 1): the same measure at every size."""
    from ancf_petsc.solving.rest_response import linear_gradient_change
    changes = []
    for s in (1.0, 1.0 / 16.0):
        P, PETSc = build_problem(_cubic_goh_bar(s))
        changes.append(linear_gradient_change(P, _snes(PETSc), 1.0))
    assert changes[0] > 0.0 and changes[1] == pytest.approx(changes[0], rel=1e-8)
