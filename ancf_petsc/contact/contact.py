"""Frictionless surface-to-surface contact with Lagrange multipliers (paper §5, eqs. 26–29).

The contact term of the virtual work (eq. 12) is −Σ_k z_k δc_k with c_k = k_s ḡ_k the scaled
weighted gaps and z_k the scaled multipliers (multipliers.py); the contact law (laws.py) says
which constraints are active.  Further *terms* (``terms``: the interface shear of a tangential
law, shear.py) add their own forces, Jacobian blocks, couplings, history and reported fields
through one protocol, so that a new term needs no change here.  The residual rows are

    q:  f_int − f_ext − Σ_p τ_p ∇g_p,   τ_p = k_s Σ_k z_k Φ_kp  (= w_p × contact pressure)
    z:  −c_k (active)  or  −k_s z_k (inactive)

and the Jacobian is the symmetric saddle-point matrix [[K − Σ τ ∇²g, −∇cᵀ], [−∇c, 0]] that
MUMPS LDLᵀ factors as it is (unsymmetric, LU, with friction or with the fade weights
differentiated: ``contact.fade: newton``, weights.py).  No penalty: the answer does not depend on k_s.

``Contact`` works on a rank's local array of node blocks (PETSc numbering, see ``set_layout``);
it never touches PETSc objects: it adds to local force arrays and returns dense blocks with their
DOF indices for the assembly layer to insert.
"""
from __future__ import annotations

import functools
import time

import numpy as np

from . import blocks, couplings, reports
from .interfaces import find_interfaces, held_ends, supported_ends
from .laws import Phase, active_set_rows, make_law, violated
from .multipliers import build_space, reference_stiffness, with_tangential
from .points import build_points, check_points_across
from .projection import Projector
from .reference_gaps import check_reference_gaps
from .tangential import make_terms
from .state import ContactState
from .weights import WEIGHT_TOL, PointWeights


class Contact:
    """Contact points, their projections, the multiplier space and the law of all interfaces."""

    def __init__(self, model, spec, interfaces):
        self.model, self.spec, self.interfaces = model, spec, interfaces
        self.law = make_law(spec.mode)
        check_points_across(interfaces, spec.curve_points, spec.projection[1] + spec.curve_spans)
        self.points = build_points(model, interfaces, spec.axial_points, spec.curve_points)
        self.projector = Projector(model, interfaces, self.points, spec.search_margin)
        #: contact terms beside the normal constraints (a tangential law's interface shear)
        self.terms = make_terms(model, spec.tangential, interfaces, self.points, self.projector, spec.scaling)
        self.space = with_tangential(build_space(
            self.points, interfaces, spec.projection, reference_stiffness(interfaces) * spec.scaling,
            spec.per_element, spec.group, supported_ends(model, interfaces, spec.supported_ends), spec.curve_spans),
            any(t.multipliers for t in self.terms), held_ends(model, interfaces, spec.tangential))
        self.timers: dict | None = None
        self.seg_mnodes = self.space.segment_nodes()
        #: set by a parallel assembly (collective): ``sum_over_ranks(values over self.mults)``
        #: (whole weighted gaps), ``all_ranks(flag)``, ``reduce(values, 'max' | 'min' | 'sum')``
        self.sum_over_ranks = self.all_ranks = None
        self.reduce = lambda values, op: values
        #: status changes of the multipliers this rank evaluates, counted over the run
        self.status_changes = 0
        #: the law may change the status at the next evaluation: set by each Jacobian, so that a
        #: line search's trial points compare one residual function (basic: every iterate decides)
        self.allow_update = True
        #: the unilateral law's tolerance [m]: a smaller penetration or pull (z) changes no status
        self.tie_tolerance = 1e-9 * min(np.sqrt(b.section.area) for b in model.beams)
        self.status = np.zeros(self.space.n_multipliers, dtype=bool)     # active set (unilateral)
        self._saved_status = self.status.copy()
        #: the points' weights past B's ends (weights.py; ``contact.fade: newton`` differentiates them)
        self.weights = PointWeights(self.points.n_points, spec.fade, spec.fade_forces != "pointwise")
        # the rank's numbering (``set_numbering``): PETSc blocks, local pieces, reported ones, Φ of them
        empty = np.zeros(0, dtype=np.int64)
        self.conn = self.mult_block = self.seg_blocks = self.segments = self.local = self.mults = empty
        self.owned, self.Phi, self.PhiT, self._cache, self.block_layouts = np.zeros(0, dtype=bool), None, None, None, None
        n_blocks = model.n_nodes + self.space.n_nodes
        self.set_numbering(np.arange(n_blocks), np.ones(self.points.n_segments, dtype=bool))
        check_reference_gaps(self)

    # ---------------------------------------------------------------- numbering and layout
    @property
    def stiffness(self) -> float:
        return self.space.stiffness

    @property
    def n_multipliers(self) -> int:
        return self.space.n_multipliers

    def padding_dofs(self) -> np.ndarray:
        """Model-numbered DOF ids of the unused multiplier slots (held at zero)."""
        node, slot = np.nonzero(self.space.padding())
        return self.model.dofs_per_node * (self.model.n_nodes + node) + slot

    def multiplier_dofs(self) -> np.ndarray:
        """Model-numbered DOF id of every multiplier (M,)."""
        return self.model.dofs_per_node * (self.model.n_nodes + self.space.node) + self.space.slot

    def set_numbering(self, perm: np.ndarray, local_segments: np.ndarray,
                      owned_elements: np.ndarray | None = None) -> None:
        """Block numbering ``perm`` (model block → PETSc block, multiplier nodes after the physical
        ones), the segments this rank evaluates and the elements whose multipliers it reports."""
        pts, sp = self.points, self.space
        self.conn = perm[self.model.connectivity()]
        self.projector.conn = self.conn
        self.mult_block = perm[self.model.n_nodes + sp.node]           # (M,) PETSc block
        self.seg_blocks = np.where(self.seg_mnodes >= 0,
                                   perm[self.model.n_nodes + np.maximum(self.seg_mnodes, 0)], -1)
        self.segments = np.flatnonzero(local_segments)
        self.local = (np.concatenate([pts.seg_start[s] + np.arange(pts.seg_size[s]) for s in self.segments])
                      if len(self.segments) else np.zeros(0, dtype=np.int64))
        m = sp.seg_mults[self.segments].ravel()
        self.mults = np.unique(m[m >= 0])          # multipliers living on the local segments
        self.owned = (np.ones(len(self.mults), dtype=bool) if owned_elements is None
                      else owned_elements[sp.element[self.mults]])
        self.Phi = sp.Phi[self.mults][:, self.local].tocsr()
        self.PhiT = self.Phi.T.tocsr()       # Φᵀ's products summed as Phi.T's, without its CSC copy
        for term in self.terms:
            term.set_numbering(self, perm)
        self._cache = self.block_layouts = None       # (contact/segment_layout.py)

    def set_layout(self, layout) -> None:
        """This rank's segments (those of its A elements) in the layout's numbering."""
        mine = layout.elem_owner == layout.rank
        self.set_numbering(layout.perm, mine[self.points.seg_eA], mine)

    def multiplier_positions(self, needed: np.ndarray) -> np.ndarray:
        """Positions of the local multipliers (``mults``) in a local DOF array over ``needed``."""
        return self.model.dofs_per_node * np.searchsorted(needed, self.mult_block[self.mults]) + self.space.slot[self.mults]

    def required_nodes(self) -> np.ndarray:
        """Node blocks (PETSc) read locally: A, B (now and at the checkpoint), neighbouring and
        wanted elements', multipliers'."""
        els = np.concatenate([self.points.eA[self.local], self.projector.eB[self.local], self.projector.wanted,
                              self.projector.neighbours(self.local), self.projector.saved_places(self.local)[0]]
                             + [t.required_elements(self) for t in self.terms])
        return np.unique(np.concatenate([self.conn[els[els >= 0]].ravel(), self.mult_block[self.mults]]
                                        + [t.required_blocks(self) for t in self.terms]))

    def set_available(self, needed: np.ndarray) -> None:
        """Record which elements have every node block in the rank's local array ``needed``."""
        self.projector.set_available(np.all(np.isin(self.conn, needed), axis=1))
        self._cache = None

    @property
    def missing(self) -> bool:
        """A projection wanted an element whose nodes this rank does not hold."""
        return self.projector.missing

    def projected_elements(self) -> np.ndarray:
        """The B element each local point projects onto now (what ``node_couplings`` follows)."""
        return self.projector.eB[self.local].copy()

    def node_couplings(self) -> tuple[np.ndarray, np.ndarray]:
        """Node-block couplings of the local segments now (``couplings.node_couplings``)."""
        return couplings.node_couplings(self)

    def coupling_graph(self) -> couplings.ContactGraph:
        """The element pairs the contact couples and its work per element (for partitions)."""
        return couplings.coupling_graph(self)

    # ---------------------------------------------------------------- evaluation
    def evaluate(self, xl: np.ndarray, needed: np.ndarray) -> ContactState:
        """Project the local points at the local state ``xl`` (n, V, 3) and apply the law.

        SNES evaluates the Jacobian at the state of the residual before it: that evaluation is
        reused.  With the parallel hooks set (``sum_over_ranks``) every rank calls it."""
        c = kept_evaluation(self, xl, needed, not (self.allow_update and self.law.decides_activity))
        if c is not None:
            return c
        t0 = time.perf_counter()

        lpos = functools.partial(np.searchsorted, needed)       # PETSc node id → local position

        def x_of(els):
            return xl[lpos(self.conn[els])].reshape(len(els), self.model.block.slots, 3)

        idx = self.local
        xA = np.einsum("pa,pai->pi", self.points.NA[idx], x_of(self.points.eA[idx]))
        pr = self.projector.project(idx, xA, x_of)
        weight = self.weights.effective(idx, pr.weight)
        sums = np.stack([self.Phi @ (pr.g * weight), self.Phi @ weight], axis=1)
        if self.sum_over_ranks is not None:          # functions shared with another rank
            sums = self.sum_over_ranks(sums)
        gbar = sums[:, 0]
        support = sums[:, 1] > 1e-9                  # Φ's rows sum to one
        z = xl.reshape(-1)[self.model.dofs_per_node * lpos(self.mult_block[self.mults]) + self.space.slot[self.mults]]
        active = decide_status(self, gbar, z, support)
        rows = active_set_rows(gbar, z, active, self.law.phase.probe)
        pressure = self.stiffness * (self.PhiT @ (z * rows.load))
        st = ContactState(pr=pr, xA=xA, gbar=gbar, z=z, active=active, tau=pressure * weight,
                          pressure=pressure, lpos=lpos, rows=rows, weight=weight, xl=xl.copy(),
                          support=support)
        st.terms = {t.name: t.evaluate(self, st, x_of) for t in self.terms}
        self._cache = None if self.missing else (st.xl, needed, st)
        if self.timers is not None:
            self.timers["contact_projection"] += time.perf_counter() - t0
        return st

    @property
    def last_evaluation(self) -> ContactState | None:
        """The evaluation the next residual or Jacobian at its state would reuse (or None)."""
        return None if self._cache is None else self._cache[2]

    def add_residual(self, xl: np.ndarray, needed: np.ndarray, floc: np.ndarray) -> bool:
        """Add the contact forces and the constraint rows to the local residual ``floc``;
        False when a point slid out of its search window."""
        st = self.evaluate(xl, needed)
        blocks.add_normal_forces(self, st, floc)
        for term in self.terms:
            term.add_forces(self, st, floc)
        return bool(st.pr.in_window)

    def jacobian_blocks(self, xl: np.ndarray, needed: np.ndarray,
                        fixed_mask: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """The contact blocks of the Jacobian at the local state (``blocks.jacobian_blocks``
        and each term's)."""
        st = self.evaluate(xl, needed)
        return blocks.jacobian_blocks(self, st, fixed_mask) + [
            b for t in self.terms for b in t.jacobian_blocks(self, st, fixed_mask)]

    @property
    def symmetric(self) -> bool:
        """Whether the Jacobian is symmetric (the weights' forces and every term's law are)."""
        return self.weights.symmetric and all(t.symmetric for t in self.terms)

    @property
    def solver_defaults(self) -> dict:
        """PETSc option defaults the normal law and (over it) the terms' laws ask for."""
        return dict(self.law.options) | {k: v for t in self.terms for k, v in t.options.items()}

    # ---------------------------------------------------------------- checks
    def begin_phase(self, phase: Phase, previous: Phase | None = None) -> None:
        """Start a phase of a Newton solve (laws.Phase); after a phase that held every
        constraint, the status follows the multipliers' signs (a pull releases)."""
        if previous is not None and previous.hold and self._cache is not None:
            st = self._cache[2]
            self.status[self.mults] = st.z > self.tie_tolerance
        self.law.begin(phase)
        self._cache = None
        self.allow_update = True

    def converged(self) -> bool:
        """Whether the last evaluation's projections all converged (this rank)."""
        return self._cache is not None and self._cache[2].pr.converged

    def restore_state(self, projection: np.ndarray | None, status: np.ndarray | None,
                      fields: dict | None = None) -> None:
        """A restart's projection state (points, 3), multiplier status (multipliers,) and the
        terms' state (``fields``: the written level's contact fields, every point)."""
        if projection is not None:
            self.projector.set_state(projection)
            self.weights.set(self.projector.weights_of_state())
        if status is not None:
            self.status = np.asarray(status, dtype=bool).copy()
        for term in self.terms:
            term.set_state(fields)
        self._cache = None
        self.checkpoint()

    def checkpoint(self) -> None:
        """A converged state: the terms keep their history (from the last evaluation, the
        converged state's), then every state is saved for a cut-back."""
        if self._cache is not None:
            for term in self.terms:
                term.accept(self, self._cache[2])
        self._saved_status = self.status.copy()
        for part in [self.projector, self.weights] + self.terms:
            part.checkpoint()

    def restore(self) -> None:
        self._cache = None
        self.status = self._saved_status.copy()
        for part in [self.projector, self.weights] + self.terms:
            part.restore()

    def refresh_weights(self) -> bool:
        """After a converged solve: the weights brought up to the last evaluation; True (solve again,
        collective) if one changed by > WEIGHT_TOL (settle) or a projection did not converge (descent.py)."""
        st = self._cache[2] if self._cache is not None else None
        change = 0.0 if st is None else self.weights.refresh(st.pr.idx, st.pr.weight)
        lost = float(st is not None and not st.pr.converged and not self.projector.metric_steps)
        change, lost = self.reduce(np.array([change, lost]), "max")
        self.weights.differentiated |= bool(change > WEIGHT_TOL and self.weights.rule == "newton")  # all ranks
        self.projector.metric_steps |= bool(lost)
        self._cache = None if change > WEIGHT_TOL or lost else self._cache     # the residual changed
        return bool(change > WEIGHT_TOL or lost)


def kept_evaluation(contact: Contact, xl: np.ndarray, needed: np.ndarray, usable: bool = True):
    """The kept evaluation (``ContactState``) if it is of the local state ``xl`` over ``needed``
    and ``usable`` on every rank, else None (collective with the parallel hooks set)."""
    c = contact._cache
    hit = usable and c is not None and c[1] is needed and np.array_equal(c[0], xl)
    if contact.all_ranks is not None:
        hit = contact.all_ranks(hit)
    return c[2] if hit else None


def decide_kept(contact: Contact, xl: np.ndarray, needed: np.ndarray) -> bool:
    """Whether the law's rule keeps the status at the kept evaluation, if that is of the
    local state ``xl`` (a converged solve's last residual was evaluated at its state): then
    that evaluation is what one there with ``allow_update`` makes, and no projection is
    made again.  False, the status as it was, without one or where the rule changes it (the
    caller evaluates: its forces, and the fade weights the next solve starts from, are the
    new status').  Collective with the parallel hooks set."""
    st = kept_evaluation(contact, xl, needed)
    if st is None:
        return False
    status, changes, memory = contact.status.copy(), contact.status_changes, contact.law.memory()
    contact.allow_update = True
    decide_status(contact, st.gbar, st.z, st.support)
    kept = contact.status_changes == changes
    if contact.all_ranks is not None:
        kept = contact.all_ranks(kept)
    if not kept:
        contact.status[:], contact.status_changes = status, changes
        contact.law.recall(memory)
    return kept


def decide_status(contact: Contact, gbar: np.ndarray, z: np.ndarray, support: np.ndarray) -> np.ndarray:
    """The status of the local multipliers in an evaluation: the law's (where it may change it),
    else the kept one.  An evaluation in which some rank's projection reached an element that
    rank does not hold is repeated after the exchange (petsc/exchange.py): it neither decides
    nor records a status, so that the law sees the gaps one rank would (collective with the
    parallel hooks set)."""
    prev = contact.status[contact.mults]
    complete = contact.all_ranks is None or contact.all_ranks(not contact.missing)
    if complete and (contact.allow_update or not contact.law.decides_activity):
        active = contact.law.update(gbar, z, prev, contact.tie_tolerance, contact.mults, contact.owned,
                                    contact.reduce) & support
        contact.allow_update = False
    else:
        active = prev & support
    if complete:
        contact.status_changes += int(np.count_nonzero(active != prev))
        contact.status[contact.mults] = active
    return active


def pending_status(contact: Contact) -> np.ndarray:
    """The local multipliers whose status the exact rule would change at the last evaluation's
    state: an active one pulling (z < −tie tolerance) or an inactive one penetrating (ḡ < −tie
    tolerance).  Where the evaluations may change the status, the last one applied the rule and
    none is pending; at a state solved with the status kept a converged residual says nothing of
    them (solving/newton.py ``_reweigh``: an accepted frame with multipliers pulling).  Empty
    without a law that decides activity or without a kept evaluation."""
    if not contact.law.decides_activity or contact._cache is None:
        return np.zeros(0, dtype=bool)
    st, tol = contact._cache[2], contact.tie_tolerance
    return violated(st.gbar, st.z, st.active, tol, tol)


def forget_evaluation(contact: Contact) -> None:
    """Drop the kept evaluation (projections, forces, blocks) of the last state: something the
    residual depends on changed outside the state (the weights' rule, a phase, a reweighing)."""
    contact._cache = None


def hold_bounds(contact: Contact, hold: bool = True) -> float:
    """Tresca's problem (solving/newton.py, "Friction's bounds"): every bounded term's bounds held
    at the last evaluation's (``hold``), or following the state again; the largest change of a
    held bound since the last hold relative to the largest, over the terms and the ranks (inf
    the first time; collective when holding)."""
    changes = [t.hold_bounds() if hold else t.release_bounds() for t in contact.terms if t.bounded]
    forget_evaluation(contact)                            # the residual changed
    if not hold:
        return 0.0
    return float(contact.reduce(np.array([max(changes, default=0.0)]), "max")[0])


def build_contact(model, spec, log=print) -> Contact:
    """Contact from the spec; prints the interfaces and the multiplier space."""
    contact = Contact(model, spec, find_interfaces(model, spec))
    for line in reports.describe(contact):
        log("[ancf]   " + line)
    return contact
