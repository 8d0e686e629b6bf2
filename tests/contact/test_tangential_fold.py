"""The tangential functions folded at held roots (issue 27, ``contact.tangential.supported_ends:
merge``): with every function sticking (at rest) exact stick repeats the supports at the roots,
and the Jacobian is singular; folded, its smallest singular value is that of frictionless
sliding (singular value decomposition of the assembled Jacobian, scripts/friction_stick_rank.py)."""
import os

import numpy as np
import pytest

from helpers import CONFIGS, build_problem, load_raw


def _at_rest(tangential, elements: int = 2):
    """The paper's tendon loaded by the three muscles equally, at rest at 10 N: the problem and
    the singular values of its Jacobian over the used unknowns (largest first)."""
    raw = load_raw("achilles_psi45_equal_muscles.yaml")
    for b in raw["beams"]:
        b["elements"] = elements
    # the quadratic pressure along the beam (friction's default until 2026-12-07): on the linear
    # one, now friction's default, kept roots leave the Jacobian as regular as frictionless
    # sliding (smallest / largest singular value 8.3e-13 against 7.8e-13)
    raw["contact"] = {"mode": "sliding", "projection": {"axial": 2}} | (
        {"tangential": tangential} if tangential else {})
    P, PETSc = build_problem(raw)
    P.load_factor = 10.0
    P.jacobian(None, P.q0, P.J, P.J)
    J = P.J.convert("dense", PETSc.Mat()).getDenseArray()
    used = np.flatnonzero(np.abs(J).sum(axis=1) > 0)
    return P, np.linalg.svd(J[np.ix_(used, used)], compute_uv=False)


@pytest.fixture(scope="module")
def spectra():
    stick = {"law": "coulomb", "friction": 3.0}
    return {ends: _at_rest(stick | {"supported_ends": ends}) for ends in ("keep", "merge")} | {
        "frictionless": _at_rest(None)}


def test_folded_roots_do_not_repeat_the_supports(spectra):
    """Kept, exact stick makes the Jacobian singular (to rounding); folded, its smallest
    singular value is within a factor 3 of the frictionless one."""
    rel = {k: s[-1] / s[0] for k, (_, s) in spectra.items()}
    assert rel["keep"] < 1e-14, rel
    assert rel["merge"] > rel["frictionless"] / 3.0, rel


def test_fold_sums_the_root_functions(spectra):
    """Each interface's first end (the held roots; the loaded ends are free) is folded into its
    neighbour: the folded vectors' functions are empty, their neighbours' areas (and so the
    bounds ∫ φ p⁺ dA) are the sums, the partition of unity is kept."""
    sp = spectra["merge"][0].contact.space
    drop = np.flatnonzero(sp.tdrop)
    assert len(drop) == 2 * len(sp.n_across) and np.all(sp.n_across == 2)
    into = drop + 2
    np.testing.assert_allclose(sp.tarea[into], sp.area[drop] + sp.area[into], rtol=1e-12)
    assert np.all(sp.tarea[drop] == 0.0) and sp.tPhi[drop].nnz == 0
    np.testing.assert_allclose(sp.tarea.sum(), sp.area.sum(), rtol=1e-12)
    rows = np.asarray(sp.tPhi.sum(axis=1)).ravel()
    np.testing.assert_allclose(rows[~sp.tdrop], 1.0, rtol=1e-12)
    kept = spectra["keep"][0].contact.space
    assert not kept.tdrop.any() and kept.tPhi is kept.Phi


@pytest.mark.mpi
@pytest.mark.slow
def test_folded_friction_gives_the_serial_answer_on_2_and_3_ranks(tmp_path):
    """μ = 3 on the folded space, equal loading, 2 elements, 10 and 30 N on 1, 2 and 3 ranks:
    the same probes at every level (the folded functions' vectors and their neighbours live on
    the root segment, whose rank evaluates both)."""
    from helpers import assert_same_as_serial, probes_table, run_on_ranks
    raw = load_raw("achilles_psi45_equal_muscles.yaml")
    for b in raw["beams"]:
        b["elements"] = 2
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["contact"] = {"mode": "sliding",
                      "tangential": {"law": "coulomb", "friction": 3.0, "supported_ends": "merge"}}
    raw["steps"] = [10.0, 30.0]
    # the secant predictor (friction's default until 2026-12-03): with the tangent one the 30 N
    # level cuts back once on this μ = 3 scene
    raw["solver"] = {"predictor": "secant"}
    runs = run_on_ranks(raw, tmp_path, ranks=(1, 2, 3))
    for _, s in runs.values():
        assert s["status"] == "completed" and sum(st["cutbacks"] for st in s["steps"]) == 0
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
