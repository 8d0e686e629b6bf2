"""contact/blocks_native.pyx (issue 40): the compiled normal forces equal the numpy ones to the last
bit, the gap-Hessian term (on one- and two-element-wide segment blocks, products over the
blocks each point has) equals the numpy path's padded product to rounding (the numpy code is
the reference and the fallback), and the module is compiled wherever Cython is."""

import numpy as np
import pytest

from ancf_petsc import native
from ancf_petsc.contact import blocks
from ancf_petsc.contact.projection import subset
from contact.test_contact import achilles
from contact.test_fade_newton import fade_state
from helpers import build_problem, contact_evaluation

NAME = "contact.blocks_native"
compiled = pytest.mark.skipif(native.load(NAME) is None, reason=native.status(NAME))
EL, DOFS_PER_NODE = 54, 18          # element 3363: 3 nodes x 18 DOFs


@pytest.fixture(scope="module")
def evaluation():
    """A sliding Achilles contact with differentiated weights at a state with pressed, partly
    weighted points (contact/test_fade_newton.py)."""
    P, _ = build_problem(achilles(contact={"mode": "sliding", "fade": "newton"}))
    P.contact.weights.differentiated = True
    P.load_factor = 50.0
    X, _ = fade_state(P)
    st = contact_evaluation(P, X)
    assert np.count_nonzero(st.tau) > 10 and len(blocks.fade_derivatives(P.contact, st).band) > 0
    return P, st


@compiled
def test_forces_equal_numpy(evaluation, monkeypatch):
    P, st = evaluation
    got = np.full(st.xl.size, 0.25)
    blocks.add_normal_forces(P.contact, st, got)
    monkeypatch.setenv("ANCF_NATIVE", "0")
    want = np.full(st.xl.size, 0.25)
    blocks.add_normal_forces(P.contact, st, want)
    np.testing.assert_array_equal(got, want)
    assert np.count_nonzero(want != 0.25) > 100


@compiled
def test_jacobian_blocks_equal_numpy(evaluation, monkeypatch):
    """Every block of the Jacobian (fade-band terms, constraint rows, gap Hessian)."""
    P, st = evaluation
    got = blocks.jacobian_blocks(P.contact, st, P.fixed_mask)
    monkeypatch.setenv("ANCF_NATIVE", "0")
    want = blocks.jacobian_blocks(P.contact, st, P.fixed_mask)
    assert len(got) == len(want) >= 1
    for (r1, k1), (r2, k2) in zip(got, want):
        np.testing.assert_array_equal(r1, r2)
        assert_rounding(k1, k2)


def assert_rounding(got: np.ndarray, want: np.ndarray) -> None:
    """Equal to rounding: every entry within 1e-14 of the largest one (the products sum the
    same terms in another order; a wrong block or a missing term is off by its size)."""
    scale = np.abs(want).max()
    err = np.abs(got - want).max()
    print(f"largest difference {err:.3g} of {scale:.3g}")
    assert err <= 1e-14 * scale


def _spread(s_loc, p_loc, cols, n_s, P_s, Dq):
    """``_segment_blocks``'s layout of per-point rows for points on any B element of a block."""
    def spread(X):
        out = np.zeros((n_s, P_s, Dq) + X.shape[2:])
        out[s_loc[:, None], p_loc[:, None], cols] = X
        return out
    return spread


@compiled
@pytest.mark.parametrize("width", [1, 2])
def test_gap_hessian_equals_numpy_on_wide_blocks(evaluation, width, monkeypatch):
    """The points of three segments in a random order, some segments not full, on B elements
    0 … width − 1 of their blocks; K's previous content kept."""
    P, st = evaluation
    rng = np.random.default_rng(width)
    n_s, P_s = 3, 9
    sel = rng.choice(len(st.tau), 20, replace=False)
    s_loc = np.repeat(np.arange(n_s), [9, 5, 6])[rng.permutation(20)]
    p_loc = np.zeros(20, dtype=np.int64)
    for s in range(n_s):
        p_loc[s_loc == s] = rng.permutation(P_s)[:np.count_nonzero(s_loc == s)]
    j = rng.integers(0, width, 20)
    Dq = DOFS_PER_NODE * (2 * width + 4)
    cols = np.concatenate([np.broadcast_to(np.arange(EL), (20, EL)),
                           EL + 2 * DOFS_PER_NODE * j[:, None] + np.arange(EL)], axis=1)
    sub, tau = subset(st.pr, sel), rng.uniform(0.5, 2.0, 20)
    K0 = rng.standard_normal((n_s, Dq + 36, Dq + 36))
    got = K0.copy()
    blocks.add_gap_hessian(got, sub, tau, None, s_loc, p_loc, cols[:, EL], P_s, Dq)
    monkeypatch.setenv("ANCF_NATIVE", "0")
    want = K0.copy()
    blocks.add_gap_hessian(want, sub, tau, _spread(s_loc, p_loc, cols, n_s, P_s, Dq), s_loc, p_loc,
                           cols[:, EL], P_s, Dq)
    assert np.abs(want - K0).max() > 0.0
    assert_rounding(got, want)
