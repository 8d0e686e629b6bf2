"""partners.pair_products (friction_blocks.py's normals' rotation and fade-weight columns): the
per-(segment, B element) sums of per-point products, against the sums taken point by point."""
import numpy as np

from ancf_petsc.contact.partners import pair_products


def test_pair_sums_equal_point_by_point_sums_in_lexicographic_order():
    rng = np.random.default_rng(5)
    P, R, I, C = 57, 7, 4, 6
    srow = np.sort(rng.integers(0, 5, P))               # points stored segment by segment
    eB = rng.integers(-1, 4, P)                          # −1: no partner element
    left, right = rng.standard_normal((P, R, I)), rng.standard_normal((P, I, C))
    pair, sums = pair_products(srow, eB, left, right)
    expected = sorted({(int(s), int(b)) for s, b in zip(srow, eB)})
    assert [tuple(p) for p in pair] == expected
    for (s, b), total in zip(expected, sums):
        mine = (srow == s) & (eB == b)
        assert np.allclose(total, np.einsum("pri,pic->rc", left[mine], right[mine]), rtol=1e-13, atol=1e-13)


def test_rank_one_columns_are_an_extra_inner_index():
    """The fade weights' outer products lw ⊗ gw enter as one more inner index (friction_blocks)."""
    rng = np.random.default_rng(6)
    P = 20
    srow, eB = np.repeat(np.arange(4), 5), rng.integers(0, 3, P)
    L, G = rng.standard_normal((P, 5, 3)), rng.standard_normal((P, 3, 8))
    lw, gw = rng.standard_normal((P, 5)), rng.standard_normal((P, 8))
    pair, both = pair_products(srow, eB, np.concatenate([L, lw[:, :, None]], 2), np.concatenate([G, gw[:, None]], 1))
    _, first = pair_products(srow, eB, L, G)
    _, second = pair_products(srow, eB, lw[:, :, None], gw[:, None])
    assert np.allclose(both, first + second, rtol=1e-13, atol=1e-13)
