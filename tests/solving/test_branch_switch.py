"""Branch switching at a bifurcation (solving/branch_switch.py) against Euler's elastica.

A clamped column of St. Venant–Kirchhoff (ν = 0) with a 10 × 6 mm section, L = 1 m, under a
dead compressive tip force P = 0.64 N = 1.2008 P_cr (P_cr = π² EI / (4 L²), the weak axis).  The
straight state stays an equilibrium past P_cr, with one negative tangent eigenvalue; load control
alone ends there (status ``unstable``).  The switch leaves it along the critical mode for the
post-buckled elastica, whose tip, for the inextensible column, is at (with k = sin(α/2) from
sqrt(P/P_cr) = 2 K(k)/π):  lateral δ = 2 k L / K(k),  shortening L (2 − 2 E(k)/K(k)).
"""
import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

from helpers import assert_same_as_serial, probe, probes_table, run_inline, run_on_ranks

E, B, H, L, P = 1.2e9, 0.01, 0.006, 1.0, 0.64


def column(elements: int = 8, switch: bool | None = None) -> dict:
    raw = {
        "name": "euler_column", "units": "SI", "geometry": {"length": L},
        "beams": [{"name": "col", "elements": elements,
                   "section": {"shape": "rectangle", "size": [B, H], "cubature_degree": 4},
                   "material": {"model": "svk", "E": E, "nu": 0.0}}],
        "boundary_conditions": [{"beam": "col", "node": "first", "fix": "clamped"}],
        "loads": [{"beam": "col", "node": "last", "force": [-P, 0.0, 0.0]}],
        "steps": [0.5, 1.0],
        "probes": [{"name": "tip", "beam": "col", "node": "last"}],
        "output": {"dir": "out", "vtk": False},
    }
    if switch is not None:
        raw["solver"] = {"branch_switch": switch}
    return raw


def elastica_tip() -> tuple[float, float]:
    """(shortening, lateral deflection) of the inextensible clamped–free elastica at P."""
    EI = E * B * H ** 3 / 12.0
    ratio = P / (np.pi ** 2 * EI / (4.0 * L ** 2))
    K = np.pi * np.sqrt(ratio) / 2.0
    m = brentq(lambda m: ellipk(m) - K, 0.0, 0.999)
    return L * (2.0 - 2.0 * ellipe(m) / ellipk(m)), 2.0 * np.sqrt(m) * L / K


def test_a_column_past_eulers_load_switches_to_the_post_buckled_elastica(tmp_path):
    s = run_inline(column(), tmp_path / "on")
    assert s["status"] == "completed" and s["reason_code"] == "BRANCH_SWITCHED", s["message"]
    switches = [x for st in s["steps"] for x in st.get("branch_switches", [])]
    assert len(switches) == 1, switches
    sw = switches[0]
    assert sw["negative_before"] == 1 and sw["negative_after"] == 0 and sw["potential_drop"] > 0.0
    assert 1.0 < sw["load_factor"] * P / (np.pi ** 2 * E * B * H ** 3 / 48.0) < 1.2008
    assert s["steps"][-1]["negative_eigenvalues"] == 0
    u = probe(s, "tip")
    shortening, deflection = elastica_tip()
    assert -u[0] == pytest.approx(shortening, rel=2e-3)
    assert np.hypot(u[1], u[2]) == pytest.approx(deflection, rel=2e-3)
    assert abs(u[1]) < 1e-9                      # in the weak plane


def test_without_the_switch_the_column_ends_on_the_unstable_straight_state(tmp_path):
    s = run_inline(column(switch=False), tmp_path / "off")
    assert s["status"] == "unstable" and s["reason_code"] == "NEGATIVE_EIGENVALUES"
    assert "branch_switches" not in s["steps"][-1]
    u = probe(s, "tip")
    assert np.hypot(u[1], u[2]) < 1e-9 and -u[0] < 1e-4     # straight, shortened by P/EA only


def test_the_sparse_eigensolver_finds_the_dense_ones_mode(tmp_path, monkeypatch):
    """Above ``DENSE_LIMIT`` free DOFs the critical mode comes from shift-invert Lanczos: the same
    mode, so the same switch and the same post-buckled column."""
    from ancf_petsc.solving import branch_switch
    dense = run_inline(column(), tmp_path / "dense")
    monkeypatch.setattr(branch_switch, "DENSE_LIMIT", 10)
    lanczos = run_inline(column(), tmp_path / "sparse")
    a, b = (s["steps"][-1]["branch_switches"][0] for s in (dense, lanczos))
    # the critical eigenvalue (-2.3e-3) from shift-invert Lanczos and the dense solver agree to
    # 1.3e-8 (relative) with one CPU's OpenBLAS kernels (2026-12-02), within 1e-8 with another's
    assert b["eigenvalue"] == pytest.approx(a["eigenvalue"], rel=1e-6) and b["sign"] == a["sign"]
    assert np.allclose(probe(lanczos, "tip"), probe(dense, "tip"), rtol=1e-8, atol=1e-12)


@pytest.mark.mpi
def test_the_switch_gives_the_serial_answer_on_2_and_3_ranks(tmp_path):
    runs = run_on_ranks(column(), tmp_path)
    for n, (_, s) in runs.items():
        assert s["reason_code"] == "BRANCH_SWITCHED", (n, s["message"])
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()}, rtol=1e-8)


def test_the_final_status_names_the_switches_and_unsettled_weights_together():
    from ancf_petsc import status
    from ancf_petsc.solving.records import StepRecord
    from ancf_petsc.solving.run import final_status

    def record(lam, switches=(), unsettled=False):
        return StepRecord(lam, 3, 1, 0, "CONVERGED_FNORM_ABS", 1e-9, 0.1, negative_eigenvalues=0,
                          weights_unsettled=unsettled, branch_switches=list(switches))
    sw = {"load_factor": 0.75}
    state, code, message = final_status([record(0.5), record(1.0, [sw], unsettled=True)], None, False)
    assert (state, code) == ("completed", status.BRANCH_SWITCHED)
    assert "switching branch 1 time(s) at a bifurcation (load factor 0.75)" in message
    assert "contact weights not settled at 1 of 2 levels (load factor 1;" in message
    assert final_status([record(0.5), record(1.0, unsettled=True)], None, False)[1] == status.WEIGHTS_UNSETTLED


def test_without_contact_a_count_of_null_pivots_is_not_blamed_on_contact_multipliers(tmp_path):
    """The uniaxial bar at L = 100 m (slenderness ~1e4): its positive definite tangent's softest
    modes (~1e-7) are null pivots, counted as 2 negative eigenvalues; the switch found no negative
    eigenvalue and said the saddle lay 'on the contact multipliers' of a model without contact."""
    from helpers import load_raw, petsc_init
    from ancf_petsc.api import solve
    from ancf_petsc.config.parse import parse_config
    petsc_init()
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["geometry"]["length"], raw["steps"], raw["output"] = 100.0, [0.1], {"vtk": False, "dir": str(tmp_path)}
    lines: list[str] = []
    solve(parse_config(raw), log=lambda *a: lines.append(" ".join(map(str, a))))
    said = [s for s in lines if "nothing to switch along" in s]
    assert said and all("contact multipliers" not in s and "null pivots" in s for s in said), said
