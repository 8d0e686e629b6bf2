"""Reference partners: what a tangential interface law (elastic matrix, friction) shares.

Every contact point p on A keeps its *reference partner* on B: the place Y_B(ζ₀) = N_B(ζ₀) q_B it
matched in the reference configuration (element e_B0, ξ₀, t₀ of the exactly touching
interface).  A law acts on the relative displacement of the two material points,

    d_p = x_A(p) − Y_B(ζ₀) = N_A q_A − N_B(ζ₀) q_B0,    ∇d = [N_A ⊗ I, −N_B(ζ₀) ⊗ I],

(linear in the nodal vectors of A's element and the partner's), with the points' weights
ω_p = w_p × weight (reference area, faded past B's ends).  ``PartnerTerm`` holds the partners,
the law's history (checkpointed with the converged increments, written for a restart), the
reported fields and statistics, and the block helpers; a law (elastic_interface.py,
friction.py) adds its forces and Jacobian blocks.  ``Contact.terms`` holds such terms.
"""
from __future__ import annotations

import numpy as np

from .multipliers import reference_modulus, reference_size
from .reports import output_signs

#: the prefix of a law's history in the point fields (results.h5 ``steps/…/contact``)
HISTORY = "history_"


def node_dofs(nodes: np.ndarray, D: int) -> np.ndarray:
    """DOF ids (n, D k) of node groups (n, k) of D DOFs each (Model.dofs_per_node), −1 for the
    unused (−1) nodes."""
    rows = (D * nodes[:, :, None] + np.arange(D)).reshape(len(nodes), -1)
    return np.where(np.repeat(nodes, D, axis=1) >= 0, rows, -1)


def drop_held(dofs: np.ndarray, fixed_mask: np.ndarray) -> np.ndarray:
    """DOF ids with the held ones (and −1) as −1 (dropped when inserted)."""
    out = dofs.copy()
    ok = out >= 0
    out[ok] = np.where(fixed_mask[out[ok]], -1, out[ok])
    return out


def tangential(d: np.ndarray, n: np.ndarray) -> np.ndarray:
    """The part of each d (P, 3) in the plane normal to n (P, 3)."""
    return d - np.einsum("pi,pi->p", d, n)[:, None] * n


def per_segment_sum(srow: np.ndarray, n_s: int, values: np.ndarray) -> np.ndarray:
    """Σ over each segment's points of ``values`` (P, ...) → (n_s, ...); the points are stored
    segment by segment (``srow`` non-decreasing)."""
    start = np.searchsorted(srow, np.arange(n_s))
    out = np.zeros((n_s,) + values.shape[1:])
    has = np.diff(np.append(start, len(srow))) > 0
    out[has] = np.add.reduceat(values, start[has], axis=0)
    return out


def _padded(group: np.ndarray, n: int, *arrays: np.ndarray) -> list[np.ndarray]:
    """Per group zero-padded copies (n, most points, ...) of per-point ``arrays``, each group's
    points in their order (``segment_outer``, ``pair_products``)."""
    count = np.bincount(group, minlength=n)
    order = np.argsort(group, kind="stable")
    slot = np.empty(len(group), dtype=np.int64)
    slot[order] = np.arange(len(group)) - np.repeat(np.cumsum(count) - count, count)
    out = []
    for a in arrays:
        padded = np.zeros((n, count.max(initial=1)) + a.shape[1:])
        padded[group, slot] = a
        out.append(padded)
    return out


def segment_outer(srow: np.ndarray, n_s: int, left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """Σ over each segment's points of left_p ⊗ right_p: (n_s, X, Y) from (P, X) and (P, Y), as
    one batched product over zero-padded segments."""
    L, R = _padded(srow, n_s, left, right)
    return np.matmul(L.transpose(0, 2, 1), R)


def pair_products(srow: np.ndarray, eB: np.ndarray, left: np.ndarray,
                  right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Σ of left_p @ right_p over the points of each (segment row, B element) pair: (pairs (n, 2)
    in lexicographic order, sums (n, R, C)) from left (P, R, I) and right (P, I, C), as one
    batched product over zero-padded pairs (the inner index runs over the pair's points × I)."""
    nb = int(eB.max(initial=0)) + 2                          # eB = −1 (no partner) sorts first
    key, inv = np.unique(srow.astype(np.int64) * nb + (eB + 1), return_inverse=True)
    (_, R, I), C, n = left.shape, right.shape[2], len(key)
    L, Rt = _padded(inv.ravel(), n, left, right)
    pair = np.stack([key // nb, key % nb - 1], axis=1)
    return pair, np.matmul(L.transpose(0, 2, 1, 3).reshape(n, R, -1), Rt.reshape(n, -1, C))


def reference_scale(interfaces) -> float:
    """E/h [Pa/m] of the softest beam of the interfaces (h = min(element length, √area)): the
    stiffness per area of an interface as stiff as the beams next to it."""
    return min(reference_modulus(b) / reference_size(b) for i in interfaces for b in (i.a, i.b))


class PartnerTerm:
    """A tangential law at the contact points: reference partners, history, fields (a base)."""
    name = "shear"
    symmetric = True
    #: the law's history per point, each (P, 3) (names)
    history: tuple = ()
    #: PETSc option defaults the law asks for (the command line and config override them)
    options: dict = {}
    #: whether the law has unknowns of its own (tangential multipliers in the multiplier space)
    multipliers = False
    #: whether the law's forces tie A's displacements to B's directly (a stiffness between two
    #: beams, outside the fascicle blocks and the multipliers: linalg.choice)
    couples_beams = False
    #: whether the law's bounds follow the state (friction's μ ẑ: ``hold_bounds``)
    bounded = False
    #: per-interface statistics of ``sums``: (name, how ranks combine it)
    columns = (("max_tangential_slip", "max"), ("max_shear_stress", "max"), ("shear_force_x", "sum"),
               ("shear_force_y", "sum"), ("shear_force_z", "sum"), ("stick_area", "sum"),
               ("pressed_area", "sum"))

    def __init__(self, model, points, projector):
        self.points = points
        self.slots = model.block.slots              # an element's shape functions (18 for 3363)
        self.node_size = model.dofs_per_node        # a node block's DOFs
        self.eB0 = projector.eB.copy()              # the projector starts at the partners
        conn = model.connectivity()

        def q0_of(els):
            return model.q0[conn[els]].reshape(len(els), self.slots, 3)
        _, _, _, self.NB0, self.NB0z = projector.surface(q0_of, points.itf, self.eB0, projector.xiB, projector.tB)
        #: B's outward normal is T_t × T_ξ, flipped where B runs its curve backwards
        self.flip = projector.flip
        self.state = {name: np.zeros((points.n_points, 3)) for name in self.history}
        self._saved = self._copy()

    # ------------------------------------------------------------------ kinematics
    def relative(self, c, st, x_of) -> np.ndarray:
        """d of the local points (P, 3)."""
        return st.xA - np.einsum("pa,pai->pi", self.NB0[c.local], x_of(self.eB0[c.local]))

    def grad_d(self, c) -> np.ndarray:
        """[N_A, −N_B(ζ₀)] of the local points (P, 36): ∇d = that ⊗ I over (A, partner)."""
        return np.concatenate([c.points.NA[c.local], -self.NB0[c.local]], axis=1)

    def add_point_forces(self, c, st, floc: np.ndarray, force: np.ndarray) -> None:
        """Add per-point forces over (A's element, the partner's): ``force`` (P, 36, 3)."""
        idx = c.local
        S, D = self.slots, self.node_size
        for e, f in ((c.points.eA[idx], force[:, :S]), (self.eB0[idx], force[:, S:])):
            pos = st.lpos(c.conn[e])                                          # (P, 3)
            dofs = (D * pos[:, :, None] + np.arange(D)).ravel()
            floc += np.bincount(dofs, f.reshape(-1), minlength=floc.size)

    def segment_nodes(self, c) -> np.ndarray:
        """(local segments, 6): A's nodes and the partner element's (PETSc numbering); every
        point of a segment has its partner on the same B element (conforming interfaces)."""
        segs = c.segments
        return np.concatenate([c.conn[c.points.seg_eA[segs]], c.conn[self.eB0[c.points.seg_start[segs]]]], axis=1)

    def couplings(self, c) -> list[np.ndarray]:
        """Node-block groups (PETSc numbering, −1 unused) the term couples, all with all."""
        return [self.segment_nodes(c)]

    def required_elements(self, c) -> np.ndarray:
        """Elements whose nodes the local evaluation reads: the partners'."""
        return self.eB0[c.local]

    def required_blocks(self, c) -> np.ndarray:
        """Node blocks of the law's own unknowns the local evaluation reads (none)."""
        return np.zeros(0, dtype=np.int64)

    def set_numbering(self, c, perm: np.ndarray) -> None:
        """The ``Contact`` c's block numbering ``perm`` changed (the law's unknowns follow it)."""

    def hold_bounds(self) -> float | None:
        """Hold the law's state-dependent bounds at the last evaluation's (friction: Tresca's
        problem); the largest change since the last hold, relative to the largest bound (inf the
        first time), this rank's; None for a law without such bounds."""
        return None

    def release_bounds(self) -> None:
        """The bounds follow the state again (``hold_bounds``)."""

    # ------------------------------------------------------------------ state
    def accept(self, c, st) -> None:
        """A converged state: the law's history of the local points from it (``kept``)."""
        for key, value in self.kept(st.terms[self.name]).items():
            self.state[key][c.local] = value

    def kept(self, ev) -> dict:
        """The history a converged evaluation leaves (none)."""
        return {}

    def _copy(self) -> dict:
        return {k: v.copy() for k, v in self.state.items()}

    def checkpoint(self) -> None:
        self._saved = self._copy()

    def restore(self) -> None:
        self.state = {k: v.copy() for k, v in self._saved.items()}

    def set_state(self, fields: dict) -> None:
        """A restart's history (every point: ``fields`` of the written level; ``shear_*`` in
        files written before issue 39)."""
        for key in self.state:
            value = fields[HISTORY + key] if HISTORY + key in fields else fields["shear_" + key]
            self.state[key] = np.asarray(value, dtype=float).copy()
        self.checkpoint()

    # ------------------------------------------------------------------ reports
    def fields(self, c, st) -> dict[str, np.ndarray]:
        """Per local point, first against second in config order (``Interface.sign``): the
        tangential slip u_first − u_second [m] from the reference partner (the part of d in B's
        tangent plane at the point's closest point), the interface stress [Pa] the first beam
        puts on the second, stick (1) or not (0), and the history a restart needs
        (``history_*``, as the law keeps it: A against B)."""
        ev, n = st.terms[self.name], st.pr.n
        sign = output_signs(c, c.points.itf[c.local])[:, None]
        out = {"tangential_slip": sign * tangential(ev.d, n), "shear_stress": sign * ev.sigma,
               "stick": ev.stick.astype(np.int8)}
        return out | {HISTORY + k: v[c.local] for k, v in self.state.items()}

    def sums(self, c, st, on: np.ndarray) -> list[float]:
        """The local parts of ``columns`` over the local points ``on`` (bool) of one interface:
        the stick share is the sticking part of the pressed area (p > 0 at the point) for a law
        the pressure bounds (friction), of the whole area for one it does not (the elastic matrix
        holds opened and pulled interfaces too: docs/running.md, 1)."""
        ev = st.terms[self.name]
        slip = np.linalg.norm(tangential(ev.d[on], st.pr.n[on]), axis=1)
        sigma = ev.sigma[on]
        force = ev.omega[on] @ sigma if on.any() else np.zeros(3)
        pressed = st.pressure[on] > 0.0 if self.bounded else np.ones(int(on.sum()), dtype=bool)
        return [slip.max(initial=0.0), np.linalg.norm(sigma, axis=1).max(initial=0.0), *force,
                float(ev.omega[on] @ (ev.stick[on] & pressed)), float(ev.omega[on] @ pressed)]

    @staticmethod
    def report(values: dict, sign: float) -> dict:
        """Per-interface entries of the summary from the combined ``columns``; ``sign`` the
        interface's ``Interface.sign`` (the shear force is the one the first beam in config
        order puts on the second [N])."""
        area = values["pressed_area"]
        return {"max_tangential_slip": values["max_tangential_slip"],
                "max_shear_stress": values["max_shear_stress"],
                "shear_force": [sign * values["shear_force_x"], sign * values["shear_force_y"],
                                sign * values["shear_force_z"]],
                "stick_share": values["stick_area"] / area if area else 0.0}
