"""A run that gives up at a critical point of its load path says so (solving/critical_point.py).

The measure is the diagonally scaled tangent's smallest eigenvalue over the next, on a mode of
the beams: checked here on matrices whose answer is known, then on the soft-matrix GOH set alex
at twist 120°, soleus-biased, unilateral (the fibre grid's cell, 4 elements), whose path folds at
7.27 N: the smallest scaled eigenvalue of the converged states falls as √(λ_f − λ) while the next
stays at 1.1e-4 (the module docstring's numbers): with ``solver.branch_switch: false`` it
stops there, and its message names the critical point.  The snap (BranchSwitch.snap) on the
second subject's sliding column at 45°, gastrocnemius-biased, whose path folds at 2977 N: it
goes on from a stable state 0.8 mm away, 0.1 % beyond, to 3 kN, the same on 2 and 3 ranks.
"""
import numpy as np
import pytest

from helpers import assert_same_as_serial, probes_table, run_inline, run_on_ranks

from ancf_petsc.solving.critical_point import ISOLATED, singular_mode


def singular_share(A, mechanical):
    found = singular_mode(A, mechanical)
    return None if found is None else found[0]


def _with_spectrum(values, rng):
    """The symmetric Q diag(values) Qᵀ of a random orthogonal Q, and Q."""
    n = len(values)
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    return Q @ np.diag(values) @ Q.T, Q


def test_the_share_is_the_smallest_eigenvalue_over_the_next_whatever_the_dofs_units():
    rng = np.random.default_rng(3)
    n = 12
    values = np.array([1e-5, 2e-2] + list(np.linspace(0.5, 3.0, n - 2)))
    # a matrix with unit diagonal: its Jacobi scaling is itself
    A, _ = _with_spectrum(values, rng)
    d = np.sqrt(np.diag(A))
    M = A / d[:, None] / d[None, :]
    share = singular_share(M, np.ones(n, dtype=bool))
    w = np.sort(np.abs(np.linalg.eigvalsh(M)))
    assert abs(share - w[0] / w[1]) < 1e-12
    # the mode in the matrix's own unknowns: A x = μ |diag A| x (the scaled eigenproblem's)
    D = np.diag(10.0 ** rng.uniform(-4, 2, n))
    A = D @ M @ D
    _, mu, x = singular_mode(A, np.ones(n, dtype=bool))
    assert np.allclose(A @ x, mu * np.abs(np.diag(A)) * x, rtol=0.0, atol=1e-9 * np.abs(np.diag(A) * x).max())
    assert abs(abs(mu) - w[0]) < 1e-12
    assert share < ISOLATED
    # nodal vectors of other units (m against 1): D M D has the same share
    assert abs(singular_share(A, np.ones(n, dtype=bool)) - share) < 1e-9 * share + 1e-15


def test_a_small_eigenvalue_of_a_constraint_mode_is_no_critical_point():
    rng = np.random.default_rng(4)
    A, Q = _with_spectrum(np.array([1e-6, 1.0, 2.0, 3.0, 4.0, 5.0]), rng)
    weight = Q[:, 0] ** 2
    mechanical = weight < np.median(weight)          # the small mode lies mostly elsewhere
    assert np.sum(weight[mechanical]) < 0.5
    assert singular_share(A, mechanical) is None
    assert singular_share(A, ~mechanical) < ISOLATED


def test_an_unsymmetric_tangent_is_read_by_its_singular_values():
    rng = np.random.default_rng(5)
    n = 8
    U, _ = np.linalg.qr(rng.standard_normal((n, n)))
    V, _ = np.linalg.qr(rng.standard_normal((n, n)))
    s = np.array([4.0, 3.0, 2.5, 2.0, 1.5, 1.0, 0.5, 2e-4])
    A = U @ np.diag(s) @ V.T
    d = np.sqrt(np.abs(np.diag(A)))
    S = A / d[:, None] / d[None, :]
    sv = np.sort(np.linalg.svd(S, compute_uv=False))
    assert abs(singular_share(A, np.ones(n, dtype=bool)) - sv[0] / sv[1]) < 1e-12


def _folding_column(switch: bool | None = None) -> dict:
    from ancf_petsc.workflows.envelope import GOH, EnvelopeCell, cell_config
    alex = [g for g in GOH if g.endswith("_alex.yaml")][0]
    raw = cell_config(EnvelopeCell(alex, 120, "soleus", None, 0.0, 4, levels=(30.0,)))
    if switch is not None:
        raw.setdefault("solver", {})["branch_switch"] = switch
    return raw


@pytest.mark.slow
@pytest.mark.parametrize("update", ["linear", "rotation"])
def test_without_switching_the_fold_stops_the_run_naming_the_critical_point(tmp_path, update):
    """alex at 120°, soleus-biased, to 30 N: the path folds at 7.2715 N with either section
    update.  With turned sections (the default with fibres) the first give-up finds the critical
    point, the pointwise fade forces go on from it and stop at a state that is not near-singular
    (scaled share 0.19, Newton wandering): the run still names the critical point, from its
    first give-up."""
    raw = _folding_column(switch=False)
    raw["solver"]["section_update"] = update
    s = run_inline(raw, tmp_path / "stop")
    assert s["status"] == "failed", s["message"]
    message = s["message"]
    assert "SNES failed at load factor 7.27" in message, message
    assert "is nearly singular" in message and "at or near a critical point there" in message, message
    if "before going on with" in message:        # the critical point was the first give-up's
        assert "is nearly singular" in message.split("the level's first give-up was")[1], message
    assert update == "linear" or "before going on with the pointwise fade forces" in message, message
    assert "no stable state was found" not in message          # no snap was tried
    assert s["failure_cause"] == "critical_point", s["failure_cause"]
    share = float(message.split("diagonally scaled, is ")[1].split(" of the next")[0])
    assert share < 0.01


def _sliding_fold() -> dict:
    """The second subject's outlines, twist 45°, gastrocnemius-biased, sliding: its path folds
    at 2977 N (the subject2 grid's cell).  Until the outlines were started at their farthest
    vertex (geometry_input/polyline.py) this was the 120° column's fold at 2567 N on the secant
    predictor's path."""
    from ancf_petsc.workflows.envelope import SUBJECT2, EnvelopeCell, cell_config
    return cell_config(EnvelopeCell(SUBJECT2, 45, "gastrocnemius", "sliding"))


def _snap_of(s: dict) -> dict:
    assert s["status"] == "completed" and s["reason_code"] == "BRANCH_SWITCHED", s["message"]
    assert "snapping 1 time(s) past a critical point (load factor 2977.0" in s["message"], s["message"]
    snaps = [x for st in s["steps"] for x in st.get("branch_switches", [])]
    assert len(snaps) == 1, snaps
    return snaps[0]


@pytest.mark.slow
def test_a_column_snaps_past_its_critical_point_to_a_stable_state_downhill(tmp_path):
    s = run_inline(_sliding_fold(), tmp_path / "snap")
    snap = _snap_of(s)
    assert snap["kind"] == "limit point" and 2977.0 < snap["critical_load_factor"] < 2978.0
    assert snap["critical_share"] < 0.01 and snap["negative_after"] == 0
    # just beyond the critical state (SNAP_STEPS[0]), a jump of a tenth of a section, downhill
    assert snap["load_factor"] == pytest.approx(snap["critical_load_factor"] * 1.001, rel=1e-12)
    assert 1e-4 < snap["jump"] < 1e-3 and snap["potential_drop"] > 0.0
    assert s["steps"][-1]["load_factor"] == 3000.0 and s["steps"][-1]["negative_eigenvalues"] == 0


@pytest.mark.slow
@pytest.mark.mpi
def test_the_snap_is_the_same_on_two_and_three_ranks(tmp_path):
    runs = run_on_ranks(_sliding_fold(), tmp_path, ranks=(1, 2, 3))
    snaps = {n: _snap_of(s) for n, (_, s) in runs.items()}
    for n in (2, 3):
        assert snaps[n]["load_factor"] == snaps[1]["load_factor"] and snaps[n]["sign"] == snaps[1]["sign"]
        assert snaps[n]["jump"] == pytest.approx(snaps[1]["jump"], rel=1e-6)
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()}, rtol=1e-8)


def test_the_log_and_the_final_message_tell_a_snap_from_a_branch_switch():
    from ancf_petsc.solving.solver_messages import switch_line, switched_message
    common = {"sign": -1.0, "amplitude": 9.77e-4, "jump": 2.7e-3, "sides": 1, "iterations": 69,
              "negative_after": 0, "eigenvalue": 3.6e-7, "potential_drop": 7.4e-6}
    snap = dict(common, kind="limit point", load_factor=7.27879, negative_before=0,
                critical_load_factor=7.27152, critical_share=3.2e-3)
    switch = dict(common, kind="bifurcation", load_factor=13.375, negative_before=1)
    line = switch_line(snap)
    assert line.startswith("  snap past a critical point at load factor 7.27152 (its tangent's smallest "
                           "scaled eigenvalue 3.2e-03 of the next"), line
    assert "at load factor 7.27879, perturbed by -0.977 mm" in line and "2.7 mm away" in line
    assert "below the critical state's" in line
    assert switch_line(switch).startswith("  branch switch at load factor 13.375: the state there had 1 negative")
    message = switched_message([switch, snap])
    assert message.startswith("completed, switching branch 1 time(s) at a bifurcation (load factor 13.375)")
    assert "; snapping 1 time(s) past a critical point (load factor 7.27152)" in message
    assert switched_message([switch]).count("snapping") == 0
