"""Residual F(q, z; λ) = f_int(q) + f_con(q, z) − λ f_ext (and the contact constraint rows) and
its Jacobian in PETSc Vec / Mat.

The only module (with ``solver``) that touches PETSc objects.  Each rank evaluates the element
kernels of its own elements on a local copy of exactly the node blocks they need (a VecScatter
from the global vector), adds the element forces back with the reverse scatter, and inserts
element matrices with one batched call per beam.  DOFs held by boundary conditions get the
residual q − q̄ and a unit row/column; their entries in element matrices are dropped (negative
indices, or zeroed values in node blocks), so the Jacobian stays symmetric.  The contact
multipliers z are extra node blocks after the beams' nodes (``Layout.n_blocks``); their unused
slots are held at zero like supported DOFs.

The Jacobian is AIJ, or SBAIJ with 18 × 18 node blocks (``matrix_type``): the upper triangle of
node blocks, inserted one block at a time (``insert_node_blocks``).  That is ~15× faster than
AIJ's entry-by-entry insertion of the same dense element and contact blocks and halves the
stored entries; MUMPS's LDLᵀ takes SBAIJ directly, but PETSc's LU, ILU and GAMG do not.
"""
from __future__ import annotations

from dataclasses import dataclass

import time

import numpy as np
import scipy.sparse as sp
from petsc4py import PETSc

from ..physics import kernels
from ..parallel.layout import Layout
from ..model.beams import Beam, Model

ADD = PETSc.InsertMode.ADD_VALUES
INSERT = PETSc.InsertMode.INSERT_VALUES

EV_ELEMENTS = PETSc.Log.Event("ANCF element kernels")
EV_CONTACT = PETSc.Log.Event("ANCF contact")
STAGE_ASSEMBLY = PETSc.Log.Stage("ANCF assembly")


@dataclass
class ElementBlock:
    """A rank's elements of one beam with their quadrature data."""
    beam: Beam
    parts: list          # [(G (E, P, S, 3), w (E, P), material)] per energy part (Beam.parts)
    nodes: np.ndarray    # (E, 3) PETSc node ids
    rows: np.ndarray     # (E, 3S) PETSc DOF ids, −1 for DOFs held by BCs
    node_dofs: np.ndarray  # (3S/3,) offsets of the active DOFs inside a node's 18-DOF block

    @property
    def G(self) -> np.ndarray:
        """Gradients at the full Gauss points (the first part)."""
        return self.parts[0][0]

    def element_vectors(self, xl: np.ndarray) -> np.ndarray:
        """Active nodal vectors of the elements (E, S, 3) from the local state (n, 6, 3)."""
        return xl[self.lnodes][:, :, list(self.beam.vectors)].reshape(len(self.nodes), -1, 3)

    def local_dofs(self) -> np.ndarray:
        """Positions of the elements' active DOFs in the local array (E, 3S)."""
        return (18 * self.lnodes[:, :, None] + self.node_dofs).reshape(len(self.nodes), -1)


#: Jacobian storage formats (``Problem(matrix_type=...)``)
MATRIX_TYPES = ("aij", "sbaij")


def node_blocks(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Node ids (n, D/18) of DOF index blocks (n, D) made of whole 18-DOF nodes, and a mask
    (n, D) of the held DOFs (−1) of nodes that have free DOFs (None when there are none).
    A node whose 18 DOFs are all −1 (unused, or held entirely) gets the node id −1."""
    n, D = rows.shape
    g = rows.reshape(n, D // 18, 18)
    valid = g >= 0
    node = np.where(valid.any(axis=2), g.max(axis=2) // 18, -1).astype(PETSc.IntType)
    held = ~valid & (node >= 0)[:, :, None]
    return node, (held.reshape(n, D) if held.any() else None)


def zero_held(values: np.ndarray, held: np.ndarray | None) -> np.ndarray:
    """Zero the rows and columns of ``held`` (n, D) in ``values`` (n, D, D), in place (the
    callers' blocks are fresh arrays, inserted once)."""
    if held is None:
        return values
    hit = np.flatnonzero(held.any(axis=1))
    v = values[hit]
    h = held[hit]
    v[h] = 0.0                                        # rows
    v.transpose(0, 2, 1)[h] = 0.0                     # columns
    values[hit] = v
    return values


def node_blocks_fit(model: Model) -> bool:
    """Whether every node's 18 DOFs are active (all beams 3363), as SBAIJ node blocks need."""
    return all(len(b.vectors) == 6 for b in model.beams)


def insert_node_blocks(mat: PETSc.Mat, rows: np.ndarray, values: np.ndarray) -> None:
    """Add dense blocks ``values`` (n, D, D) at DOF indices ``rows`` (n, D; −1 = dropped) to an
    AIJ or SBAIJ ``mat``.  For SBAIJ the DOFs must come as whole nodes (18 consecutive indices
    18 k … 18 k + 17, held ones −1); its lower triangle is ignored (the blocks are symmetric)."""
    if mat.getType().endswith("sbaij"):
        node, held = node_blocks(rows)
        mat.setValuesBlockedRCV(node, node, zero_held(values, held), ADD)
    else:
        rows = rows.astype(PETSc.IntType)
        mat.setValuesRCV(rows, rows, values, ADD)


class Problem:
    """PETSc residual/Jacobian of a model on a layout; ``load_factor`` scales the external loads."""

    def __init__(self, model: Model, layout: Layout, comm=PETSc.COMM_WORLD, contact=None,
                 matrix_type: str = "aij"):
        if matrix_type not in MATRIX_TYPES:
            raise ValueError(f"matrix_type must be one of {MATRIX_TYPES}, not {matrix_type!r}")
        if matrix_type == "sbaij" and not node_blocks_fit(model):
            raise ValueError("SBAIJ node blocks need every beam to use all six nodal vectors "
                             "(element 3363); use matrix_type 'aij'")
        self.matrix_type = matrix_type
        self.model, self.layout, self.comm = model, layout, comm
        self.contact = contact
        self.load_factor = 0.0
        self.timers = {"element_kernels": 0.0, "element_assembly": 0.0, "contact_projection": 0.0,
                       "contact_assembly": 0.0}
        if contact is not None:
            contact.timers = self.timers
        self.inverted = False
        self.contact_failed = False
        if contact is not None and layout.n_blocks != model.n_nodes + contact.space.n_nodes:
            raise ValueError("the layout has no blocks for the contact multipliers; make it with "
                             "partition.make_layout(..., contact)")
        lo, hi = layout.owned_nodes
        n_owned = hi - lo
        self.n_blocks = layout.n_blocks
        N = 18 * self.n_blocks
        held = model.fixed_dofs if contact is None else np.concatenate([model.fixed_dofs,
                                                                      contact.padding_dofs()])
        fixed_petsc = layout.petsc_dofs(held)
        self.fixed_mask = np.zeros(N, dtype=bool)
        self.fixed_mask[fixed_petsc] = True
        owned_fixed = np.sort(fixed_petsc[(fixed_petsc >= 18 * lo) & (fixed_petsc < 18 * hi)])
        self.owned_fixed_local = owned_fixed - 18 * lo

        # nodes this rank needs: those of its elements, plus the contact partners' (see _exchange)
        conn_all = layout.perm[model.connectivity()]
        local_el = layout.local_elements
        self.element_nodes = np.unique(conn_all[local_el].ravel()).astype(np.int64)

        self.blocks: list[ElementBlock] = []
        elem_beam = model.element_beam()
        for beam in model.beams:
            mine = local_el[elem_beam[local_el] == beam.index]
            if len(mine) == 0:
                continue
            local_ids = mine - beam.element_offset
            parts = model.element_data(beam, local_ids)
            cn = conn_all[mine]
            node_dofs = (3 * np.array(beam.vectors)[:, None] + np.arange(3)).ravel()
            rows = (18 * cn[:, :, None] + node_dofs).reshape(len(mine), -1)
            rows = np.where(self.fixed_mask[rows], -1, rows).astype(PETSc.IntType)
            self.blocks.append(ElementBlock(beam, parts, cn, rows, node_dofs))

        self.X = PETSc.Vec().createMPI((18 * n_owned, N), bsize=18, comm=comm)
        self.F = self.X.duplicate()
        # reference state of every block (multipliers start at zero)
        self._model_q0 = np.zeros(N)
        self._model_q0[:model.n_dofs] = model.q0.reshape(-1)
        # owned blocks that are beam nodes (not multipliers)
        self.owned_physical = np.argsort(layout.perm)[lo:hi] < model.n_nodes
        self.n_constraints = 0 if contact is None else contact.n_multipliers
        self.exchanges = 0              # how often the contact exchange was rebuilt
        self.scatter = None
        if contact is not None:
            contact.set_layout(layout)
            if comm.size > 1:
                # a multiplier's function may live on elements of two ranks: its weighted gap
                # (and the law's decision) needs both ranks' points
                contact.sum_over_ranks = self._sum_over_ranks
                contact.all_ranks = self._all_ranks
            self._build_exchange(contact.required_nodes())
        else:
            self._build_exchange(np.zeros(0, dtype=np.int64))
        self.q0 = self._global_from_model(self._model_q0)
        fext = np.zeros(N)
        fext[:model.n_dofs] = model.f_ext
        self.fext = self._global_from_model(fext)
        self.J = self._create_matrix()
        self.set_near_null_space()

    def rigid_body_modes(self) -> list[PETSc.Vec]:
        """Orthonormal rigid-body modes of the reference configuration in nodal coordinates:
        translations move r only; an infinitesimal rotation ω× acts on all six nodal vectors.
        Given to the Jacobian as its near null space (used by GAMG, ignored by LU)."""
        x = self.q0.getArray(readonly=True).reshape(-1, 6, 3)
        phys = self.owned_physical[:, None, None]
        vecs = []
        for k in range(3):
            v = np.zeros_like(x)
            v[:, 0, k] = 1.0
            vecs.append(v * phys)
        for k in range(3):
            vecs.append(np.cross(np.eye(3)[k], x) * phys)
        out = []
        for v in vecs:                          # modified Gram-Schmidt (collective dots)
            w = self.X.duplicate()
            w.setArray(v.ravel())
            for u in out:
                w.axpy(-w.dot(u), u)
            w.scale(1.0 / w.norm())
            out.append(w)
        return out

    def set_near_null_space(self) -> None:
        ns = PETSc.NullSpace().create(vectors=self.rigid_body_modes(), comm=self.comm)
        self.J.setNearNullSpace(ns)

    # ------------------------------------------------------------------ contact exchange
    def _build_exchange(self, contact_nodes: np.ndarray) -> None:
        """(Re)build the local node array and the scatter global → local (collective).

        The local array holds this rank's element nodes and the node blocks its contact points
        read (their A elements and the B elements they project onto): never the whole vector."""
        self.needed = np.union1d(self.element_nodes, contact_nodes).astype(np.int64)
        self.contact_nodes = np.asarray(contact_nodes, dtype=np.int64)
        if self.scatter is not None:
            for obj in (self.scatter, self.xloc, self.floc):
                obj.destroy()
        self.xloc = PETSc.Vec().createSeq(18 * len(self.needed), bsize=18, comm=PETSc.COMM_SELF)
        self.floc = self.xloc.duplicate()
        is_needed = PETSc.IS().createBlock(18, self.needed.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
        self.scatter = PETSc.Scatter().create(self.X, is_needed, self.xloc, None)
        is_needed.destroy()
        # the internal forces are evaluated with held DOFs at their prescribed values, so the free
        # residuals do not depend on them and the symmetric Jacobian (held columns dropped) is exact
        model_node = np.argsort(self.layout.perm)[self.needed]
        held = self.fixed_mask[(18 * self.needed[:, None] + np.arange(18))]
        self.held_local = np.flatnonzero(held.ravel())
        self.held_values = self._model_q0.reshape(-1, 18)[model_node].ravel()[self.held_local]
        for blk in self.blocks:
            blk.lnodes = np.searchsorted(self.needed, blk.nodes)
        if self.contact is not None:
            self.contact.set_available(self.needed)

    def _exchange(self) -> None:
        """Rebuild the exchange if any rank's contact pairs changed (collective)."""
        if self.contact is None:
            return
        want = self.contact.required_nodes()
        changed = self.contact.missing or not np.array_equal(want, self.contact_nodes)
        if self.comm.tompi4py().allreduce(int(changed)):
            self._build_exchange(want)
            self.exchanges += 1

    def _with_exchange(self, X: PETSc.Vec, evaluate):
        """Run ``evaluate(xl)`` on the local state of X; if a contact projection reached a node
        block the rank did not hold, exchange and evaluate again (collective)."""
        for _ in range(20):
            self._exchange()
            xl = self._local_state(X)
            out = evaluate(xl)
            missing = self.contact is not None and self.contact.missing
            if not self.comm.tompi4py().allreduce(int(missing)):
                return out
        raise RuntimeError("contact exchange did not settle")   # not reached: one element per retry

    def _sum_over_ranks(self, values: np.ndarray) -> np.ndarray:
        """Sum per-rank partial values of the local multipliers (columns of ``values``) over
        the ranks that hold them (collective: reverse scatter-add, forward scatter)."""
        pos = self.contact.multiplier_positions(self.needed)
        out = np.empty_like(values)
        work = self.F.duplicate()
        local = np.zeros(self.xloc.getLocalSize())
        for c in range(values.shape[1]):
            local[:] = 0.0
            local[pos] = values[:, c]
            self.floc.setArray(local)
            work.set(0.0)
            self.scatter.scatter(self.floc, work, ADD, PETSc.ScatterMode.REVERSE)
            self.scatter.scatter(work, self.floc, INSERT, PETSc.ScatterMode.FORWARD)
            out[:, c] = self.floc.getArray(readonly=True)[pos]
        work.destroy()
        return out

    def _all_ranks(self, flag: bool) -> bool:
        return bool(self.comm.tompi4py().allreduce(int(not flag)) == 0)

    # ------------------------------------------------------------------ helpers
    def _global_from_model(self, arr_model: np.ndarray) -> PETSc.Vec:
        """Global Vec from a model-numbered array of every block (every rank holds it all)."""
        v = self.X.duplicate()
        lo, hi = self.layout.owned_nodes
        inv = np.argsort(self.layout.perm)[lo:hi]          # PETSc node → model node
        v.setArray(arr_model.reshape(-1, 18)[inv].ravel())
        return v

    def to_model_order(self, full_petsc: np.ndarray) -> np.ndarray:
        """A full PETSc-ordered array (18 n_blocks,) → model order (n_blocks, 6, 3): the beam
        nodes, then the multiplier blocks."""
        return full_petsc.reshape(-1, 18)[self.layout.perm].reshape(-1, 6, 3)

    def node_pattern(self, rows: tuple[int, int] | None = None) -> sp.csr_matrix:
        """Node-block coupling (PETSc numbering): elements + the contact pairs seen so far;
        with ``rows = (lo, hi)`` only those node rows (shape (hi − lo, n))."""
        n = self.n_blocks
        lo, hi = (0, n) if rows is None else rows
        conn = self.layout.perm[self.model.connectivity()]
        conn = conn[np.any((conn >= lo) & (conn < hi), axis=1)]
        r = np.repeat(conn, 3, axis=1).ravel()
        c = np.tile(conn, (1, 3)).ravel()
        if self.contact is not None:
            cr, cc = np.divmod(self._contact_pairs, n)
            r, c = np.concatenate([r, cr]), np.concatenate([c, cc])
        mine = (r >= lo) & (r < hi)
        A = sp.coo_matrix((np.ones(int(mine.sum()), dtype=np.int8), (r[mine] - lo, c[mine])),
                          shape=(hi - lo, n)).tocsr()
        A.data[:] = 1
        return A

    def _current_contact_pairs(self) -> np.ndarray:
        """Block pairs (row · n_blocks + col) the contact of every rank couples now (collective)."""
        cr, cc = self.contact.node_couplings()
        mine = np.unique(cr.astype(np.int64) * self.n_blocks + cc)
        return np.unique(np.concatenate(self.comm.tompi4py().allgather(mine)))

    def grow_pattern(self) -> bool:
        """Add the node couplings of the current contact pairs to the Jacobian's nonzero pattern
        (collective).  A point that slides onto another element of B couples new node blocks:
        the matrix is preallocated again with the union (MUMPS redoes its symbolic analysis), so
        the pattern holds exactly the couplings that occurred, never a whole search window."""
        if self.contact is None:
            return False
        # the couplings follow the B elements the local points project onto: unchanged on
        # every rank, nothing to do (the common case; no allgather of the pairs)
        projected = self.contact.projected_elements()
        changed = not np.array_equal(projected, self._projected)
        if not self.comm.tompi4py().allreduce(int(changed)):
            return False
        self._projected = projected
        now = self._current_contact_pairs()
        new = np.setdiff1d(now, self._contact_pairs, assume_unique=True)
        if len(new) == 0:                       # the same on every rank (allgathered)
            return False
        self._contact_pairs = np.union1d(self._contact_pairs, new)
        self._preallocate(self.J)
        self.pattern_growths += 1
        return True

    def _preallocate(self, J: PETSc.Mat) -> None:
        """(Re)set J's nonzero pattern from ``node_pattern``, in J's format."""
        if self.matrix_type == "sbaij":
            self._preallocate_sbaij(J)
        else:
            self._preallocate_aij(J)

    def _preallocate_aij(self, J: PETSc.Mat) -> None:
        """(Re)set an AIJ J's pattern from ``node_pattern`` (exact; held DOFs only on the diagonal).

        A free DOF row of node i couples with every free DOF of the nodes i is coupled with; a
        held DOF's row is its diagonal alone (its column is dropped everywhere else)."""
        lo, hi = self.layout.owned_nodes
        A = self.node_pattern((lo, hi))
        free = ~self.fixed_mask
        node_cols = (18 * A.indices[:, None] + np.arange(18)).ravel()      # DOF columns per entry
        keep = free[node_cols]
        cols = node_cols[keep]                                            # free columns, node by node
        count = np.add.reduceat(keep.reshape(-1, 18).sum(axis=1), A.indptr[:-1]) \
            if A.nnz else np.zeros(hi - lo, dtype=np.int64)
        count[np.diff(A.indptr) == 0] = 0
        start = np.concatenate([[0], np.cumsum(count)])[:-1]
        rows = 18 * lo + np.arange(18 * (hi - lo))
        row_free = free[rows]
        length = np.where(row_free, np.repeat(count, 18), 1)
        indptr = np.concatenate([[0], np.cumsum(length)])
        # free row r of node i: cols[start_i : start_i + count_i]; held row: itself.  Entry k of
        # row r reads cols[start_i + k - indptr_r] (few full-size temporaries: this runs on
        # millions of entries, and fresh large arrays cost page faults)
        shift = np.where(row_free, np.repeat(start, 18), 0) - indptr[:-1]
        src = np.repeat(shift, length)
        src += np.arange(indptr[-1])
        indices = cols.astype(PETSc.IntType)[src]
        del src
        held = np.flatnonzero(~row_free)
        indices[indptr[held]] = rows[held]
        J.setPreallocationCSR((indptr.astype(PETSc.IntType), indices))
        J.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        J.setOption(PETSc.Mat.Option.SYMMETRIC, True)

    def _preallocate_sbaij(self, J: PETSc.Mat) -> None:
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

    def _create_matrix(self) -> PETSc.Mat:
        lo, hi = self.layout.owned_nodes
        self.pattern_growths = 0
        if self.contact is not None:
            self._contact_pairs = self._current_contact_pairs()
            self._projected = self.contact.projected_elements()
        J = PETSc.Mat().create(comm=self.comm)
        N = 18 * self.n_blocks
        J.setSizes(((18 * (hi - lo), N), (18 * (hi - lo), N)), bsize=18)
        J.setType(PETSc.Mat.Type.SBAIJ if self.matrix_type == "sbaij" else PETSc.Mat.Type.AIJ)
        self._preallocate(J)
        return J

    def _local_state(self, X: PETSc.Vec) -> np.ndarray:
        """The needed node blocks of X, with held DOFs at their prescribed values."""
        self.scatter.scatter(X, self.xloc, INSERT, PETSc.ScatterMode.FORWARD)
        xl = self.xloc.getArray().reshape(-1, 6, 3)
        xl.reshape(-1)[self.held_local] = self.held_values
        return xl

    # ------------------------------------------------------------------ SNES callbacks
    def residual(self, snes, X: PETSc.Vec, F: PETSc.Vec) -> None:
        STAGE_ASSEMBLY.push()
        try:
            floc, bad = self._with_exchange(X, self._local_residual)
            self._finish_residual(X, F, floc, bad or self.contact_failed)
        finally:
            STAGE_ASSEMBLY.pop()

    def _local_residual(self, xl: np.ndarray) -> tuple[np.ndarray, bool]:
        """Internal (eq. 9) and contact forces of this rank's elements and points, local order."""
        floc = np.zeros(self.xloc.getLocalSize())
        bad = False
        EV_ELEMENTS.begin()
        t0 = time.perf_counter()
        for blk in self.blocks:
            qe = blk.element_vectors(xl)
            for k, (G, w, material) in enumerate(blk.parts):
                f, Jmin = kernels.internal_force(qe, G, w, material)
                bad |= k == 0 and not np.all(Jmin > 0.0)      # full-section part
                floc += np.bincount(blk.local_dofs().ravel(), f.ravel(), minlength=floc.size)
        self.timers["element_kernels"] += time.perf_counter() - t0
        EV_ELEMENTS.end()
        self.contact_failed = False
        if self.contact is not None:
            EV_CONTACT.begin()
            t0, p0 = time.perf_counter(), self.timers["contact_projection"]
            ok = self.contact.add_residual(xl, self.needed, floc)
            self.timers["contact_assembly"] += (time.perf_counter() - t0
                                                - (self.timers["contact_projection"] - p0))
            self.contact_failed = not ok
            EV_CONTACT.end()
        return floc, bad

    def _finish_residual(self, X, F, floc, bad):
        self.floc.setArray(floc)
        F.set(0.0)
        self.scatter.scatter(self.floc, F, ADD, PETSc.ScatterMode.REVERSE)
        F.axpy(-self.load_factor, self.fext)
        fa = F.getArray()
        if len(self.owned_fixed_local):
            fa[self.owned_fixed_local] = (X.getArray(readonly=True)[self.owned_fixed_local]
                                          - self.q0.getArray(readonly=True)[self.owned_fixed_local])
        self.inverted = bool(bad or not np.all(np.isfinite(fa)))
        if self.inverted:
            self.inverted = not self.contact_failed
            # J <= 0 somewhere: a NaN residual makes the line search back off (no exception,
            # so no rank is left waiting in a collective call)
            fa[:] = np.nan
        del fa

    def min_jacobian(self, X: PETSc.Vec) -> float:
        """Smallest det F over every Gauss point of every rank (collective)."""
        xl = self._local_state(X)
        local = np.inf
        for blk in self.blocks:
            F = kernels.deformation_gradient(blk.element_vectors(xl), blk.G)
            local = min(local, float(np.min(np.linalg.det(F))))
        val = self.comm.tompi4py().allreduce(local, op=__import__("mpi4py").MPI.MIN)
        return val if np.isfinite(val) else -np.inf

    def precheck(self, X: PETSc.Vec, Y: PETSc.Vec, j_min: float = 0.1, halvings: int = 12) -> bool:
        """Line-search pre-check (collective).  A Newton step that moves a node by more than ten
        section sizes is scaled down to that first (a near-singular tangent gives absurd steps);
        then the step X − Y is halved until no Gauss point has det F below ``j_min``.  If that
        fails, Y is filled with NaN so that SNES reports a domain failure and the load step is
        cut back.  Returns whether Y was changed."""
        from mpi4py import MPI
        comm = self.comm.tompi4py()
        size = min(np.sqrt(b.section.area) for b in self.model.beams)
        y = Y.getArray(readonly=True).reshape(-1, 6, 3)[self.owned_physical]
        big = comm.allreduce(float(np.abs(y[:, 0]).max(initial=0.0)), op=MPI.MAX) / (10.0 * size)
        changed = False
        if big > 1.0:
            Y.scale(1.0 / big)
            changed = True
        trial = X.duplicate()
        try:
            for _ in range(halvings):
                X.copy(trial)
                trial.axpy(-1.0, Y)
                if self.min_jacobian(trial) >= j_min:
                    return changed
                Y.scale(0.5)
                changed = True
            Y.set(np.nan)
            return True
        finally:
            trial.destroy()

    def reference_residual_norm(self) -> float:
        """‖F(q0, λ = 0)‖: zero in exact arithmetic, so it measures the residual's rounding floor."""
        lam = self.load_factor
        self.load_factor = 0.0
        X, F = self.q0.copy(), self.F.duplicate()
        self.residual(None, X, F)
        self.load_factor = lam
        value = F.norm()
        X.destroy()
        F.destroy()
        return value

    def objective(self, snes, X: PETSc.Vec) -> float:
        """Total potential Π = Σ ∫Ψ dV + Π_con − λ f_ext·q (the residual is its gradient).

        Used by the line searches (bt, l2) as merit function instead of ‖F‖²; +inf when an
        element is inverted.  Collective: every rank returns the same value.  Not defined with
        contact: the residual is then the gradient of a Lagrangian, whose stationary point is a
        saddle (``has_potential``).
        """
        if not self.has_potential:
            raise RuntimeError("no potential with contact multipliers; use the residual merit")
        STAGE_ASSEMBLY.push()
        try:
            def local_energy(xl):
                local = 0.0
                for blk in self.blocks:
                    qe = blk.element_vectors(xl)
                    local += sum(float(np.sum(kernels.energy(qe, G, w, material)))
                                 for G, w, material in blk.parts)
                return local
            local = self._with_exchange(X, local_energy)
            total = self.comm.tompi4py().allreduce(local)
            total -= self.load_factor * self.fext.dot(X)
            return total if np.isfinite(total) else np.inf
        finally:
            STAGE_ASSEMBLY.pop()

    def jacobian(self, snes, X: PETSc.Vec, J: PETSc.Mat, P: PETSc.Mat) -> None:
        STAGE_ASSEMBLY.push()
        try:
            P.zeroEntries()
            if self.contact is not None:
                # contact first: the exchange may grow the local array; its blocks are only
                # added to P once no rank had to exchange again
                EV_CONTACT.begin()
                t0, p0 = time.perf_counter(), self.timers["contact_projection"]
                blocks = []

                def contact_blocks(xl):
                    blocks[:] = self.contact.jacobian_blocks(xl, self.needed, self.fixed_mask)
                    return xl
                xl = self._with_exchange(X, contact_blocks)
                if self.grow_pattern():
                    if P.handle != self.J.handle:
                        raise RuntimeError("the contact pattern grew on a preconditioner matrix "
                                           "this Problem did not create")
                    if snes is not None and self.matrix_type == "sbaij":
                        # re-preallocating an SBAIJ matrix does not mark its pattern as new, so
                        # the factorisation would reuse the old symbolic analysis: start afresh
                        snes.getKSP().getPC().reset()
                for rows, values in blocks:
                    insert_node_blocks(P, rows, values)
                self.timers["contact_assembly"] += (time.perf_counter() - t0
                                                    - (self.timers["contact_projection"] - p0))
                EV_CONTACT.end()
            else:
                xl = self._local_state(X)
            EV_ELEMENTS.begin()
            for blk in self.blocks:
                qe = blk.element_vectors(xl)
                t0 = time.perf_counter()
                K = sum(kernels.internal_force_and_tangent(qe, G, w, material)[1]
                        for G, w, material in blk.parts)
                t1 = time.perf_counter()
                insert_node_blocks(P, blk.rows, K)
                self.timers["element_kernels"] += t1 - t0
                self.timers["element_assembly"] += time.perf_counter() - t1
            EV_ELEMENTS.end()
            d = (self.owned_fixed_local + 18 * self.layout.owned_nodes[0]).astype(PETSc.IntType)
            if len(d):
                P.setValuesRCV(d[:, None], d[:, None], np.ones((len(d), 1, 1)), ADD)
            P.assemble()
            if J.handle != P.handle:
                J.assemble()
        finally:
            STAGE_ASSEMBLY.pop()

    # ------------------------------------------------------------------ state
    @property
    def has_potential(self) -> bool:
        """Whether the residual is the gradient of a potential (no contact multipliers)."""
        return self.contact is None

    def contact_gaps(self, X: PETSc.Vec) -> dict | None:
        """Per-interface gap and pressure statistics at X, each rank over its own points,
        combined (collective)."""
        if self.contact is None:
            return None
        from mpi4py import MPI
        from ..contact import GAP_COLUMNS
        local = self._with_exchange(X, lambda xl: self.contact.gap_sums(xl, self.needed))
        comm = self.comm.tompi4py()
        out = np.empty_like(local)
        for op, mpi_op in (("max", MPI.MAX), ("sum", MPI.SUM)):
            cols = [k for k, (_, how) in enumerate(GAP_COLUMNS) if how == op]
            part = np.empty((len(local), len(cols)))
            comm.Allreduce(np.ascontiguousarray(local[:, cols]), part, op=mpi_op)
            out[:, cols] = part
        return self.contact.gap_report(out)

    def contact_fields(self, X: PETSc.Vec) -> dict | None:
        """``Contact.point_fields`` of every rank on rank 0, points sorted by id (``point_*``,
        ``x``, ...) and multipliers sorted by id (``multiplier_*``); collective; None without
        contact and on the other ranks."""
        if self.contact is None:
            return None
        q0 = self.model.q0                                       # (n_nodes, 6, 3)
        conn = self.model.connectivity()

        def q0_of(els):
            return q0[conn[els]].reshape(len(els), 18, 3)
        local = self._with_exchange(X, lambda xl: self.contact.point_fields(xl, self.needed, q0_of))
        parts = self.comm.tompi4py().gather(local, root=0)
        if self.comm.rank != 0:
            return None
        out = {k: np.concatenate([p[k] for p in parts]) for k in local}
        for key in ("id", "multiplier_id"):
            order = np.argsort(out[key])
            for k in out:
                if k.startswith("multiplier") == key.startswith("multiplier"):
                    out[k] = out[k][order]
        return out

    def state_is_clean(self) -> bool:
        """After SNES converged: did the last residual use converged contact projections? (collective)"""
        ok = self.contact is None or self.contact.converged()
        return bool(self.comm.tompi4py().allreduce(int(not ok)) == 0)

    def checkpoint(self) -> None:
        """Called at every converged state: history the residual depends on (contact projections)."""
        if self.contact is not None:
            self.contact.checkpoint()

    def restore(self) -> None:
        """Back to the last checkpoint after a failed attempt."""
        if self.contact is not None:
            self.contact.restore()

    def gather(self, X: PETSc.Vec | None = None, blocks: bool = False) -> np.ndarray | None:
        """Beam nodal vectors in model order (n_nodes, 6, 3) on rank 0 (None elsewhere); with
        ``blocks`` every block, multiplier blocks after the nodes (n_blocks, 6, 3)."""
        X = self.X if X is None else X
        scat, full = PETSc.Scatter.toZero(X)
        scat.scatter(X, full, INSERT, PETSc.ScatterMode.FORWARD)
        out = None
        if self.comm.rank == 0:
            out = self.to_model_order(full.getArray().copy())
            out = out if blocks else out[:self.model.n_nodes]
        scat.destroy()
        full.destroy()
        return out
