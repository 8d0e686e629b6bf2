"""Frictionless surface-to-surface contact with Lagrange multipliers (paper §5, eqs. 26–29).

The contact term of the virtual work (eq. 12) is −Σ_k z_k δc_k with c_k = k_s ḡ_k the scaled
weighted gaps and z_k the scaled multipliers (multipliers.py); the contact law (laws.py) says
which constraints are active.  The residual rows are

    q:  f_int − f_ext − Σ_p τ_p ∇g_p,   τ_p = k_s Σ_k z_k Φ_kp  (= w_p × contact pressure)
    z:  −c_k (active)  or  −k_s z_k (inactive)

and the Jacobian is the symmetric saddle-point matrix [[K − Σ τ ∇²g, −∇cᵀ], [−∇c, 0]] that
MUMPS LDLᵀ factors as it is.  No penalty: the answer does not depend on k_s.

``Contact`` works on a rank's local array of node blocks (PETSc numbering, see ``set_layout``);
it never touches PETSc objects: it adds to local force arrays and returns dense blocks with their
DOF indices for the assembly layer to insert.
"""
from __future__ import annotations

import time

import numpy as np

from ..physics.element3363 import DOFS_PER_NODE, SLOTS
from . import blocks, reports
from .interfaces import ContactSetupError, find_interfaces
from .laws import Phase, active_set_rows, make_law
from .multipliers import build_space
from .points import build_points
from .projection import Projector
from .state import ContactState
from .weights import WEIGHT_TOL, PointWeights


def reference_stiffness(interfaces) -> float:
    """k_s = E_min h [N/m]: E the small-strain Young's modulus of the softer beam, h = min(element
    length, √area).  It only scales the multiplier unknowns (the constraint rows then have the
    size of the stiffness rows); the answer does not depend on it."""
    best = np.inf
    for itf in interfaces:
        for beam in (itf.a, itf.b):
            mat = beam.material
            E = getattr(mat, "E", None)
            if E is None:
                E = 9.0 * mat.K * mat.mu / (3.0 * mat.K + mat.mu)
            h = min(beam.x_nodes[2] - beam.x_nodes[0], np.sqrt(beam.section.area))
            best = min(best, E * h)
    return float(best)


class Contact:
    """Contact points, their projections, the multiplier space and the law of all interfaces."""

    def __init__(self, model, spec, interfaces):
        self.model, self.spec, self.interfaces = model, spec, interfaces
        self.law = make_law(spec.mode)
        self.points = build_points(model, interfaces, spec.axial_points, spec.curve_points)
        self.space = build_space(self.points, interfaces, spec.projection,
                                 reference_stiffness(interfaces) * spec.scaling, spec.per_element)
        self.projector = Projector(model, interfaces, self.points, spec.search_margin)
        self.timers: dict | None = None
        # multiplier nodes of each segment's functions: its own A element's and the previous
        # element's (whose end function it shares), −1 where there is only one
        sm = self.space.seg_mults
        nodes = np.where(sm >= 0, self.space.node[np.maximum(sm, 0)], -1)
        first = nodes[:, 0]
        last = np.max(nodes, axis=1)
        self.seg_mnodes = np.stack([first, np.where(last != first, last, -1)], axis=1)
        #: set by a parallel assembly for laws that need whole weighted gaps (unilateral):
        #: ``sum_over_ranks(values over self.mults)`` and ``all_ranks(flag)`` (both collective)
        self.sum_over_ranks = None
        self.all_ranks = None
        #: ``reduce(values, 'max' | 'min')`` over the ranks (collective; set with the hooks above)
        self.reduce = lambda values, op: values
        #: status changes of the multipliers this rank evaluates, counted over the run
        self.status_changes = 0
        #: the law may change the status at the next evaluation: once per Newton iteration (set
        #: by each Jacobian), so that a line search's trial points (bt, l2, cp) compare one
        #: residual function; with the full step (basic) every iterate decides
        self.allow_update = True
        #: the unilateral law's tolerance [m]: a penetration or a pull (z) smaller than this does
        #: not change a constraint's status (rounding of positions in a touching reference)
        self.tie_tolerance = 1e-9 * min(np.sqrt(b.section.area) for b in model.beams)
        self.status = np.zeros(self.space.n_multipliers, dtype=bool)     # active set (unilateral)
        self._saved_status = self.status.copy()
        #: the points' weights when their partners slide past B's ends (weights.py)
        self.weights = PointWeights(self.points.n_points)
        self._cache = None
        # the rank's numbering (``set_numbering``): PETSc block of every element node, multiplier
        # and segment multiplier node; the local segments, points and multipliers, which of those
        # multipliers this rank reports, and Φ restricted to them
        empty = np.zeros(0, dtype=np.int64)
        self.conn, self.mult_block, self.seg_blocks = empty, empty, empty
        self.segments, self.local, self.mults = empty, empty, empty
        self.owned = np.zeros(0, dtype=bool)
        self.Phi = None
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
        return DOFS_PER_NODE * (self.model.n_nodes + node) + slot

    def multiplier_dofs(self) -> np.ndarray:
        """Model-numbered DOF id of every multiplier (M,)."""
        return DOFS_PER_NODE * (self.model.n_nodes + self.space.node) + self.space.slot

    def set_numbering(self, perm: np.ndarray, local_segments: np.ndarray,
                      owned_elements: np.ndarray | None = None) -> None:
        """Block numbering ``perm`` (model block id → PETSc block id, multiplier nodes after the
        physical ones), the segments this rank evaluates (bool per segment) and the elements it
        owns (bool per element; default all), whose multipliers it reports."""
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
        self._cache = None

    def set_layout(self, layout) -> None:
        """This rank's segments (those of its A elements) in the layout's numbering."""
        mine = layout.elem_owner == layout.rank
        self.set_numbering(layout.perm, mine[self.points.seg_eA], mine)

    def multiplier_positions(self, needed: np.ndarray) -> np.ndarray:
        """Positions of the local multipliers (``mults``) in a local DOF array over ``needed``."""
        return DOFS_PER_NODE * np.searchsorted(needed, self.mult_block[self.mults]) + self.space.slot[self.mults]

    def required_nodes(self) -> np.ndarray:
        """Node blocks (PETSc numbering) the local evaluation reads: the A and B elements of the
        local points, any B element a projection wanted but did not have, the multiplier nodes."""
        els = np.concatenate([self.points.eA[self.local], self.projector.eB[self.local],
                              self.projector.wanted])
        return np.unique(np.concatenate([self.conn[els].ravel(), self.mult_block[self.mults]]))

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
        """Node-block couplings (PETSc numbering) of the local segments now: per segment its A
        nodes, the nodes of every B element its points project onto and its multiplier node,
        all with all.  Couplings that sliding creates later are added when they first occur."""
        if len(self.local) == 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        seg = self.points.seg[self.local]
        seg_b = np.unique(np.stack([seg, self.projector.eB[self.local]], 1), axis=0)
        e_a = self.points.seg_eA[seg_b[:, 0]]
        group = np.concatenate([self.conn[e_a], self.conn[seg_b[:, 1]], self.seg_blocks[seg_b[:, 0]]],
                               axis=1)                                         # (pairs, 8), −1 unused
        a = np.repeat(group, 8, axis=1).ravel()
        b = np.tile(group, (1, 8)).ravel()
        ok = (a >= 0) & (b >= 0)
        rows, cols = [a[ok]], [b[ok]]
        # a segment on several B elements also couples those elements with each other
        first = np.searchsorted(seg_b[:, 0], seg_b[:, 0])
        for i in np.flatnonzero(first != np.arange(len(seg_b))):
            others = self.conn[seg_b[first[i]:i, 1]].ravel()
            mine = self.conn[seg_b[i, 1]]
            rows += [np.repeat(mine, len(others)), np.tile(others, 3)]
            cols += [np.tile(others, 3), np.repeat(mine, len(others))]
        return np.concatenate(rows), np.concatenate(cols)

    # ---------------------------------------------------------------- evaluation
    def evaluate(self, xl: np.ndarray, needed: np.ndarray) -> ContactState:
        """Project the local points at the local state ``xl`` (n, 6, 3) and apply the law.

        SNES evaluates the Jacobian at the state of the residual before it: that evaluation is
        reused (the projection state is its result, so nothing else changes).  With the
        parallel hooks set (``sum_over_ranks``) this is collective: every rank calls it."""
        c = self._cache
        hit = (c is not None and c[1] is needed and np.array_equal(c[0], xl)
               and not (self.allow_update and self.law.decides_activity))
        if self.all_ranks is not None:
            hit = self.all_ranks(hit)
        if hit:
            return c[2]
        t0 = time.perf_counter()

        def lpos(nodes):
            return np.searchsorted(needed, nodes)

        def x_of(els):
            return xl[lpos(self.conn[els])].reshape(len(els), SLOTS, 3)

        idx = self.local
        xA = np.einsum("pa,pai->pi", self.points.NA[idx], x_of(self.points.eA[idx]))
        pr = self.projector.project(idx, xA, x_of)
        weight = self.weights.effective(idx, pr.weight)
        sums = np.stack([self.Phi @ (pr.g * weight), self.Phi @ weight], axis=1)
        if self.sum_over_ranks is not None:          # functions shared with another rank
            sums = self.sum_over_ranks(sums)
        gbar = sums[:, 0]
        support = sums[:, 1] > 1e-9                  # Φ's rows sum to one
        z = xl.reshape(-1)[DOFS_PER_NODE * lpos(self.mult_block[self.mults]) + self.space.slot[self.mults]]
        prev = self.status[self.mults]
        if self.allow_update or not self.law.decides_activity:
            active = self.law.update(gbar, z, prev, self.tie_tolerance, self.mults, self.owned,
                                     self.reduce) & support
            self.allow_update = False
        else:
            active = prev & support
        self.status_changes += int(np.count_nonzero(active != prev))
        self.status[self.mults] = active
        rows = active_set_rows(gbar, z, active, self.law.phase.probe)
        tau = self.stiffness * (self.Phi.T @ (z * rows.load)) * weight
        st = ContactState(pr=pr, xA=xA, gbar=gbar, z=z, active=active, tau=tau, lpos=lpos,
                          rows=rows, weight=weight)
        self._cache = None if self.missing else (xl.copy(), needed, st)
        if self.timers is not None:
            self.timers["contact_projection"] += time.perf_counter() - t0
        return st

    def add_residual(self, xl: np.ndarray, needed: np.ndarray, floc: np.ndarray) -> bool:
        """Add the contact forces and the constraint rows to the local residual ``floc``;
        False when a point slid out of its search window."""
        st = self.evaluate(xl, needed)
        pr = st.pr
        traction = st.tau[:, None] * pr.n                                  # τ_p n_p
        for e, N, sign in ((self.points.eA[pr.idx], pr.NA, -1.0), (pr.eB, pr.NB, 1.0)):
            f = sign * N[:, :, None] * traction[:, None, :]                   # (P, 18, 3)
            pos = st.lpos(self.conn[e])                                       # (P, 3)
            dofs = (DOFS_PER_NODE * pos[:, :, None] + np.arange(DOFS_PER_NODE)).ravel()
            floc += np.bincount(dofs, f.reshape(-1), minlength=floc.size)
        # the constraint rows; a function shared with another rank: each adds its own points
        rows = DOFS_PER_NODE * st.lpos(self.mult_block[self.mults]) + self.space.slot[self.mults]
        share = self.Phi @ np.ones(len(pr.g)) if self.sum_over_ranks is not None else 1.0
        floc[rows] += self.stiffness * st.rows.R * share
        return bool(pr.in_window)

    def jacobian_blocks(self, xl: np.ndarray, needed: np.ndarray,
                        fixed_mask: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """The contact blocks of the Jacobian at the local state (``blocks.jacobian_blocks``)."""
        return blocks.jacobian_blocks(self, self.evaluate(xl, needed), fixed_mask)

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

    def restore_state(self, projection: np.ndarray | None, status: np.ndarray | None) -> None:
        """A restart's projection state (points, 3) and multiplier status (multipliers,)."""
        if projection is not None:
            self.projector.set_state(projection)
            self.weights.set(self.projector.weights_of_state())
        if status is not None:
            self.status = np.asarray(status, dtype=bool).copy()
        self._cache = None
        self.checkpoint()

    def checkpoint(self) -> None:
        self.projector.checkpoint()
        self._saved_status = self.status.copy()
        self.weights.checkpoint()

    def restore(self) -> None:
        self._cache = None
        self.projector.restore()
        self.status = self._saved_status.copy()
        self.weights.restore()

    def refresh_weights(self) -> bool:
        """After a converged solve: bring the points' weights up to their partners' places in
        the last evaluation; True (on every rank) when one changed by more than WEIGHT_TOL, so
        that the state must be solved again (collective)."""
        st = self._cache[2] if self._cache is not None else None
        change = 0.0 if st is None else self.weights.refresh(st.pr.idx, st.pr.weight)
        changed = bool(self.reduce(np.array([change]), "max")[0] > WEIGHT_TOL)
        if changed:
            self._cache = None                  # the residual at this state changed
        return changed

    # ---------------------------------------------------------------- reports
    def describe(self) -> list[str]:
        ka, kc = self.space.degrees
        lines = [f"contact: {self.law.describe()}; Lagrange multipliers (pressure of degree {ka} "
                 f"along the beam x {kc} across the interface per element, {self.n_multipliers} in "
                 f"all); {self.points.n_points} points ({self.spec.axial_points} axial x "
                 f"{self.spec.curve_points} per curve piece); unknowns scaled by k_s = "
                 f"{self.stiffness:.4g} N/m"]
        for itf in self.interfaces:
            lines.append(f"  interface {itf.name}: {itf.n_points} points on {itf.a.name}, "
                         f"projected onto {itf.b.name}")
        return lines

    def gap_sums(self, xl: np.ndarray, needed: np.ndarray) -> np.ndarray:
        """Per interface the local parts of ``reports.GAP_COLUMNS`` at the local state."""
        return reports.gap_sums(self, self.evaluate(xl, needed))

    def gap_report(self, sums: np.ndarray) -> dict:
        """Per-interface statistics from (rank-combined) ``gap_sums``."""
        return reports.gap_report(self.interfaces, sums)

    def point_fields(self, xl: np.ndarray, needed: np.ndarray, q0_of) -> dict:
        """Per local point and owned multiplier fields for the output (``reports.point_fields``)."""
        return reports.point_fields(self, self.evaluate(xl, needed), q0_of)


def check_reference_gaps(contact) -> None:
    """The reference configuration must be gap-free (sliding) or not penetrating
    (unilateral): evaluated with every point local, then the projection state is reset."""
    n_blocks = contact.model.n_nodes + contact.space.n_nodes
    xl = np.zeros((n_blocks, 6, 3))
    xl[:contact.model.n_nodes] = contact.model.q0
    st = contact.evaluate(xl, np.arange(n_blocks))
    size = max(np.sqrt(b.section.area) for b in contact.model.beams)
    g = st.pr.g[st.pr.valid]
    contact.restore()
    if contact.law.decides_activity:          # unilateral: touching or apart
        if not st.pr.in_window or np.min(g, initial=0.0) < -1e-9 * size:
            raise ContactSetupError("the bodies interpenetrate in the reference configuration "
                                f"(gap {np.min(g):.3e} m); separate them")
        return
    gap = np.linalg.norm(st.pr.d, axis=1)
    if not st.pr.in_window or gap.max() > 1e-9 * size:
        raise ContactSetupError(f"the interfaces do not match in the reference configuration "
                                f"(largest gap {gap.max():.3e} m); neighbours must share "
                                "their interface curve and element boundaries")


def build_contact(model, spec, log=print) -> Contact:
    """Contact from the spec; prints the interfaces and the multiplier space."""
    contact = Contact(model, spec, find_interfaces(model, spec))
    for line in contact.describe():
        log("[ancf]   " + line)
    return contact
