"""Element blocks and node-block insertion into PETSc matrices (AIJ or SBAIJ).

The Jacobian is AIJ, or SBAIJ with 18 × 18 node blocks (``linalg.options.matrix_type``): the upper
triangle of node blocks, inserted one block at a time (``insert_node_blocks``).  That is ~15×
faster than AIJ's entry-by-entry insertion of the same dense element and contact blocks and halves
the stored entries; MUMPS's LDLᵀ takes SBAIJ directly, but PETSc's LU, ILU and GAMG do not.  On one
rank a Problem adds an AIJ Jacobian's blocks into its value array at once instead (aij_blocks.py).
DOFs held by boundary conditions are −1 in the element rows (AIJ drops them) or zeroed inside
their node block (SBAIJ), so the Jacobian stays symmetric.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from petsc4py import PETSc

from ..linalg.options import node_blocks_fit
from ..model.beams import Beam, Model
from ..parallel.layout import Layout

ADD = PETSc.InsertMode.ADD_VALUES
INSERT = PETSc.InsertMode.INSERT_VALUES


@dataclass
class ElementBlock:
    """A rank's elements of one beam with their quadrature data."""
    beam: Beam
    parts: list          # [(G (E, P, S, 3), w (E, P), material)] per energy part (Beam.parts)
    nodes: np.ndarray    # (E, k) PETSc node ids (k axial nodes)
    rows: np.ndarray     # (E, 3S) PETSc DOF ids, −1 for DOFs held by BCs
    node_dofs: np.ndarray  # (3S/k,) offsets of the active DOFs inside a node's block (18 DOFs for 3363)
    lnodes: np.ndarray | None = None   # (E, k) positions of the nodes in the local array (exchange.py)
    _node_ids: tuple | None = field(default=None, repr=False)   # (bs, node_blocks(rows, bs))

    @property
    def G(self) -> np.ndarray:
        """Gradients at the full Gauss points (the first part)."""
        return self.parts[0][0]

    def element_vectors(self, xl: np.ndarray) -> np.ndarray:
        """Active nodal vectors of the elements (E, S, 3) from the local state (n, V, 3)."""
        vectors = list(self.beam.vectors)
        if vectors == list(range(xl.shape[1])):          # every vector of the node (3363): one gather
            return xl[self.lnodes].reshape(len(self.nodes), -1, 3)
        return xl[self.lnodes][:, :, vectors].reshape(len(self.nodes), -1, 3)

    def node_ids(self, bs: int) -> tuple[np.ndarray, np.ndarray | None]:
        """``node_blocks(rows, bs)`` of the elements' fixed rows, made once (SBAIJ insertion)."""
        if self._node_ids is None or self._node_ids[0] != bs:
            self._node_ids = (bs, node_blocks(self.rows, bs))
        return self._node_ids[1]

    def local_dofs(self) -> np.ndarray:
        """Positions of the elements' active DOFs in the local array (E, 3S)."""
        D = self.beam.layout.block.dofs_per_node
        return (D * self.lnodes[:, :, None] + self.node_dofs).reshape(len(self.nodes), -1)


#: Jacobian storage formats (``Problem(matrix_type=...)``)
MATRIX_TYPES = ("aij", "sbaij")


def check_matrix_type(model: Model, matrix_type: str) -> None:
    """ValueError unless ``matrix_type`` is one of MATRIX_TYPES and fits the model (SBAIJ node
    blocks need every beam to interpolate its whole node block)."""
    if matrix_type not in MATRIX_TYPES:
        raise ValueError(f"matrix_type must be one of {MATRIX_TYPES}, not {matrix_type!r}")
    if matrix_type == "sbaij" and not node_blocks_fit(model):
        raise ValueError("SBAIJ node blocks need every beam to use all nodal vectors of its node "
                         "block (e.g. element 3363); use matrix_type 'aij'")


def node_blocks(rows: np.ndarray, bs: int = 18) -> tuple[np.ndarray, np.ndarray | None]:
    """Node ids (n, D/bs) of DOF index blocks (n, D) made of whole nodes of ``bs`` DOFs (18 for
    3363), and a mask (n, D) of the held DOFs (−1) of nodes that have free DOFs (None when there
    are none).  A node whose DOFs are all −1 (unused, or held entirely) gets the node id −1."""
    n, D = rows.shape
    g = rows.reshape(n, D // bs, bs)
    valid = g >= 0
    node = np.where(valid.any(axis=2), g.max(axis=2) // bs, -1).astype(PETSc.IntType)
    held = ~valid & (node >= 0)[:, :, None]
    return node, (held.reshape(n, D) if held.any() else None)


def zero_held(values: np.ndarray, held: np.ndarray | None) -> np.ndarray:
    """Zero the rows and columns of ``held`` (n, D) in ``values`` (n, D, D), in place (the
    callers' blocks are fresh arrays, inserted once).  Boolean assignment through the array and
    its transposed view writes only the held rows and columns (a copy of the blocks that have
    any was 100× slower: 0.37 s of a 37-fascicle run)."""
    if held is None:
        return values
    values[held] = 0.0                                # rows
    values.transpose(0, 2, 1)[held] = 0.0             # columns
    return values


def insert_node_blocks(mat: PETSc.Mat, rows: np.ndarray, *values: np.ndarray, nodes=None) -> None:
    """Add dense blocks ``values`` (n, D, D) at DOF indices ``rows`` (n, D; −1 = dropped) to an
    AIJ or SBAIJ ``mat``.  For SBAIJ the DOFs must come as whole nodes (18 consecutive indices
    18 k … 18 k + 17, held ones −1); its lower triangle is ignored (the blocks are symmetric);
    ``nodes(bs)``: ``node_blocks(rows, bs)`` when the caller keeps them (``ElementBlock.node_ids``).
    ``insert_node_blocks(mat, rows, columns, values)``: rectangular blocks (n, R, C), AIJ only."""
    if len(values) == 2:
        if mat.getType().endswith("sbaij"):
            raise ValueError("rectangular blocks (an unsymmetric Jacobian) need an AIJ matrix")
        cols, vals = values
        mat.setValuesRCV(rows.astype(PETSc.IntType), cols.astype(PETSc.IntType), vals, ADD)
        return
    values = values[0]
    if mat.getType().endswith("sbaij"):
        bs = mat.getBlockSize()
        node, held = node_blocks(rows, bs) if nodes is None else nodes(bs)
        mat.setValuesBlockedRCV(node, node, zero_held(values, held), ADD)
    else:
        rows = rows.astype(PETSc.IntType)
        mat.setValuesRCV(rows, rows, values, ADD)


def element_blocks(model: Model, layout: Layout, fixed_mask: np.ndarray) -> list[ElementBlock]:
    """This rank's elements, one block per beam, with quadrature data and PETSc DOF rows."""
    conn_all = layout.perm[model.connectivity()]
    local_el = layout.local_elements
    elem_beam = model.element_beam()
    out = []
    for beam in model.beams:
        mine = local_el[elem_beam[local_el] == beam.index]
        if len(mine) == 0:
            continue
        parts = model.element_data(beam, mine - beam.element_offset)
        cn = conn_all[mine]
        node_dofs = (3 * np.array(beam.vectors)[:, None] + np.arange(3)).ravel()
        rows = (model.dofs_per_node * cn[:, :, None] + node_dofs).reshape(len(mine), -1)
        rows = np.where(fixed_mask[rows], -1, rows).astype(PETSc.IntType)
        out.append(ElementBlock(beam, parts, cn, rows, node_dofs))
    return out


def refresh_parts(blocks: list[ElementBlock], model: Model, layout: Layout, beams: list[int]) -> None:
    """After the material laws of ``beams`` (indices) changed in place in the model (same mesh):
    their element blocks' quadrature parts again (``Model.element_data``).  The matrix, its
    pattern and the solver's symbolic factorisation are untouched (not collective)."""
    local_el = layout.local_elements
    elem_beam = model.element_beam()
    for blk in blocks:
        if blk.beam.index in beams:
            mine = local_el[elem_beam[local_el] == blk.beam.index]
            blk.parts = model.element_data(blk.beam, mine - blk.beam.element_offset)
