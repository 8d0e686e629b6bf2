"""Dense node-block matrices → the local rows of the PETSc Jacobian, summed in numpy.

Element matrices and contact (mortar) matrices arrive as batches of dense blocks over node lists
(18 DOFs per node, or a subset of them for element 3333).  Adding them with ``MatSetValues``
costs a search per entry, and the contact blocks repeat the same node pairs many times (a
fascicle element is the A side of six interfaces).  Here every batch is cut into 18 × 18 node
blocks, the blocks of one node pair are summed by a sparse 0/1 matrix product, and the owned rows
are handed to PETSc as one CSR with the held DOFs left out; blocks of rows owned by another rank
go through ``setValuesRCV``.  The index plan depends only on the node lists, so it is kept until
they change (when a contact point slides onto another element).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from petsc4py import PETSc

B = 18                    # DOFs per node block


@dataclass
class BlockBatch:
    """``values[e]`` is the dense matrix over the DOFs ``18 nodes[e, i] + dofs[a]`` (i-major).

    ``used[e, i]`` False leaves node i of entry e out (its rows/columns must be zero)."""
    nodes: np.ndarray               # (n, k) PETSc node ids
    values: np.ndarray              # (n, k d, k d)
    dofs: np.ndarray | None = None  # (d,) offsets inside the 18-DOF block; None = all 18
    used: np.ndarray | None = None  # (n, k) bool


class _Plan:
    """How the blocks of a list of batches land in the local CSR (see ``BlockAssembler``)."""

    def __init__(self, batches: list[BlockBatch], node_lo: int, node_hi: int, n_nodes: int,
                 free: np.ndarray):
        keys, self.sums = [], []
        for bt in batches:
            n, k = bt.nodes.shape
            I = np.repeat(bt.nodes, k, axis=1).ravel()
            J = np.tile(bt.nodes, (1, k)).ravel()
            ok = np.ones(n * k * k, dtype=bool)
            if bt.used is not None:
                ok = (bt.used[:, :, None] & bt.used[:, None, :]).ravel()
            keys.append(np.where(ok, I.astype(np.int64) * n_nodes + J, -1))
        allkeys = np.concatenate(keys)
        uniq = np.unique(allkeys[allkeys >= 0])
        self.n_blocks = len(uniq)
        start = 0
        for bt, kk in zip(batches, keys):
            ok = kk >= 0
            cols = np.flatnonzero(ok)
            rows = np.searchsorted(uniq, kk[ok])
            self.sums.append(sp.csr_matrix((np.ones(len(cols)), (rows, cols)),
                                           shape=(self.n_blocks, len(kk))))
            start += len(kk)
        I, J = np.divmod(uniq, n_nodes)
        own = (I >= node_lo) & (I < node_hi)
        # owned node rows → CSR over DOF rows 18 I + a (held rows keep no entries here)
        self.own = np.flatnonzero(own)
        Io, Jo = I[own], J[own]
        n_rows = node_hi - node_lo
        g = np.bincount(Io - node_lo, minlength=n_rows)          # blocks per node row
        first = np.concatenate([[0], np.cumsum(g)])[:-1]
        pos = np.arange(len(Io)) - first[Io - node_lo]            # block's place in its row
        a = np.arange(B)
        # CSR position of entry (block u, row a, col b) before the held DOFs are dropped
        rowbase = np.concatenate([[0], np.cumsum(B * B * g)])[:-1]
        P = (rowbase[Io - node_lo][:, None, None] + a[None, :, None] * (B * g[Io - node_lo])[:, None, None]
             + B * pos[:, None, None] + a[None, None, :])        # (U_own, 18, 18)
        flat = (self.own[:, None, None] * (B * B) + a[:, None] * B + a[None, :]).ravel()
        order = np.empty(P.size, dtype=np.int64)
        order[P.ravel()] = np.arange(P.size)
        gather = flat[order]                                     # CSR entry → value index
        row_dof = 18 * np.repeat(np.arange(node_lo, node_hi), B)
        row_dof += np.tile(a, n_rows)
        col_dof = (B * J[gather // (B * B)] + gather % B).astype(np.int64)
        row_of = np.repeat(row_dof, np.repeat(B * g, B))        # DOF row of each CSR entry
        keep = free[row_of] & free[col_dof]
        self.gather = gather[keep]
        self.indices = col_dof[keep].astype(PETSc.IntType)
        counts = np.bincount(np.repeat(np.arange(B * n_rows), np.repeat(B * g, B))[keep],
                             minlength=B * n_rows)
        self.indptr = np.concatenate([[0], np.cumsum(counts)]).astype(PETSc.IntType)
        # blocks of rows another rank owns
        self.off = np.flatnonzero(~own)
        dof = B * I[self.off][:, None] + a
        self.off_rows = np.where(free[dof], dof, -1).astype(PETSc.IntType)
        dof = B * J[self.off][:, None] + a
        self.off_cols = np.where(free[dof], dof, -1).astype(PETSc.IntType)


class BlockAssembler:
    """Adds batches of node-block matrices to an AIJ matrix (see the module docstring)."""

    def __init__(self, owned_nodes: tuple[int, int], n_nodes: int, free: np.ndarray):
        self.lo, self.hi = owned_nodes
        self.n_nodes, self.free = n_nodes, free
        self._plan: _Plan | None = None
        self._signature: list | None = None
        self.plans_built = 0

    def _same(self, batches: list[BlockBatch]) -> bool:
        sig = self._signature
        if sig is None or len(sig) != len(batches):
            return False
        for (nodes, dofs, used), bt in zip(sig, batches):
            if nodes.shape != bt.nodes.shape or not np.array_equal(nodes, bt.nodes):
                return False
            if (dofs is None) != (bt.dofs is None) or (dofs is not None and not np.array_equal(dofs, bt.dofs)):
                return False
            if (used is None) != (bt.used is None) or (used is not None and not np.array_equal(used, bt.used)):
                return False
        return True

    def block_sums(self, batches: list[BlockBatch]) -> np.ndarray:
        """(n_blocks, 18, 18) sums of every node pair's blocks, in the plan's order."""
        if not self._same(batches):
            self._plan = _Plan(batches, self.lo, self.hi, self.n_nodes, self.free)
            self._signature = [(bt.nodes.copy(), None if bt.dofs is None else bt.dofs.copy(),
                                None if bt.used is None else bt.used.copy()) for bt in batches]
            self.plans_built += 1
        plan = self._plan
        total = np.zeros((plan.n_blocks, B * B))
        for bt, S in zip(batches, plan.sums):
            n, k = bt.nodes.shape
            d = B if bt.dofs is None else len(bt.dofs)
            blocks = bt.values.reshape(n, k, d, k, d).transpose(0, 1, 3, 2, 4).reshape(n * k * k, d * d)
            if d == B:
                total += S @ blocks
            else:
                cols = (bt.dofs[:, None] * B + bt.dofs[None, :]).ravel()
                total[:, cols] += S @ blocks
        return total.reshape(-1, B, B)

    def add_to(self, mat: PETSc.Mat, batches: list[BlockBatch]) -> None:
        """mat += Σ batches (owned rows by one CSR, other ranks' rows by setValuesRCV)."""
        if not batches:
            return
        total = self.block_sums(batches)
        plan = self._plan
        values = total.reshape(-1)[plan.gather]
        mat.setValuesCSR(plan.indptr, plan.indices, values, PETSc.InsertMode.ADD_VALUES)
        if len(plan.off):
            mat.setValuesRCV(plan.off_rows[:, :, None], plan.off_cols[:, None, :],
                             total[plan.off], PETSc.InsertMode.ADD_VALUES)
