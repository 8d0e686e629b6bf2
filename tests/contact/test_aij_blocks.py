"""The one-rank AIJ Jacobian's blocks added at once (petsc/aij_blocks.py) against PETSc's own
``MatSetValues``: bitwise the same matrix, with Coulomb friction's rectangular blocks (whose
tangential multiplier rows straddle two multiplier nodes), held DOFs, partly weighted points, and
positions kept from one assembly to the next."""
import numpy as np
import pytest

from contact.test_contact import achilles
from contact.test_fade_newton import fade_state
from contact.test_friction_fade import FRICTION, _with_history
from helpers import build_problem


def _friction_state():
    # the quadratic pressure along the beam, whose tangential rows straddle two multiplier nodes
    P, _ = build_problem(achilles(contact={"mode": "sliding", "tangential": dict(FRICTION),
                                           "projection": {"axial": 2}}))
    P.contact.weights.differentiated = True
    P.load_factor = 50.0
    X, free = fade_state(P)
    _with_history(P, X)
    P.checkpoint()                  # each assembly projects from the same places (``_values``)
    return P, X, free


def _values(P, X, collect: bool) -> np.ndarray:
    """J(X)'s value array, its blocks added by the collector or (``collect`` False) by MatSetValues."""
    kept = P.aij_blocks
    if not collect:
        P.aij_blocks = None
    try:
        P.restore()
        P.contact._cache = None
        P.jacobian(None, X, P.J, P.J)
    finally:
        P.aij_blocks = kept
    return P.J.getValuesCSR()[2].copy()


def test_collected_blocks_give_matsetvalues_matrix_bitwise():
    P, X, _ = _friction_state()
    assert P.J.getType() == "seqaij" and P.aij_blocks is not None
    reference = _values(P, X, collect=False)
    assert np.count_nonzero(reference) > 10_000
    assert np.array_equal(_values(P, X, collect=True), reference)
    # friction's blocks are among them: 18 multiplier rows spanning two multiplier nodes
    blocks = P.contact.jacobian_blocks(P.exchange.local_state(X), P.exchange.needed, P.fixed_mask)
    rows = [b[0] for b in blocks if b[-1].shape[1:] == (126, 108)]
    D = P.model.dofs_per_node
    assert rows and any(len(np.unique(r[:D][r[:D] >= 0] // D)) == 2 for r in rows[0])


def test_kept_positions_follow_new_values_bitwise():
    """A second assembly at another state reuses the first one's positions (the same contact
    pairs) and still equals MatSetValues' matrix there."""
    P, X, free = _friction_state()
    _values(P, X, collect=True)
    slots = list(P.aij_blocks._slots)
    Y = X.copy()
    Y.setArray(X.getArray() + 1e-9 * np.random.default_rng(5).standard_normal(X.getLocalSize()) * free)
    fresh = _values(P, Y, collect=True)
    assert len(slots) > 3 and all(a[2] is b[2] for a, b in zip(slots, P.aij_blocks._slots))
    assert np.array_equal(fresh, _values(P, Y, collect=False))
    assert not np.array_equal(fresh, _values(P, X, collect=False))


def test_an_entry_outside_the_pattern_is_refused():
    """As MatSetValues refuses a new nonzero (NEW_NONZERO_ALLOCATION_ERR), the collector raises:
    a beam's root node and its end node share no element (2 elements) and no contact pair."""
    from ancf_petsc.petsc.aij_blocks import AIJStructure
    P, _, _ = _friction_state()
    beam, D = P.model.beams[0], P.model.dofs_per_node
    root, end = P.layout.perm[[beam.node_offset, beam.node_offset + beam.n_nodes - 1]]
    free = ~P.fixed_mask
    rows, cols = (np.where(free[d], d, -1)[None, :] for d in (D * root + np.arange(D), D * end + np.arange(D)))
    structure = AIJStructure(P.J, D, P.fixed_mask)
    structure.positions(rows, rows)                 # within the pattern
    with pytest.raises(ValueError, match="outside the AIJ pattern"):
        structure.positions(rows, cols)
    with pytest.raises(ValueError, match="not the node pattern"):      # the held DOFs mistaken
        AIJStructure(P.J, D, np.zeros_like(P.fixed_mask))


def test_sbaij_and_large_matrices_keep_matsetvalues(monkeypatch):
    from ancf_petsc.petsc import aij_blocks
    P, _ = build_problem(achilles(contact={"mode": "sliding"}), matrix_type="sbaij")
    assert P.aij_blocks is None
    P, _ = build_problem(achilles(contact={"mode": "sliding", "tangential": dict(FRICTION)}))
    assert aij_blocks.AIJBlocks.of(P.J, P.model.dofs_per_node, P.fixed_mask) is not None
    monkeypatch.setattr(aij_blocks, "MAX_NODES", 3)
    assert aij_blocks.AIJBlocks.of(P.J, P.model.dofs_per_node, P.fixed_mask) is None
