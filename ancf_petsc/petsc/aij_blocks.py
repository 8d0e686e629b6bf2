"""Dense blocks added into a sequential AIJ Jacobian's value array in one pass.

The unsymmetric Jacobians (Coulomb friction, ``contact.fade_forces: pointwise``) are AIJ for
MUMPS's LU, and ``MatSetValues`` adds their dense element and contact blocks entry by entry, a
search of the row's columns for each: on the μ = 0.3 walking stride ~0.5 M values, 11 ms a
Jacobian, a quarter of the solve (docs/gait.md).  The AIJ pattern is the node pattern
(petsc/pattern.py ``JacobianPattern._aij``): a free row of node I holds every free DOF of the
nodes coupled to I, in column order, and a held row its diagonal alone.  So an entry (r, c) sits
at indptr[r] + offset(I, J) + rank(c), with offset(I, J) the free columns of I's coupled nodes
before node J (one dense table over node pairs) and rank(c) c's place among its node's free DOFs.

``AIJBlocks`` collects the blocks of one assembly in order and adds them with one ``bincount``:
every position receives the same additions in the same order as block-by-block
``MatSetValues(ADD_VALUES)`` after ``zeroEntries``, so the matrix is bitwise the same.  One rank
only (``seqaij``); an MPI AIJ matrix keeps ``MatSetValues``.
"""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from ..linalg.compact_factor import ValueArray
from .blocks import insert_node_blocks

#: node blocks up to which the node-pair offsets are one dense table (int32, 64 MB at the limit);
#: a larger one-rank model keeps ``MatSetValues``
MAX_NODES = 4096


class AIJStructure:
    """Where every (row, column) of a seqaij matrix's pattern sits in its value array."""

    def __init__(self, mat: PETSc.Mat, bs: int, held: np.ndarray):
        ia, ja = mat.getRowIJ(symmetric=False, compressed=False)
        self.indptr = np.asarray(ia, dtype=np.int64)
        indices = np.asarray(ja, dtype=np.int64)
        self.nnz, self.bs = len(indices), bs
        self.nodes = nodes = (len(self.indptr) - 1) // bs
        free = ~np.asarray(held, dtype=bool).reshape(nodes, bs)
        #: a DOF's place among its node's free DOFs
        self.rank = (np.cumsum(free, axis=1) - free).ravel()
        #: offset(I, J): where node J's columns start in a free row of node I (−1: not coupled)
        self.offsets = np.full((nodes, nodes), -1, dtype=np.int32)
        count = free.sum(axis=1)
        for node in np.flatnonzero(count):
            r = node * bs + np.argmax(free[node])       # every free row of a node has the same columns
            col_nodes = indices[self.indptr[r]:self.indptr[r + 1]] // bs
            coupled, first = np.unique(col_nodes, return_index=True)
            if not np.array_equal(np.diff(np.append(first, len(col_nodes))), count[coupled]):
                raise ValueError(f"row {r} of the AIJ matrix is not the node pattern's (petsc/pattern.py)")
            self.offsets[node, coupled] = first

    def positions(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Value-array positions (n, R, C) of the entries of blocks at DOF ``rows`` (n, R) and
        ``cols`` (n, C); a dropped entry's (row or column −1) is ``nnz``, one past the array.
        ValueError for an entry outside the pattern (as MatSetValues would refuse it)."""
        bs, nodes = self.bs, self.nodes
        r, c = np.maximum(rows, 0), np.maximum(cols, 0)
        pos = np.take(self.offsets.ravel(), (r // bs * nodes)[:, :, None] + (c // bs)[:, None, :]).astype(np.int64)
        dropped = (rows < 0)[:, :, None] | (cols < 0)[:, None, :]
        if np.any((pos < 0) & ~dropped):
            raise ValueError("a block couples nodes outside the AIJ pattern")
        pos += self.indptr[r][:, :, None]
        pos += self.rank[c][:, None, :]
        pos[dropped] = self.nnz
        return pos


class AIJBlocks:
    """The blocks of one assembly into a seqaij matrix, added at once (``flush``).  The k-th
    block set of an assembly keeps its positions while its rows and columns are those of the
    k-th of the last one (the contact pairs did not change): only the values are new."""

    def __init__(self, mat: PETSc.Mat, bs: int, held: np.ndarray):
        self.mat, self.bs, self.held = mat, bs, held
        self.structure: AIJStructure | None = None
        self._values: list[np.ndarray] = []
        self._slots: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []   # (rows, cols, positions)
        self._all: np.ndarray | None = None          # the last assembly's positions, concatenated
        self._hits = 0

    @classmethod
    def of(cls, mat: PETSc.Mat, bs: int, held: np.ndarray) -> "AIJBlocks | None":
        """The collector of a one-rank AIJ ``mat`` with ``bs``-DOF node blocks and the DOFs
        ``held`` (a mask in its numbering), None for any other matrix (SBAIJ, MPI, more than
        ``MAX_NODES`` nodes): those keep ``insert_node_blocks``."""
        if mat.getType() != PETSc.Mat.Type.SEQAIJ or mat.getSize()[0] > bs * MAX_NODES:
            return None
        return cls(mat, bs, held)

    def begin(self) -> None:
        """A new assembly: blocks an interrupted one collected are dropped."""
        self._values, self._hits = [], 0

    def reset(self) -> None:
        """The matrix's pattern changed (``JacobianPattern.grow``): read it again."""
        self.structure, self._slots, self._all = None, [], None

    def add(self, rows: np.ndarray, *values: np.ndarray, nodes=None) -> None:
        """``insert_node_blocks(mat, rows, values)`` or ``(mat, rows, cols, values)``, deferred
        (``nodes``, SBAIJ's node ids, is not needed here)."""
        if self.structure is None:
            self.structure = AIJStructure(self.mat, self.bs, self.held)
        cols, vals = (rows, values[0]) if len(values) == 1 else values
        k = len(self._values)
        if k < len(self._slots) and np.array_equal(self._slots[k][0], rows) and np.array_equal(self._slots[k][1], cols):
            self._hits += 1
        else:
            pos = self.structure.positions(rows, cols).ravel().astype(np.int32)     # nnz < 2**31
            del self._slots[k:]
            self._slots.append((np.array(rows), np.array(cols), pos))
        self._values.append(np.asarray(vals, dtype=float).ravel())

    def flush(self) -> None:
        """Add every collected block to the matrix's values, in the order they came."""
        n = len(self._values)
        if not n:
            return
        if self._all is None or self._hits < n or len(self._slots) != n:
            del self._slots[n:]
            self._all = np.concatenate([slot[2] for slot in self._slots])
        vals = np.concatenate(self._values)
        self._values, self._hits = [], 0
        summed = np.bincount(self._all, vals, minlength=self.structure.nnz + 1)[:-1]   # the last: dropped
        with ValueArray(self.mat, self.structure.nnz) as a:
            a += summed


class DirectBlocks:
    """``insert_node_blocks`` into a matrix as it comes (``add``), for every other matrix."""

    def __init__(self, mat: PETSc.Mat):
        self.mat = mat

    def add(self, rows: np.ndarray, *values: np.ndarray, nodes=None) -> None:
        insert_node_blocks(self.mat, rows, *values, nodes=nodes)

    def flush(self) -> None:
        """Nothing is held back."""


def blocks_into(collector: AIJBlocks | None, P: PETSc.Mat) -> "AIJBlocks | DirectBlocks":
    """Where an assembly's blocks go: ``collector`` (started afresh) when P is its matrix, else
    straight into P."""
    if collector is not None and P.handle == collector.mat.handle:
        collector.begin()
        return collector
    return DirectBlocks(P)


def jacobian_matrix(pattern) -> tuple[PETSc.Mat, "AIJBlocks | None"]:
    """A new Jacobian from ``pattern`` (petsc/pattern.py ``JacobianPattern``) and the collector of
    its blocks (None unless one-rank AIJ)."""
    J = pattern.create_matrix()
    return J, AIJBlocks.of(J, pattern.model.dofs_per_node, pattern.fixed_mask)
