"""Stability of converged states (negative tangent eigenvalues from the LDLᵀ factor) and the
coarse Achilles models of Table 2: the mean sliding gap leaves one-element subtendons unstable,
the gap linear across the interface keeps them stable to 400 N."""
import os

import h5py
import numpy as np
import pytest

from ancf_petsc import report as rp
from helpers import CONFIGS, load_raw, read_summary, run_inline, solve_cli, write_config


def coarse_achilles(psi=0, elements=1, steps=(10, 50), projection=None):
    raw = load_raw(f"achilles_type3_psi{psi}.yaml")
    for b in raw["beams"]:
        b["elements"] = elements
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["steps"] = list(steps)
    if projection is not None:
        raw["contact"]["projection"] = projection
    return raw


def dense_negative_eigenvalues(raw, out_dir, step):
    """Negative eigenvalues of the free-DOF Jacobian at a stored converged state (numpy eigvalsh),
    independent of the factorisation the solver counted them with."""
    from test_solver import _problem
    problem, PETSc = _problem(raw)
    with h5py.File(os.path.join(out_dir, "results.h5")) as h5:
        g = h5["steps"][f"step_{step:04d}"]
        q, lam = g["nodal_vectors"][()], float(g.attrs["load_factor"])
    X = problem.X.duplicate()
    X.setArray(q.reshape(-1, 18)[np.argsort(problem.layout.perm)].ravel())
    problem.load_factor = lam
    F = problem.F.duplicate()
    problem.residual(None, X, F)                    # the contact projections of this state
    problem.jacobian(None, X, problem.J, problem.J)
    K = problem.J.convert("dense").getDenseArray()
    free = ~problem.fixed_mask
    K = K[np.ix_(free, free)]
    d = 1.0 / np.sqrt(np.abs(np.diag(K)))          # scaling keeps the count, sharpens the spectrum
    w = np.linalg.eigvalsh(0.5 * (K + K.T) * d[:, None] * d[None, :])
    return int(np.sum(w < 0.0)), w


def test_negative_pivots_equal_the_dense_spectrum(tmp_path):
    raw = coarse_achilles()
    s = run_inline(raw, tmp_path / "mean")
    counts = [st["negative_eigenvalues"] for st in s["steps"]]
    # one element per subtendon, mean gap: stable at 10 N, a saddle at 50 N (a twist of the
    # soleus section that the mean gap does not see, driven by the contact tractions)
    assert counts == [0, 1]
    for k, expected in ((1, 0), (2, 1)):
        n, w = dense_negative_eigenvalues(raw, tmp_path / "mean", k)
        # the solver's count is the last Newton iteration's factor; the state itself agrees
        assert n == expected, w[:4]
        if n:
            assert w[0] < -1e-6 * abs(w[n])


def test_stability_count_on_two_ranks(tmp_path):
    raw = coarse_achilles()
    raw["output"] = {"dir": str(tmp_path / "n2"), "vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "n2.yaml"), ranks=2)
    # an unstable level makes the run end 'unstable' (exit 4, one warning line; docs/running.md)
    assert p.returncode == 4, p.stderr
    assert "UNSTABLE: 1 negative tangent eigenvalue(s)" in p.stdout
    assert sum(ln.startswith("ancf-solve: unstable: 1 of 2 levels") for ln in p.stderr.splitlines()) == 1
    s = read_summary(tmp_path / "n2")
    assert [st["negative_eigenvalues"] for st in s["steps"]] == [0, 1]
    assert s["status"] == "unstable" and s["unstable_levels"] == [50.0]


@pytest.mark.parametrize("psi, paper", [(0, 6.051), (45, 6.123)])
def test_linear_gap_takes_one_element_subtendons_to_400N(tmp_path, psi, paper):
    raw = coarse_achilles(psi, steps=(100, 200, 300, 400), projection=rp.T2_VARIANTS["linear gap"])
    s = run_inline(raw, tmp_path / f"lin{psi}")
    assert s["status"] == "completed"
    assert all(st["negative_eigenvalues"] == 0 for st in s["steps"])
    _, el = rp.elongations(s)
    # Table 2's 1 x 1 x 1 row (measured: -0.23 % and +1.04 %)
    assert el[-1] == pytest.approx(paper, rel=0.015)


def test_no_count_without_an_ldlt_factor(tmp_path):
    raw = coarse_achilles(steps=(10,))
    s = run_inline(raw, tmp_path / "lu", petsc={"pc_type": "lu"})
    assert s["steps"][0]["negative_eigenvalues"] is None


def test_table2_markdown_marks_unstable_and_stopped_runs():
    rows = {}
    for v in rp.T2_VARIANTS:
        for p in rp.TWISTS:
            for n in rp.T2_ELEMENTS:
                rows[(v, p, n)] = {"elong": 6.1 + 0.01 * n, "status": "completed", "reason": "",
                                   "reached": 400.0, "unstable_from": None, "dofs": 54 * (2 * n + 1)}
    rows[("mean gap", 0, 1)].update(elong=np.nan, status="failed", reached=200.0, unstable_from=50.0,
                                    reason="could not reach load factor 300")
    text = rp.table2_markdown(rows)
    assert "**mean gap** (default)" in text and "**linear gap** (contact.projection:" in text
    assert "stopped after 200 N (u ≥ 50 N)" in text
    assert "- mean gap, ψ=0°, 1 element(s): failed: could not reach load factor 300" in text
    assert text.count("| 4 | 486 |") == 2
