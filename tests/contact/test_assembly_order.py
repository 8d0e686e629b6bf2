"""The contact assembly's fast paths add exactly what their plain numpy forms add (issue 40)."""
import numpy as np
import pytest

from ancf_petsc import native
from ancf_petsc.contact.blocks import add_point_blocks

EL, DOFS_PER_NODE = 54, 18          # element 3363: 3 nodes x 18 DOFs


def test_point_blocks_add_what_add_at_adds_bitwise():
    """Repeated, unsorted segments and B elements 0-2 of a block three B elements wide: every
    entry gets the same additions in the same order as np.add.at's, so the sums are bitwise equal."""
    rng = np.random.default_rng(4)
    width, n_s, n = 3, 5, 23
    D = DOFS_PER_NODE * (2 * width + 6)
    seg = rng.integers(0, n_s, n)
    j = rng.integers(0, width, n)
    values = rng.standard_normal((n, 2 * EL, 2 * EL)) * 10.0 ** rng.integers(-8, 8, (n, 1, 1))
    K0 = rng.standard_normal((n_s, D, D))
    cols = np.concatenate([np.broadcast_to(np.arange(EL), (n, EL)),
                           EL + 2 * DOFS_PER_NODE * j[:, None] + np.arange(EL)], axis=1)
    expected = K0.copy()
    np.add.at(expected, (seg[:, None, None], cols[:, :, None], cols[:, None, :]), values)
    got = K0.copy()
    add_point_blocks(got, seg, j, values, EL, 2 * DOFS_PER_NODE)
    assert np.array_equal(got, expected)


def test_point_blocks_with_no_points_change_nothing():
    K = np.ones((2, 144, 144))
    add_point_blocks(K, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros((0, 108, 108)),
                     EL, 2 * DOFS_PER_NODE)
    assert np.array_equal(K, np.ones((2, 144, 144)))


@pytest.mark.parametrize("variational", [True, False])
def test_band_blocks_compiled_add_the_numpy_values_bitwise(variational, monkeypatch):
    """The fade band's stiffness (blocks._band_blocks: −p ∇g ∇wᵀ, with the variational forces
    also its transpose and −p g ∇²w), formed point by point in the compiled loop without the
    (points, 108, 108) temporaries: bitwise the numpy values added by add_point_blocks."""
    from types import SimpleNamespace
    from ancf_petsc.contact.blocks import _band_blocks
    if native.load("contact.blocks_native") is None:
        pytest.fail(native.status("contact.blocks_native"))
    rng = np.random.default_rng(7)
    width, n_s, n = 2, 4, 9
    D = DOFS_PER_NODE * (2 * width + 6)
    lay = SimpleNamespace(s_loc=rng.integers(0, n_s, n + 3), j=rng.integers(0, width, n + 3))
    band = np.sort(rng.choice(n + 3, n, replace=False))
    pgrad, gw = rng.standard_normal((n, 2 * EL)) * 1e3, rng.standard_normal((n, 2 * EL)) * 1e-2
    coef, hess = rng.standard_normal(n), rng.standard_normal((n, 2 * EL, 2 * EL))
    K0 = rng.standard_normal((n_s, D, D))
    got = K0.copy()
    _band_blocks(got, lay, band, pgrad, gw, coef, hess, variational, EL, 2 * DOFS_PER_NODE)
    monkeypatch.setenv("ANCF_NATIVE", "0")
    want = K0.copy()
    _band_blocks(want, lay, band, pgrad, gw, coef, hess, variational, EL, 2 * DOFS_PER_NODE)
    assert np.array_equal(got, want) and not np.array_equal(got, K0)
