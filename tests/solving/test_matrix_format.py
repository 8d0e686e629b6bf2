"""The Jacobian's storage: SBAIJ node blocks (the default under MUMPS LDLᵀ) against AIJ.

SBAIJ keeps the upper triangle of 18 × 18 node blocks and takes whole element and contact blocks
in one call each; it must hold exactly the AIJ matrix (whose tangent is checked against finite
differences in test_solver/test_contact), also after the contact pattern grows, and a run must
follow the same path.  AIJ stays where SBAIJ cannot work (LU, ILU, GAMG; element 3333)."""
import numpy as np
import pytest

from helpers import CONFIGS, load_raw, petsc_init, run_inline
from helpers import two_beam_twisted


def _problems(raw):
    petsc_init()
    from petsc4py import PETSc
    from ancf_petsc.petsc.problem import Problem
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.contact import build_contact
    from ancf_petsc.parallel.partition import make_layout
    from ancf_petsc.model.build import build_model
    spec = parse_config(raw, base_dir=CONFIGS)
    model = build_model(spec)
    out = {}
    for kind in ("aij", "sbaij"):
        contact = build_contact(model, spec.contact, lambda *_: None) if spec.contact else None
        layout = make_layout(model, "blocks", 1, 0, contact)
        out[kind] = Problem(model, layout, PETSc.COMM_WORLD, contact, kind)
    return out


def _products(P, x, vs):
    X = P.X
    X.setArray(x)
    P.jacobian(None, X, P.J, P.J)
    out = []
    for v in vs:
        V, Y = X.duplicate(), X.duplicate()
        V.setArray(v)
        P.J.mult(V, Y)
        out.append(Y.getArray().copy())
    return np.array(out)


def test_sbaij_holds_the_aij_jacobian_with_contact_and_supports():
    probs = _problems(load_raw("achilles_type3_psi45.yaml"))
    P = probs["aij"]
    assert probs["sbaij"].J.getType() == "seqsbaij" and P.J.getType() == "seqaij"
    rng = np.random.default_rng(3)
    free = ~P.fixed_mask
    x = P.q0.getArray() + 2e-5 * rng.standard_normal(P.q0.getLocalSize()) * free
    vs = rng.standard_normal((3, len(x)))           # held DOFs included: unit rows/columns
    ref = _products(P, x, vs)
    got = _products(probs["sbaij"], x, vs)
    assert np.abs(got - ref).max() <= 1e-13 * np.abs(ref).max()
    # a re-preallocated pattern (what a growing contact pattern does) holds the same matrix
    probs["sbaij"].pattern.preallocate(probs["sbaij"].J)
    again = _products(probs["sbaij"], x, vs)
    assert np.abs(again - ref).max() <= 1e-13 * np.abs(ref).max()


def test_sbaij_run_follows_the_aij_path_through_pattern_growth(tmp_path):
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["steps"] = [10, 100, 400]                   # the soleus slides onto new elements
    runs = {}
    for kind in ("aij", "sbaij"):
        raw["solver"] = dict(raw.get("solver", {}), matrix=kind)
        runs[kind] = run_inline(dict(raw, output={"vtk": False}), tmp_path / kind)
    assert runs["sbaij"]["jacobian_pattern_growths"] > 0
    assert "on SBAIJ" in runs["sbaij"]["solver"] and "on AIJ" in runs["aij"]["solver"]
    for a, b in zip(runs["aij"]["steps"], runs["sbaij"]["steps"]):
        assert a["iterations"] == b["iterations"]
        ua = np.array(a["probes"]["soleus"]["displacement"])
        ub = np.array(b["probes"]["soleus"]["displacement"])
        assert np.abs(ua - ub).max() <= 1e-9 * np.abs(ua).max()


def test_matrix_format_choice():
    petsc_init()
    from ancf_petsc.config.values import ConfigError
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from ancf_petsc.linalg.options import matrix_type
    m3363 = build_model(parse_config(load_raw("achilles_type3_psi0.yaml"), base_dir=CONFIGS))
    mixed = two_beam_twisted()
    mixed["beams"][1].update({"element": 3333})
    m_mixed = build_model(parse_config(mixed, base_dir=CONFIGS))
    assert matrix_type(m3363, "auto", {}) == "sbaij"
    assert matrix_type(m3363, "auto", {"pc_type": "lu"}) == "aij"
    assert matrix_type(m3363, "auto", {"pc_factor_mat_solver_type": "superlu_dist"}) == "aij"
    assert matrix_type(m_mixed, "auto", {}) == "aij"
    assert matrix_type(m3363, "aij", {}) == "aij"
    with pytest.raises(ConfigError, match="^solver.matrix: .*pc_type lu"):
        matrix_type(m3363, "sbaij", {"pc_type": "lu"})
    with pytest.raises(ConfigError, match="^solver.matrix: .*3363"):
        matrix_type(m_mixed, "sbaij", {})


def test_a_coloured_finite_difference_jacobian_gets_aij(tmp_path):
    """-snes_fd_color colours the Jacobian's pattern, which needs AIJ: on the default SBAIJ the
    first level failed 'with PETSC_ERROR in the linear solver (...): Ordering requires IJ'.  It
    now takes AIJ and solves the cantilever to the tolerance of its inexact tangent."""
    from helpers import cantilever, probe
    raw = cantilever([0.5], elements=2)
    ref = run_inline(raw, tmp_path / "default")
    for value in (True, "yes"):
        s = run_inline(raw, tmp_path / "fd", petsc={"snes_fd_color": value})
        assert s["status"] == "completed" and "PC cholesky (mumps) on AIJ" in s["solver"]
        tip, tip_ref = np.array(probe(s, "tip")), np.array(probe(ref, "tip"))
        assert np.abs(tip - tip_ref).max() <= 1e-6 * np.abs(tip_ref).max()
    s = run_inline(raw, tmp_path / "off", petsc={"snes_fd_color": False})
    assert "on SBAIJ" in s["solver"]
