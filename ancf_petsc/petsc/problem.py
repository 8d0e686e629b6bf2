"""Residual F(q, z; λ) = f_int(q) + f_con(q, z) − λ f_ext (and the contact constraint rows) and
its Jacobian in PETSc Vec / Mat: the callbacks SNES calls.

Each rank evaluates the element kernels of its own elements on a local copy of exactly the node
blocks they need (``exchange.GhostExchange``), adds the element forces back with the reverse
scatter, and inserts element matrices with one batched call per beam (``blocks``) into a matrix
preallocated with the exact node-block pattern (``pattern``).  DOFs held by boundary conditions
get the residual q − q̄ and a unit row/column.  The contact multipliers z are extra node blocks
after the beams' nodes (``Layout.n_blocks``); their unused slots are held at zero like supported
DOFs.
"""
from __future__ import annotations

import contextlib
import time

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from ..model.beams import Model
from ..parallel.layout import Layout
from ..physics import kernels
from ..physics.element3363 import DOFS_PER_NODE
from ..physics.rigid import rigid_modes
from . import logging
from .blocks import ADD, INSERT, MATRIX_TYPES, element_blocks, insert_node_blocks, node_blocks_fit
from .exchange import GhostExchange
from .pattern import JacobianPattern


#: largest node move of one Newton step, in section sizes (precheck); full Newton steps with
#: contact are held to fewer (solving/stepper.py): a step of several sections makes the
#: closest-point pairing meaningless (the paper's tendon in fixed steps of 100 N from rest
#: wandered to |F| ~ 1e8 and failed with 10)
MAX_STEP_SECTIONS = 10.0
MAX_STEP_SECTIONS_CONTACT = 2.0


class Problem:
    """PETSc residual/Jacobian of a model on a layout; ``load_factor`` scales the external loads."""

    def __init__(self, model: Model, layout: Layout, comm=None, contact=None, matrix_type: str = "aij"):
        comm = PETSc.COMM_WORLD if comm is None else comm
        if matrix_type not in MATRIX_TYPES:
            raise ValueError(f"matrix_type must be one of {MATRIX_TYPES}, not {matrix_type!r}")
        if matrix_type == "sbaij" and not node_blocks_fit(model):
            raise ValueError("SBAIJ node blocks need every beam to use all six nodal vectors "
                             "(element 3363); use matrix_type 'aij'")
        if contact is not None and layout.n_blocks != model.n_nodes + contact.space.n_nodes:
            raise ValueError("the layout has no blocks for the contact multipliers; make it with "
                             "parallel.partition.make_layout(..., contact)")
        self.matrix_type = matrix_type
        self.model, self.layout, self.comm, self.contact = model, layout, comm, contact
        self.step_sections = MAX_STEP_SECTIONS          # precheck's largest step (section sizes)
        self.load_factor = 0.0
        self.timers = {"element_kernels": 0.0, "element_assembly": 0.0, "contact_projection": 0.0,
                       "contact_assembly": 0.0}
        self.inverted = False                   # the last residual met det F <= 0
        self.contact_failed = False             # the last residual's contact projection failed
        lo, hi = layout.owned_nodes
        self.n_blocks = layout.n_blocks
        N = DOFS_PER_NODE * self.n_blocks
        held = model.fixed_dofs if contact is None else np.concatenate([model.fixed_dofs,
                                                                      contact.padding_dofs()])
        fixed_petsc = layout.petsc_dofs(held)
        self.fixed_mask = np.zeros(N, dtype=bool)
        self.fixed_mask[fixed_petsc] = True
        owned_fixed = np.sort(fixed_petsc[(fixed_petsc >= DOFS_PER_NODE * lo) & (fixed_petsc < DOFS_PER_NODE * hi)])
        self.owned_fixed_local = owned_fixed - DOFS_PER_NODE * lo
        self.blocks = element_blocks(model, layout, self.fixed_mask)
        self.X = PETSc.Vec().createMPI((DOFS_PER_NODE * (hi - lo), N), bsize=DOFS_PER_NODE, comm=comm)
        self.F = self.X.duplicate()
        q0_model = np.zeros(N)                  # reference state of every block (multipliers 0)
        q0_model[:model.n_dofs] = model.q0.reshape(-1)
        self.owned_physical = np.argsort(layout.perm)[lo:hi] < model.n_nodes   # beam nodes, not z
        self.n_constraints = 0 if contact is None else contact.n_multipliers
        if contact is not None:
            contact.timers = self.timers
            contact.set_layout(layout)
        self.exchange = GhostExchange(self.X, layout, self.fixed_mask, q0_model, self.blocks, contact)
        if contact is not None and comm.size > 1:
            # a multiplier's function may live on elements of two ranks: its weighted gap (and
            # the law's decision) needs both ranks' points
            contact.sum_over_ranks = self.exchange.sum_over_ranks
            contact.all_ranks = self.exchange.all_ranks
            contact.reduce = self.exchange.reduce
        self.q0 = self.global_vector(q0_model)
        fext = np.zeros(N)
        fext[:model.n_dofs] = model.f_ext
        self.fext = self.global_vector(fext)
        self.pattern = JacobianPattern(model, layout, self.fixed_mask, contact, comm, matrix_type)
        self.J = self.pattern.create_matrix()
        modes = self.rigid_body_modes()
        null_space = PETSc.NullSpace().create(vectors=modes, comm=comm)
        self.J.setNearNullSpace(null_space)
        for obj in modes + [null_space]:        # J keeps its own reference
            obj.destroy()

    def rigid_body_modes(self) -> list[PETSc.Vec]:
        """Orthonormal rigid-body modes of the reference configuration (``physics.rigid``), given
        to the Jacobian as its near null space (used by GAMG, ignored by LU)."""
        x = self.q0.getArray(readonly=True).reshape(-1, 6, 3)
        out = []
        for v in rigid_modes(x):                # modified Gram-Schmidt (collective dots)
            w = self.X.duplicate()
            w.setArray((v * self.owned_physical[:, None, None]).ravel())
            for u in out:
                w.axpy(-w.dot(u), u)
            w.scale(1.0 / w.norm())
            out.append(w)
        return out

    def global_vector(self, arr_model: np.ndarray) -> PETSc.Vec:
        """Global Vec from a model-numbered array of every block (every rank holds it all)."""
        v = self.X.duplicate()
        lo, hi = self.layout.owned_nodes
        inv = np.argsort(self.layout.perm)[lo:hi]          # PETSc node → model node
        v.setArray(arr_model.reshape(-1, DOFS_PER_NODE)[inv].ravel())
        return v

    @property
    def pattern_growths(self) -> int:
        return self.pattern.growths

    # ------------------------------------------------------------------ SNES callbacks
    def residual(self, snes, X: PETSc.Vec, F: PETSc.Vec) -> None:
        """F(X) (SNES function callback)."""
        logging.stage(logging.ASSEMBLY).push()
        try:
            floc, bad = self.exchange.evaluate(X, self._local_residual)
            self._finish_residual(X, F, floc, bad or self.contact_failed)
        finally:
            logging.stage(logging.ASSEMBLY).pop()

    def _local_residual(self, xl: np.ndarray) -> tuple[np.ndarray, bool]:
        """Internal (eq. 9) and contact forces of this rank's elements and points, local order."""
        floc = np.zeros(self.exchange.xloc.getLocalSize())
        bad = False
        logging.event(logging.ELEMENTS).begin()
        t0 = time.perf_counter()
        for blk in self.blocks:
            qe = blk.element_vectors(xl)
            for k, (G, w, material) in enumerate(blk.parts):
                f, Jmin = kernels.internal_force(qe, G, w, material)
                bad |= k == 0 and not np.all(Jmin > 0.0)      # full-section part
                floc += np.bincount(blk.local_dofs().ravel(), f.ravel(), minlength=floc.size)
        self.timers["element_kernels"] += time.perf_counter() - t0
        logging.event(logging.ELEMENTS).end()
        self.contact_failed = False
        if self.contact is not None:
            with self._contact_timer():
                self.contact_failed = not self.contact.add_residual(xl, self.exchange.needed, floc)
        return floc, bad

    def _finish_residual(self, X, F, floc, bad):
        self.exchange.add_to(floc, F)
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

    @contextlib.contextmanager
    def _contact_timer(self):
        """Time contact assembly (minus the projection, which the contact times itself)."""
        logging.event(logging.CONTACT).begin()
        t0, p0 = time.perf_counter(), self.timers["contact_projection"]
        try:
            yield
        finally:
            self.timers["contact_assembly"] += (time.perf_counter() - t0
                                                - (self.timers["contact_projection"] - p0))
            logging.event(logging.CONTACT).end()

    def jacobian(self, snes, X: PETSc.Vec, J: PETSc.Mat, P: PETSc.Mat) -> None:
        """J(X) (SNES Jacobian callback): contact blocks, element blocks, unit rows of held DOFs."""
        logging.stage(logging.ASSEMBLY).push()
        try:
            P.zeroEntries()
            xl = self._contact_jacobian(snes, X, P) if self.contact is not None \
                else self.exchange.local_state(X)
            logging.event(logging.ELEMENTS).begin()
            for blk in self.blocks:
                qe = blk.element_vectors(xl)
                t0 = time.perf_counter()
                K = sum(kernels.internal_force_and_tangent(qe, G, w, material)[1]
                        for G, w, material in blk.parts)
                t1 = time.perf_counter()
                insert_node_blocks(P, blk.rows, K)
                self.timers["element_kernels"] += t1 - t0
                self.timers["element_assembly"] += time.perf_counter() - t1
            logging.event(logging.ELEMENTS).end()
            d = (self.owned_fixed_local + DOFS_PER_NODE * self.layout.owned_nodes[0]).astype(PETSc.IntType)
            if len(d):
                P.setValuesRCV(d[:, None], d[:, None], np.ones((len(d), 1, 1)), ADD)
            P.assemble()
            if J.handle != P.handle:
                J.assemble()
        finally:
            logging.stage(logging.ASSEMBLY).pop()

    def _contact_jacobian(self, snes, X: PETSc.Vec, P: PETSc.Mat) -> np.ndarray:
        """Contact blocks into P, first: the exchange may grow the local array, and the blocks
        are only added once no rank had to exchange again.  Returns the local state."""
        with self._contact_timer():
            blocks = []

            def contact_blocks(xl):
                blocks[:] = self.contact.jacobian_blocks(xl, self.exchange.needed, self.fixed_mask)
                return xl
            xl = self.exchange.evaluate(X, contact_blocks)
            if self.pattern.grow(self.J):
                if P.handle != self.J.handle:
                    raise RuntimeError("the contact pattern grew on a preconditioner matrix "
                                       "this Problem did not create")
                if snes is not None and self.matrix_type == "sbaij":
                    # re-preallocating an SBAIJ matrix does not mark its pattern as new, so
                    # the factorisation would reuse the old symbolic analysis: start afresh
                    snes.getKSP().getPC().reset()
            for rows, values in blocks:
                insert_node_blocks(P, rows, values)
        return xl

    def objective(self, snes, X: PETSc.Vec) -> float:
        """Total potential Π = Σ ∫Ψ dV + Π_con − λ f_ext·q (the residual is its gradient).

        Used by the line searches (bt, l2) as merit function instead of ‖F‖²; +inf when an
        element is inverted.  Collective: every rank returns the same value.  Not defined with
        contact: the residual is then the gradient of a Lagrangian, whose stationary point is a
        saddle (``has_potential``).
        """
        if not self.has_potential:
            raise RuntimeError("no potential with contact multipliers; use the residual merit")
        logging.stage(logging.ASSEMBLY).push()
        try:
            def local_energy(xl):
                local = 0.0
                for blk in self.blocks:
                    qe = blk.element_vectors(xl)
                    local += sum(float(np.sum(kernels.energy(qe, G, w, material)))
                                 for G, w, material in blk.parts)
                return local
            local = self.exchange.evaluate(X, local_energy)
            total = self.comm.tompi4py().allreduce(local)
            total -= self.load_factor * self.fext.dot(X)
            return total if np.isfinite(total) else np.inf
        finally:
            logging.stage(logging.ASSEMBLY).pop()

    def min_jacobian(self, X: PETSc.Vec) -> float:
        """Smallest det F over every Gauss point of every rank (collective)."""
        xl = self.exchange.local_state(X)
        local = np.inf
        for blk in self.blocks:
            F = kernels.deformation_gradient(blk.element_vectors(xl), blk.G)
            local = min(local, float(np.min(np.linalg.det(F))))
        val = self.comm.tompi4py().allreduce(local, op=MPI.MIN)
        return val if np.isfinite(val) else -np.inf

    def precheck(self, X: PETSc.Vec, Y: PETSc.Vec, j_min: float = 0.1, halvings: int = 12) -> bool:
        """Line-search pre-check (collective).  A Newton step that moves a node by more than
        ``step_sections`` section sizes is scaled down to that first (a near-singular tangent
        gives absurd steps); then the step X − Y is halved until no Gauss point has det F below
        ``j_min``.  If that fails, Y is filled with NaN so that SNES reports a domain failure and
        the load step is cut back.  Returns whether Y was changed."""
        comm = self.comm.tompi4py()
        size = min(np.sqrt(b.section.area) for b in self.model.beams)
        y = Y.getArray(readonly=True).reshape(-1, 6, 3)[self.owned_physical]
        big = comm.allreduce(float(np.abs(y[:, 0]).max(initial=0.0)), op=MPI.MAX) / (self.step_sections * size)
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

    # ------------------------------------------------------------------ state
    @property
    def has_potential(self) -> bool:
        """Whether the residual is the gradient of a potential (no contact multipliers)."""
        return self.contact is None

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
            out = full.getArray()[:].reshape(-1, DOFS_PER_NODE)[self.layout.perm].reshape(-1, 6, 3)
            out = out if blocks else out[:self.model.n_nodes]
        scat.destroy()
        full.destroy()
        return out

    def destroy(self) -> None:
        """Free the PETSc objects of this problem (vectors, matrix, scatter); not collective."""
        self.exchange.destroy()
        for obj in (self.X, self.F, self.q0, self.fext, self.J):
            obj.destroy()
