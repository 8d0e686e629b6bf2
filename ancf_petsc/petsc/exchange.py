"""The node blocks one rank reads (ghost exchange): its elements' nodes plus the nodes its contact
points read (their A elements and the B elements they project onto), never the whole vector.

A VecScatter copies them from the global vector into a local array (``local_state``) and adds
local forces back (``add_to``).  When a contact projection reaches a node block the rank does
not hold, the exchange is rebuilt and the evaluation repeated (``evaluate``; collective).
"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from ..parallel.layout import Layout
from .blocks import ADD, INSERT, ElementBlock


class GhostExchange:
    """Global vector ↔ this rank's local node array (collective methods unless noted)."""

    def __init__(self, X: PETSc.Vec, layout: Layout, fixed_mask: np.ndarray, q0_model: np.ndarray,
                 blocks: list[ElementBlock], contact=None, moved_model: list | None = None):
        self.X, self.layout, self.fixed_mask, self.contact = X, layout, fixed_mask, contact
        self.q0_model = q0_model                # reference state of every block, model order
        #: prescribed displacements at multiplier 1 per load group (model order; displacement
        #: control) and the groups' multipliers now: held DOFs are at q0 + Σ m_g moved_g
        self.moved_model = list(moved_model or [])
        self.multipliers = np.zeros(len(self.moved_model))
        self.blocks = blocks
        self.comm = X.getComm()
        conn = np.concatenate([b.nodes.ravel() for b in blocks]) if blocks else np.zeros(0, np.int64)
        self.element_nodes = np.unique(conn).astype(np.int64)
        self.needed = self.element_nodes        # local array: these node blocks, in this order
        self.contact_nodes = np.zeros(0, dtype=np.int64)
        self.scatter: PETSc.Scatter | None = None
        self.last: PETSc.Vec | None = None      # the state of the last evaluation (with contact)
        self.xloc: PETSc.Vec | None = None
        self.floc: PETSc.Vec | None = None
        self.held_local = np.zeros(0, dtype=np.int64)    # held DOFs in the local array …
        self.held_values = np.zeros(0)                   # … their reference values …
        self.held_moves = np.zeros((0, 0))               # … and prescribed displacements
        self.rebuilds = 0                       # how often contact pairs changed the exchange
        self.build(contact.required_nodes() if contact is not None else np.zeros(0, dtype=np.int64))

    def build(self, contact_nodes: np.ndarray) -> None:
        """(Re)build the local node array and the scatter global → local (collective).

        The local array holds this rank's element nodes and the node blocks its contact points
        read (their A elements and the B elements they project onto): never the whole vector."""
        self.needed = np.union1d(self.element_nodes, contact_nodes).astype(np.int64)
        self.forget_state()                     # a new local array: the next evaluation refreshes
        self.contact_nodes = np.asarray(contact_nodes, dtype=np.int64)
        if self.scatter is not None:
            for obj in (self.scatter, self.xloc, self.floc):
                obj.destroy()
        D = self.layout.dofs_per_node
        self.xloc = PETSc.Vec().createSeq(D * len(self.needed), bsize=D, comm=PETSc.COMM_SELF)
        self.floc = self.xloc.duplicate()
        is_needed = PETSc.IS().createBlock(D, self.needed.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
        self.scatter = PETSc.Scatter().create(self.X, is_needed, self.xloc, None)
        is_needed.destroy()
        # the internal forces are evaluated with held DOFs at their prescribed values, so the free
        # residuals do not depend on them and the symmetric Jacobian (held columns dropped) is exact
        model_node = np.argsort(self.layout.perm)[self.needed]
        held = self.fixed_mask[(D * self.needed[:, None] + np.arange(D))]
        self.held_local = np.flatnonzero(held.ravel())
        self.held_values = self.q0_model.reshape(-1, D)[model_node].ravel()[self.held_local]
        self.held_moves = np.array([m.reshape(-1, D)[model_node].ravel()[self.held_local]
                                    for m in self.moved_model]).reshape(len(self.moved_model), -1)
        for blk in self.blocks:
            blk.lnodes = np.searchsorted(self.needed, blk.nodes)
        if self.contact is not None:
            self.contact.set_available(self.needed)

    def forget_state(self) -> None:
        """No last evaluated state (``evaluate`` then refreshes the exchange first)."""
        if self.last is not None:
            self.last.destroy()
        self.last = None

    def refresh(self, reached: np.ndarray | None = None) -> None:
        """Rebuild the exchange if any rank's contact pairs changed (``reached``: node blocks an
        attempt of the evaluation being repeated reached, kept)."""
        if self.contact is None:
            return
        want = self.contact.required_nodes()
        if reached is not None:
            want = np.union1d(want, reached)
        changed = self.contact.missing or not np.array_equal(want, self.contact_nodes)
        if self.comm.tompi4py().allreduce(int(changed)):
            self.build(want)
            self.rebuilds += 1

    def evaluate(self, X: PETSc.Vec, evaluate):
        """``evaluate(xl)`` on the local state of X; if a contact projection reached a node block
        the rank did not hold, exchange and evaluate again, every point from the place it started
        the first attempt from: its descent is then the one a single rank makes (an attempt's
        point waits at the boundary of the element it lacks, and a descent from there may end at
        another closest point), and the contact law decides on that evaluation only (Contact)."""
        start = None if self.contact is None else self.contact.projector.state()
        reached = None
        # at the state the last evaluation was made at, its exchange served it: a rebuild (to a
        # smaller set) would only drop the contact's kept evaluation, and the projections made
        # again from their own results may move where one rank's kept ones do not
        again = self.last is not None and X.equal(self.last)
        for attempt in range(20):
            if attempt or not again:
                self.refresh(reached)
            out = evaluate(self.local_state(X))
            missing = self.contact is not None and self.contact.missing
            if not self.comm.tompi4py().allreduce(int(missing)):
                if self.contact is not None:
                    self.last = X.copy(self.last)
                return out
            reached = np.union1d(self.contact.required_nodes(), [] if reached is None else reached)
            self.contact.projector.resume(start)
        raise RuntimeError("contact exchange did not settle")   # not reached: one element per retry

    def local_state(self, X: PETSc.Vec) -> np.ndarray:
        """The needed node blocks of X (n, V, 3), with held DOFs at their prescribed values."""
        self.scatter.scatter(X, self.xloc, INSERT, PETSc.ScatterMode.FORWARD)
        xl = self.xloc.getArray().reshape(-1, self.layout.dofs_per_node // 3, 3)
        xl.reshape(-1)[self.held_local] = self.held_values + self.multipliers @ self.held_moves
        return xl

    def add_to(self, local: np.ndarray, F: PETSc.Vec) -> None:
        """F = the local forces summed over the ranks (reverse scatter-add)."""
        self.floc.setArray(local)
        F.set(0.0)
        self.scatter.scatter(self.floc, F, ADD, PETSc.ScatterMode.REVERSE)

    def sum_over_ranks(self, values: np.ndarray) -> np.ndarray:
        """Sum per-rank partial values of the local multipliers (columns of ``values``) over
        the ranks that hold them (collective: reverse scatter-add, forward scatter)."""
        pos = self.contact.multiplier_positions(self.needed)
        out = np.empty_like(values)
        work = self.X.duplicate()
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

    def reduce(self, values: np.ndarray, op: str) -> np.ndarray:
        """Element-wise 'max', 'min' or 'sum' of ``values`` over the ranks."""
        out = np.empty_like(values)
        self.comm.tompi4py().Allreduce(values, out, op={"max": MPI.MAX, "min": MPI.MIN, "sum": MPI.SUM}[op])
        return out

    def all_ranks(self, flag: bool) -> bool:
        """Whether ``flag`` holds on every rank."""
        return bool(self.comm.tompi4py().allreduce(int(not flag)) == 0)

    def destroy(self) -> None:
        """Free the scatter and the local vectors (not collective)."""
        for obj in (self.scatter, self.xloc, self.floc, self.last):
            if obj is not None:
                obj.destroy()
        self.scatter = self.xloc = self.floc = self.last = None
