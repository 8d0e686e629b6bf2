"""Distribution of elements and nodes over MPI ranks.

A ``Layout`` says which rank computes each element and how nodes are renumbered so that every
rank owns one contiguous range of node blocks (18 DOFs each) in the PETSc vectors.  A node is
owned by the rank of the lowest-numbered element that contains it.  Besides the beams' nodes
there may be *extra* blocks that belong to one element each (the contact multipliers of an A
element, contact/multipliers.py): model block ids n_nodes, n_nodes + 1, ..., owned with their
element.  ``block_layout`` cuts the
beam-major element list into contiguous blocks (the design card's "by subtendon and element
blocks"); a graph partitioner only has to supply another ``elem_owner``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np



@dataclass
class Layout:
    size: int
    rank: int
    elem_owner: np.ndarray      # (n_elements,) rank computing each element
    node_owner: np.ndarray      # (n_blocks,) rank owning each block (in model numbering)
    perm: np.ndarray            # (n_blocks,) model block id → PETSc block id
    ranges: np.ndarray          # (size + 1,) PETSc node ownership ranges
    method: str = "blocks"
    n_nodes: int = -1           # beam nodes; blocks n_nodes … n_blocks − 1 are extra blocks
    dofs_per_node: int = 18     # DOFs of a block (the model's node block, Model.dofs_per_node)

    @property
    def n_blocks(self) -> int:
        return len(self.perm)

    @property
    def owned_nodes(self) -> tuple[int, int]:
        return int(self.ranges[self.rank]), int(self.ranges[self.rank + 1])

    @property
    def local_elements(self) -> np.ndarray:
        return np.flatnonzero(self.elem_owner == self.rank)

    def blocks_per_rank(self) -> tuple[list[int], list[int]]:
        """(beam nodes, extra blocks) each rank owns: the multipliers' blocks are no nodes."""
        n = len(self.node_owner) if self.n_nodes < 0 else self.n_nodes
        return tuple(np.bincount(owners, minlength=self.size).tolist()
                     for owners in (self.node_owner[:n], self.node_owner[n:]))

    def petsc_dofs(self, model_dofs: np.ndarray) -> np.ndarray:
        """Map model DOF ids to PETSc DOF ids (negative ids pass through unchanged)."""
        model_dofs = np.asarray(model_dofs)
        D = self.dofs_per_node
        node, local = np.divmod(np.maximum(model_dofs, 0), D)
        return np.where(model_dofs < 0, model_dofs, D * self.perm[node] + local)

    def summary(self, asked: str | None = None) -> str:
        """The log's partition line; ``asked``: the config's partition.method, named when the
        ranks are split otherwise (the fieldsplit solver keeps every beam whole on one rank)."""
        counts = np.bincount(self.elem_owner, minlength=self.size)
        nodes, extra = self.blocks_per_rank()
        blocks = f", multiplier blocks per rank {extra}" if sum(extra) else ""
        note = f", not partition.method {asked}: the fieldsplit solver keeps every beam whole on " \
               "one rank" if self.size > 1 and asked not in (None, self.method) else ""
        return (f"partition ({self.method}{note}): elements per rank {counts.tolist()}, "
                f"nodes per rank {nodes}{blocks}")


def layout_from_owner(elem_owner: np.ndarray, connectivity: np.ndarray, n_nodes: int,
                      size: int, rank: int, method: str,
                      extra_elements: np.ndarray | None = None) -> Layout:
    """Complete a layout from an element → rank assignment (nodes follow their first element,
    extra blocks their element)."""
    n_el = len(elem_owner)
    elem_owner = np.asarray(elem_owner, dtype=np.int64)
    first_elem = np.full(n_nodes, n_el, dtype=np.int64)
    for k in range(connectivity.shape[1]):
        np.minimum.at(first_elem, connectivity[:, k], np.arange(n_el))
    if np.any(first_elem == n_el):
        raise ValueError("a node belongs to no element")
    extra = np.zeros(0, dtype=np.int64) if extra_elements is None else np.asarray(extra_elements)
    node_owner = np.concatenate([elem_owner[first_elem], elem_owner[extra]])
    n_blocks = len(node_owner)
    order = np.lexsort((np.arange(n_blocks), node_owner))      # by rank, then model id
    perm = np.empty(n_blocks, dtype=np.int64)
    perm[order] = np.arange(n_blocks)
    ranges = np.concatenate([[0], np.cumsum(np.bincount(node_owner, minlength=size))])
    return Layout(size, rank, elem_owner, node_owner, perm, ranges, method, n_nodes)


def block_layout(connectivity: np.ndarray, n_nodes: int, size: int, rank: int,
                 extra_elements: np.ndarray | None = None) -> Layout:
    """Contiguous blocks of the beam-major element list, as equal as possible."""
    n_el = connectivity.shape[0]
    elem_owner = (np.arange(n_el) * size) // max(n_el, 1)
    return layout_from_owner(elem_owner, connectivity, n_nodes, size, rank, "blocks", extra_elements)
