"""The Jacobian's nonzero pattern in node blocks: the elements' couplings plus the contact
couplings that occurred so far (never a whole search window), preallocated exactly in AIJ or
SBAIJ form.  A contact point that slides onto another element of B couples new node blocks:
``grow`` adds them and preallocates again (MUMPS then redoes its symbolic analysis)."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from petsc4py import PETSc

from ..model.beams import Model
from ..parallel.layout import Layout


class JacobianPattern:
    """Node-block pattern of one Problem's Jacobian (collective methods unless noted)."""

    def __init__(self, model: Model, layout: Layout, fixed_mask: np.ndarray, contact, comm,
                 matrix_type: str):
        self.model, self.layout, self.contact, self.comm = model, layout, contact, comm
        self.fixed_mask = fixed_mask
        self.matrix_type = matrix_type
        self.n_blocks = layout.n_blocks
        self.growths = 0                       # how often contact added couplings
        self.contact_pairs = np.zeros(0, dtype=np.int64)   # block pairs row · n_blocks + col
        self.projected = None                  # B elements the local points projected onto
        if contact is not None:
            self.contact_pairs = self._current_contact_pairs()
            self.projected = contact.projected_elements()

    def node_pattern(self, rows: tuple[int, int] | None = None) -> sp.csr_matrix:
        """Node-block coupling (PETSc numbering): elements + the contact pairs seen so far;
        with ``rows = (lo, hi)`` only those node rows (shape (hi − lo, n))."""
        n = self.n_blocks
        lo, hi = (0, n) if rows is None else rows
        conn = self.layout.perm[self.model.connectivity()]
        conn = conn[np.any((conn >= lo) & (conn < hi), axis=1)]
        k = conn.shape[1]                     # axial nodes of an element
        r = np.repeat(conn, k, axis=1).ravel()
        c = np.tile(conn, (1, k)).ravel()
        if self.contact is not None:
            cr, cc = np.divmod(self.contact_pairs, n)
            r, c = np.concatenate([r, cr]), np.concatenate([c, cc])
        mine = (r >= lo) & (r < hi)
        A = sp.coo_matrix((np.ones(int(mine.sum()), dtype=np.int8), (r[mine] - lo, c[mine])),
                          shape=(hi - lo, n)).tocsr()
        A.data[:] = 1
        return A

    def _current_contact_pairs(self) -> np.ndarray:
        """Block pairs the contact of every rank couples now (allgathered)."""
        cr, cc = self.contact.node_couplings()
        mine = np.unique(cr.astype(np.int64) * self.n_blocks + cc)
        return np.unique(np.concatenate(self.comm.tompi4py().allgather(mine)))

    def grow(self, J: PETSc.Mat) -> bool:
        """Add the couplings of the current contact pairs to J's pattern; whether it grew."""
        if self.contact is None:
            return False
        # the couplings follow the B elements the local points project onto: unchanged on
        # every rank, nothing to do (the common case; no allgather of the pairs)
        projected = self.contact.projected_elements()
        changed = not np.array_equal(projected, self.projected)
        if not self.comm.tompi4py().allreduce(int(changed)):
            return False
        self.projected = projected
        new = np.setdiff1d(self._current_contact_pairs(), self.contact_pairs, assume_unique=True)
        if len(new) == 0:                       # the same on every rank (allgathered)
            return False
        self.contact_pairs = np.union1d(self.contact_pairs, new)
        self.preallocate(J)
        self.growths += 1
        return True

    def create_matrix(self) -> PETSc.Mat:
        """A new AIJ or SBAIJ matrix (D × D node blocks, 18 for 3363) preallocated with the pattern."""
        D = self.model.dofs_per_node
        lo, hi = self.layout.owned_nodes
        J = PETSc.Mat().create(comm=self.comm)
        N = D * self.n_blocks
        J.setSizes(((D * (hi - lo), N), (D * (hi - lo), N)), bsize=D)
        J.setType(PETSc.Mat.Type.SBAIJ if self.matrix_type == "sbaij" else PETSc.Mat.Type.AIJ)
        self.preallocate(J)
        return J

    def preallocate(self, J: PETSc.Mat) -> None:
        """(Re)set J's nonzero pattern from ``node_pattern``, in J's format."""
        if self.matrix_type == "sbaij":
            self._sbaij(J)
        else:
            self._aij(J)

    def _aij(self, J: PETSc.Mat) -> None:
        """(Re)set an AIJ J's pattern from ``node_pattern`` (exact; held DOFs only on the diagonal).

        A free DOF row of node i couples with every free DOF of the nodes i is coupled with; a
        held DOF's row is its diagonal alone (its column is dropped everywhere else)."""
        D = self.model.dofs_per_node
        lo, hi = self.layout.owned_nodes
        A = self.node_pattern((lo, hi))
        free = ~self.fixed_mask
        node_cols = (D * A.indices[:, None] + np.arange(D)).ravel()      # DOF columns per entry
        keep = free[node_cols]
        cols = node_cols[keep]                                            # free columns, node by node
        count = np.add.reduceat(keep.reshape(-1, D).sum(axis=1), A.indptr[:-1]) \
            if A.nnz else np.zeros(hi - lo, dtype=np.int64)
        count[np.diff(A.indptr) == 0] = 0
        start = np.concatenate([[0], np.cumsum(count)])[:-1]
        rows = D * lo + np.arange(D * (hi - lo))
        row_free = free[rows]
        length = np.where(row_free, np.repeat(count, D), 1)
        indptr = np.concatenate([[0], np.cumsum(length)])
        # free row r of node i: cols[start_i : start_i + count_i]; held row: itself.  Entry k of
        # row r reads cols[start_i + k - indptr_r] (few full-size temporaries: this runs on
        # millions of entries, and fresh large arrays cost page faults)
        shift = np.where(row_free, np.repeat(start, D), 0) - indptr[:-1]
        src = np.repeat(shift, length)
        src += np.arange(indptr[-1])
        indices = cols.astype(PETSc.IntType)[src]
        del src
        held = np.flatnonzero(~row_free)
        indices[indptr[held]] = rows[held]
        J.setPreallocationCSR((indptr.astype(PETSc.IntType), indices))
        J.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        J.setOption(PETSc.Mat.Option.SYMMETRIC, self.contact is None or self.contact.symmetric)

    def _sbaij(self, J: PETSc.Mat) -> None:
        """(Re)set an SBAIJ J's pattern: the node blocks of ``node_pattern`` on or above the
        diagonal (held DOFs are stored inside their node's block, as explicit zeros)."""
        lo, hi = self.layout.owned_nodes
        A = self.node_pattern((lo, hi))
        row = np.repeat(np.arange(hi - lo), np.diff(A.indptr))
        upper = A.indices >= row + lo
        indptr = np.concatenate([[0], np.cumsum(np.bincount(row[upper], minlength=hi - lo))])
        J.setPreallocationCSR((indptr.astype(PETSc.IntType), A.indices[upper].astype(PETSc.IntType)))
        J.setOption(PETSc.Mat.Option.IGNORE_LOWER_TRIANGULAR, True)
        J.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
