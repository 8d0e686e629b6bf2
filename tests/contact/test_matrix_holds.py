"""The support check counts an elastic interface matrix as holding (it ties the beams at rest):
the shear-lag core held only by its two interfaces solves and follows the closed form; without
a tangential law, or with Coulomb friction (nothing pressed at rest), it is still refused."""
import numpy as np
import pytest

from helpers import run_inline
from test_interface_shear import B, EA, F, L, outer_force, sandwich
from ancf_petsc.errors import InputError


def free_core(k_t: float | None) -> dict:
    """configs/shear_lag_sandwich.yaml with the core's root support removed."""
    raw = sandwich(k_t)
    raw["boundary_conditions"] = [bc for bc in raw["boundary_conditions"] if bc["beam"] != "core"]
    return raw


def free_core_transfer(x: np.ndarray, k_line: float) -> np.ndarray:
    """Axial force of each outer bar when the core is free at x = 0 (shear-lag theory): s = u_c −
    u_o solves s'' = s/ℓ² with s'(0) = −F/(2 EA_o) (N_c(0) = 0, N_o(0) = F/2) and s'(L) = F/EA_c;
    N_o(x) = F/2 − k ∫₀ˣ s."""
    ell = 1.0 / np.sqrt(k_line * (2.0 / EA + 1.0 / EA))
    b = -ell * F / (2.0 * EA)
    a = (ell * F / EA - b * np.cosh(L / ell)) / np.sinh(L / ell)
    return F / 2 - k_line * ell * (a * np.sinh(x / ell) + b * (np.cosh(x / ell) - 1.0))


def test_a_core_held_only_by_the_matrix_follows_the_shear_lag_solution(tmp_path):
    """Before: refused, 'nothing holds core (free: translation along x, ...) (frictionless contact
    lets beams slide along each other)'.  Now each outer bar's force along the bar is the closed
    form's within 1 % of F/2 (measured 1.8e-4) and each root carries F/2."""
    k_t = 1.0e6
    s = run_inline(free_core(k_t), tmp_path)
    assert s["status"] == "completed"
    x = np.linspace(0.0, L, 17)[:-1]
    exact = free_core_transfer(x, k_t * B)
    assert np.abs(outer_force(tmp_path, x) - exact).max() < 0.01 * F / 2
    for root in ("top.0", "bottom.0"):
        assert abs(-s["steps"][-1]["reactions"][root][0] - F / 2) < 1e-6 * F


@pytest.mark.parametrize("law, words", [(None, "frictionless contact"),
                                        ({"law": "coulomb", "friction": 0.3}, "Coulomb friction holds only")])
def test_a_core_held_by_sliding_or_friction_alone_is_refused(tmp_path, law, words):
    raw = free_core(None)
    if law is not None:
        raw["contact"]["tangential"] = law
    with pytest.raises(InputError) as exc:
        run_inline(raw, tmp_path)
    assert "nothing holds core" in str(exc.value) and words in str(exc.value)


def test_a_soft_matrix_holds_the_core_as_well(tmp_path):
    """At k_t = 1e3 Pa/m the layer holds the core's turn about z about as stiffly as the core's own
    bending does (k_t Σ ω x² 8e-5 against EI/L 3e-5 N m): held, whatever k_t > 0, not compared
    with the multipliers' unit k_s (which found that turn free).  The core slides 2.6 mm; the
    two roots carry F between them."""
    s = run_inline(free_core(1.0e3), tmp_path)
    assert s["status"] == "completed"
    roots = sum(-s["steps"][-1]["reactions"][r][0] for r in ("top.0", "bottom.0"))
    assert abs(roots - F) < 1e-6 * F


def test_the_matrix_sticks_where_the_interfaces_open(tmp_path):
    """The paper's tendon (2 elements) with a stiff matrix (k_t = 1e10 Pa/m) and unilateral
    contact: at 400 N every interface is open (no pressing force) while the matrix carries
    18-187 N of shear.  Its stick_share read 0.0 there (the sticking part of the pressed area,
    friction's measure), as if the layer slid freely; the matrix holds every point: 1.0."""
    from helpers import load_raw
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["elements"] = 2
    raw["steps"] = [10, 100, 400]
    raw["output"] = {"vtk": False}
    raw["contact"] = {"mode": "unilateral", "tangential": {"law": "elastic", "stiffness": 1.0e10}}
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed"
    last = s["steps"][-1]["contact"]
    assert any(c["pressing_force"] == 0.0 and np.linalg.norm(c["shear_force"]) > 10.0 for c in last.values())
    assert all(c["stick_share"] == 1.0 for st in s["steps"] for c in st["contact"].values())


def test_free_motions_read_as_unit_modes():
    """The core held by frictionless contact alone is free along x and y and to turn about z;
    eigh's basis of that triple zero read 'translation along (-0.20, -0.98, -0.00) with rotation
    about z, ...' once the check measured lengths in the beams' length.  Now the basis is the unit
    modes themselves, in their order."""
    from helpers import build_problem
    from ancf_petsc.solving.supports import free_rigid_motions
    P, _ = build_problem(free_core(None))
    assert free_rigid_motions(P) == ["core (free: translation along x, translation along y, rotation about z)"]
