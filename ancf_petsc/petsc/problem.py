"""Residual F(q, z; λ) = f_int(q) + f_con(q, z) − f_ext(λ) (and the contact constraint rows) and
its Jacobian in PETSc Vec / Mat: the callbacks SNES calls.

Each rank evaluates the element kernels of its own elements on a local copy of exactly the node
blocks they need (``exchange.GhostExchange``), adds the element forces back with the reverse
scatter, and inserts element matrices with one batched call per beam (``blocks``) into a matrix
preallocated with the exact node-block pattern (``pattern``).  DOFs held by boundary conditions
get the residual q − q̄(λ) and a unit row/column.  The loads and the prescribed displacements
follow the load factor in groups (model/loading.py): f_ext(λ) = Σ_g m_g(λ) f_g and
q̄(λ) = q̄₀ + Σ_g m_g(λ) ū_g, m_g(λ) = λ or a load curve (displacement control, preloads,
unloading); a support's reaction is the internal and contact force at its held DOFs.  The
contact multipliers z are extra node blocks after the beams' nodes (``Layout.n_blocks``); their
unused slots are held at zero like supported DOFs.
"""
from __future__ import annotations

import contextlib
import time

import numpy as np
from petsc4py import PETSc

from ..contact import pending_status
from ..model.beams import Model
from ..parallel.layout import Layout
from ..physics import kernels
from ..linalg import logging
from .aij_blocks import blocks_into, jacobian_matrix
from .blocks import ADD, INSERT, check_matrix_type, element_blocks
from .exchange import GhostExchange
from .loading import AppliedLoads, every_block, held_dofs
from .mixed_tangent import MixedTangent
from .pattern import JacobianPattern
from .potential import set_near_null_space, total_potential
from .reactions import support_rows
from .step_limits import StepLimits


class Problem:
    """PETSc residual/Jacobian of a model on a layout; ``load_factor`` scales the external loads."""

    def __init__(self, model: Model, layout: Layout, comm=None, contact=None, matrix_type: str = "aij"):
        comm = PETSc.COMM_WORLD if comm is None else comm
        check_matrix_type(model, matrix_type)
        if contact is not None and layout.n_blocks != model.n_nodes + contact.space.n_nodes:
            raise ValueError("the layout has no blocks for the contact multipliers; make it with "
                             "parallel.partition.make_layout(..., contact)")
        self.matrix_type = matrix_type
        self.model, self.layout, self.comm, self.contact = model, layout, comm, contact
        self._load_factor = 0.0
        self.timers = {"element_kernels": 0.0, "element_assembly": 0.0, "contact_projection": 0.0,
                       "contact_assembly": 0.0}
        self.residual_evaluations = 0           # F(X) callbacks of the run (summary.json)
        self.inverted = False                   # the last residual met det F <= 0
        self.contact_failed = False             # the last residual's contact projection failed
        lo, hi = layout.owned_nodes
        self.n_blocks = layout.n_blocks
        D = layout.dofs_per_node = model.dofs_per_node      # the model's node block
        N = D * self.n_blocks
        # held DOFs (supports, unused multiplier slots): a mask of every DOF, the owned ones
        self.fixed_mask, self.owned_fixed_local = held_dofs(model, layout, contact)
        self.blocks = element_blocks(model, layout, self.fixed_mask)
        self.X = PETSc.Vec().createMPI((D * (hi - lo), N), bsize=D, comm=comm)
        self.F = self.X.duplicate()
        q0_model, forces, moved = every_block(model, N)
        self.owned_physical = np.argsort(layout.perm)[lo:hi] < model.n_nodes   # beam nodes, not z
        self.n_constraints = 0 if contact is None else contact.n_multipliers
        if contact is not None:
            contact.timers = self.timers
            contact.set_layout(layout)
        self.exchange = GhostExchange(self.X, layout, self.fixed_mask, q0_model, self.blocks, contact,
                                      list(moved))
        if contact is not None and comm.size > 1:
            # a multiplier's function may live on elements of two ranks: its weighted gap (and
            # the law's decision) needs both ranks' points
            contact.sum_over_ranks = self.exchange.sum_over_ranks
            contact.all_ranks = self.exchange.all_ranks
            contact.reduce = self.exchange.reduce
        self.q0 = self.global_vector(q0_model)
        self.loads = AppliedLoads(model.loading, [self.global_vector(f) for f in forces],
                                  [self.global_vector(m) for m in moved], self.q0)
        self.support_rows = support_rows(model, layout)     # reactions.py
        self.limits = StepLimits(self)                     # the line-search pre-check
        self.mixed: MixedTangent | None = None             # solver.tangent: mixed (mixed_tangent.py)
        self.pattern = JacobianPattern(model, layout, self.fixed_mask, contact, comm, matrix_type)
        #: the Jacobian, and the collector of its blocks where it is one-rank AIJ (aij_blocks.py)
        self.J, self.aij_blocks = jacobian_matrix(self.pattern)
        set_near_null_space(self)

    def global_vector(self, arr_model: np.ndarray) -> PETSc.Vec:
        """Global Vec from a model-numbered array of every block (every rank holds it all)."""
        v = self.X.duplicate()
        lo, hi = self.layout.owned_nodes
        inv = np.argsort(self.layout.perm)[lo:hi]          # PETSc node → model node
        v.setArray(arr_model.reshape(-1, self.model.dofs_per_node)[inv].ravel())
        return v

    @property
    def load_factor(self) -> float:
        """λ: the external loads and the prescribed displacements are scaled by it."""
        return self._load_factor

    @load_factor.setter
    def load_factor(self, value: float) -> None:
        self._load_factor = float(value)
        self.exchange.multipliers = self.loads.multipliers(self._load_factor)

    @property
    def pattern_growths(self) -> int:
        return self.pattern.growths

    # ------------------------------------------------------------------ SNES callbacks
    def residual(self, snes, X: PETSc.Vec, F: PETSc.Vec) -> None:
        """F(X) (SNES function callback)."""
        self.residual_evaluations += 1
        logging.stage(logging.ASSEMBLY).push()
        try:
            floc, bad = self.exchange.evaluate(X, self._local_residual)
            self._finish_residual(X, F, floc, bad or self.contact_failed)
        finally:
            logging.stage(logging.ASSEMBLY).pop()

    def local_forces(self, X: PETSc.Vec) -> np.ndarray:
        """The internal and contact forces of this rank at X, in its local order (collective)."""
        logging.stage(logging.ASSEMBLY).push()
        try:
            return self.exchange.evaluate(X, self._local_residual)[0]
        finally:
            logging.stage(logging.ASSEMBLY).pop()

    def _local_residual(self, xl: np.ndarray) -> tuple[np.ndarray, bool]:
        """Internal (eq. 9) and contact forces of this rank's elements and points, local order."""
        floc = np.zeros(self.exchange.xloc.getLocalSize())
        bad = False
        logging.event(logging.ELEMENTS).begin()
        t0 = time.perf_counter()
        # a trial iterate may overflow (a fibre's e^(k2 Ē²)): its residual is not finite, which
        # _finish_residual turns into the NaN the line search backs off from; no warning needed
        with np.errstate(over="ignore", invalid="ignore"):
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
        self.loads.subtract(F, self._load_factor)
        fa = F.getArray()
        if len(self.owned_fixed_local):
            fa[self.owned_fixed_local] = (X.getArray(readonly=True)[self.owned_fixed_local]
                                          - self.loads.held_values(self._load_factor)[self.owned_fixed_local])
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
            into = blocks_into(self.aij_blocks, P)
            xl = self._contact_jacobian(snes, X, P, into) if self.contact is not None \
                else self.exchange.local_state(X)
            add_element_blocks(self, xl, into)
            d = (self.owned_fixed_local + self.model.dofs_per_node * self.layout.owned_nodes[0]).astype(PETSc.IntType)
            if len(d):
                P.setValuesRCV(d[:, None], d[:, None], np.ones((len(d), 1, 1)), ADD)
            P.assemble()
            if J.handle != P.handle:
                J.assemble()
        finally:
            logging.stage(logging.ASSEMBLY).pop()

    def _contact_jacobian(self, snes, X: PETSc.Vec, P: PETSc.Mat, into) -> np.ndarray:
        """Contact blocks into P (``into``: aij_blocks.py), first: the exchange may grow the local
        array, and the blocks are only added once no rank had to exchange again.  Returns the
        local state."""
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
                if self.aij_blocks is not None:
                    self.aij_blocks.reset()
            for block in blocks:
                into.add(*block)
        return xl

    def objective(self, snes, X: PETSc.Vec) -> float:
        """The total potential (``potential.total_potential``), the line searches' merit."""
        return total_potential(self, X)

    def impose(self, X: PETSc.Vec) -> None:
        """Put the held DOFs of X at q̄(λ) (the start of a load increment)."""
        if len(self.owned_fixed_local):
            x = X.getArray()
            x[self.owned_fixed_local] = self.loads.held_values(self._load_factor)[self.owned_fixed_local]
            del x

    # ------------------------------------------------------------------ state
    @property
    def symmetric(self) -> bool:
        """Whether the Jacobian is symmetric (not with an interface's Coulomb friction)."""
        return self.contact is None or self.contact.symmetric

    @property
    def solver_defaults(self) -> dict:
        """PETSc option defaults the model's laws ask for (below the config and command line)."""
        return {} if self.contact is None else self.contact.solver_defaults

    @property
    def has_potential(self) -> bool:
        """Whether the residual is the gradient of a potential (no contact multipliers)."""
        return self.contact is None

    def state_is_clean(self) -> bool:
        """After SNES converged: is the last residual's state an answer? (``unclean``; collective)"""
        return unclean(self) is None

    def checkpoint(self) -> None:
        """Called at every converged state: history the residual depends on (contact projections)."""
        if self.contact is not None:
            self.contact.checkpoint()

    def restore(self) -> None:
        """Back to the last checkpoint after a failed attempt."""
        if self.contact is not None:
            self.contact.restore()

    def gather(self, X: PETSc.Vec | None = None, blocks: bool = False) -> np.ndarray | None:
        """Beam nodal vectors in model order (n_nodes, V, 3) on rank 0 (None elsewhere; V vectors
        per node); with ``blocks`` every block, multiplier blocks after the nodes (n_blocks, V, 3)."""
        X = self.X if X is None else X
        scat, full = PETSc.Scatter.toZero(X)
        scat.scatter(X, full, INSERT, PETSc.ScatterMode.FORWARD)
        out = None
        if self.comm.rank == 0:
            D = self.model.dofs_per_node
            out = full.getArray()[:].reshape(-1, D)[self.layout.perm].reshape(-1, D // 3, 3)
            out = out if blocks else out[:self.model.n_nodes]
        scat.destroy()
        full.destroy()
        return out

    def destroy(self) -> None:
        """Free the PETSc objects of this problem (vectors, matrix, scatter); not collective."""
        self.exchange.destroy()
        self.loads.destroy()
        for obj in (self.X, self.F, self.q0, self.J):
            obj.destroy()


def add_element_blocks(problem: Problem, xl: np.ndarray, into) -> None:
    """The element tangents at the local state ``xl`` into the Jacobian (``into``: after the
    contact's blocks), then every held-back block (aij_blocks.py), timed."""
    logging.event(logging.ELEMENTS).begin()
    timers = problem.timers
    for n, blk in enumerate(problem.blocks):
        qe = blk.element_vectors(xl)
        t0 = time.perf_counter()
        K = sum(kernels.internal_force_and_tangent(qe, G, w, material)[1] for G, w, material in blk.parts)
        if problem.mixed is not None:
            K = problem.mixed.correct(n, qe, blk.parts, K)
        t1 = time.perf_counter()
        into.add(blk.rows, K, nodes=blk.node_ids)
        timers["element_kernels"] += t1 - t0
        timers["element_assembly"] += time.perf_counter() - t1
    t1 = time.perf_counter()
    into.flush()                                        # mostly the contact's entries
    timers["contact_assembly" if problem.contact is not None else "element_assembly"] += time.perf_counter() - t1
    logging.event(logging.ELEMENTS).end()


def unclean(problem: Problem) -> str | None:
    """After SNES converged, what keeps the last residual's state from being an answer:
    "projection" (a contact projection did not converge), "conditions" (a unilateral status the
    exact rule would change there: contact.pending_status) or None.  Collective."""
    c = problem.contact
    flags = [c is not None and not c.converged(), c is not None and bool(np.any(pending_status(c)))]
    flags = problem.comm.tompi4py().allreduce(np.array(flags, dtype=int))
    return "projection" if flags[0] else ("conditions" if flags[1] else None)
