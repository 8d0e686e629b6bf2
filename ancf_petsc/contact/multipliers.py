"""The contact pressure space: Lagrange multipliers on weighted gaps (mortar type).

The paper holds the sliding gap at zero with a penalty (eqs. 28–29).  Here the constraint is
exact.  On every interface the pressure is p_h(x, τ) = Σ_k λ_k φ_k(x, τ): along the beam the
functions are continuous piecewise Bernstein polynomials of degree ``axial`` over A's elements
(the trace space of the quadratic elements for degree 2: one function per A node, so no
constraint repeats what continuity already says — a per-element space would, and its
multipliers would not be unique), piecewise constants for degree 0; across the interface they
are Bernstein polynomials of degree ``curve`` in τ ∈ [−1, 1] (or, with ``curve_spans`` > 1, the
B-splines of that degree on equal spans of τ: local functions that see an edge's gap, for
unilateral contact; docs/contact.md, "Pointwise penetration").  The constraints are the weighted
mean gaps

    ḡ_k = ∫ φ_k g dA / ∫ φ_k dA = Σ_p Φ_kp g_p,       Φ_kp = w_p φ_k(p) / A_k,

held at zero (sliding) or non-negative with λ_k ≥ 0 (unilateral).  Bernstein polynomials are
non-negative and sum to one, so λ_k ≥ 0 means p_h ≥ 0 everywhere and ḡ_k ≥ 0 is a weighted
non-penetration condition.

**Supported ends** (Wohlmuth 2000, crosspoints; Puso & Laursen 2004; Popp et al. 2012): where both
bodies of an interface are held at an end node (every DOF supported, e.g. ``fix: clamped``), the
gap there is fixed by the supports, and the end's axial function repeats them (2E + 1 functions
of degree 2 on a trace with 2E free nodal values): its multipliers are ill-determined and take
large self-equilibrated values next to the supports.  ``merged`` ends fold that function into its
neighbour, φ₁ ← φ₁ + φ₀ (non-negative, the partition of unity kept), for every function across.

Unknowns: z_k = λ_k A_k / k_s [m] with k_s = E h [N/m] a reference stiffness, so that the
constraint rows k_s ∂ḡ/∂q are of the size of the stiffness rows.  A multiplier belongs to the
lowest A element its function lives on (as a node does); each element's multipliers are packed
per interface into *multiplier nodes* of 18 slots (the Jacobian's node blocks); unused slots are
held at zero like supported DOFs.

A friction law (friction.py) adds a tangential multiplier vector per pressure function
(``with_tangential``): three more slots per function, packed per A element into nodes of their own.
Its functions are the pressure's, except at ends where both bodies' positions are held
(``contact.tangential.supported_ends: merge``, issue 27): there the end axial function's
tangential vector is folded into its neighbour's (one vector for φ₀ + φ₁, the bound summed), the
folded vector held at zero, as exact stick there repeats the supports.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp


#: multiplier slots in one node block (the multipliers share the beams' 18-DOF block layout)


def bernstein(x: np.ndarray, degree: int) -> np.ndarray:
    """Bernstein polynomials of ``degree`` on [−1, 1] at x: (len(x), degree + 1)."""
    s = 0.5 * (np.asarray(x, dtype=float)[:, None] + 1.0)
    k = np.arange(degree + 1)
    binomial = np.array([math.comb(degree, j) for j in k], dtype=float)
    return binomial * s ** k * (1.0 - s) ** (degree - k)


def across_functions(tau: np.ndarray, degree: int, spans: int = 1) -> np.ndarray:
    """The pressure functions across the interface at τ ∈ [−1, 1]: (len(τ), degree + spans).
    One span: the Bernstein polynomials of ``degree``; more: the B-splines of ``degree`` on
    ``spans`` equal spans with maximal smoothness (clamped knots), non-negative and summing to
    one like them, but each living on degree + 1 spans only, so that a function near an edge of
    the interface sees that edge's gap (docs/contact.md, "Pointwise penetration")."""
    if spans == 1:
        return bernstein(tau, degree)
    from scipy.interpolate import BSpline
    knots = np.concatenate([np.full(degree, -1.0), np.linspace(-1.0, 1.0, spans + 1), np.full(degree, 1.0)])
    x = np.clip(np.asarray(tau, dtype=float), -1.0, 1.0)
    return BSpline.design_matrix(x, knots, degree, extrapolate=False).toarray()


@dataclass
class MultiplierSpace:
    Phi: sp.csr_matrix        # (M, P) Φ_kp: ḡ = Φ g
    area: np.ndarray          # (M,) A_k = ∫ φ_k dA [m²]
    interface: np.ndarray     # (M,) interface of each multiplier
    element: np.ndarray       # (M,) A element owning it (the lowest its function lives on)
    node: np.ndarray          # (M,) multiplier node (0-based among multiplier nodes)
    slot: np.ndarray          # (M,) slot in its node (0 .. node_slots − 1)
    node_element: np.ndarray  # (nodes,) A element each multiplier node belongs to
    seg_mults: np.ndarray     # (S, K) the multipliers whose functions live on each segment
    dense: np.ndarray         # (S, K, P) Φ of those multipliers over the segment's own points
    degrees: tuple[int, int]
    stiffness: float          # k_s [N/m]
    #: (M, 3) node and slot of each function's tangential multiplier components (friction)
    tnode: np.ndarray | None = None
    tslot: np.ndarray | None = None
    #: (n_interfaces,) the functions across each interface (axial-major numbering)
    n_across: np.ndarray | None = None
    #: the tangential functions (friction): Φ (M, P), A_k (M,), per segment Φ (S, K, P) and the
    #: folded (held at zero) ones (M,); the pressure's unless folded (``with_tangential``)
    tPhi: sp.csr_matrix | None = None
    tarea: np.ndarray | None = None
    tdense: np.ndarray | None = None
    tdrop: np.ndarray | None = None
    #: slots of a multiplier node: the DOFs of the beams' node block (18 for 3363; Model.dofs_per_node)
    node_slots: int = 18

    @property
    def n_multipliers(self) -> int:
        return len(self.area)

    @property
    def n_nodes(self) -> int:
        return len(self.node_element)

    def segment_nodes(self) -> np.ndarray:
        """(S, 2) the multiplier nodes of each segment's functions: its own A element's and the
        previous element's (whose end function it shares), −1 where there is only one."""
        sm = self.seg_mults
        nodes = np.where(sm >= 0, self.node[np.maximum(sm, 0)], -1)
        first, last = nodes[:, 0], np.max(nodes, axis=1)
        return np.stack([first, np.where(last != first, last, -1)], axis=1)

    def padding(self) -> np.ndarray:
        """(nodes, node_slots) True for the slots no multiplier uses."""
        used = np.zeros((self.n_nodes, self.node_slots), dtype=bool)
        used[self.node, self.slot] = True
        if self.tnode is not None:
            used[self.tnode, self.tslot] = True
        return ~used


def with_tangential(space: MultiplierSpace, wanted: bool = True,
                    folded: np.ndarray | None = None) -> MultiplierSpace:
    """The space with a tangential multiplier vector (3 components) per pressure function,
    in multiplier nodes after the normal ones: each A element's, in multiplier order, 6 to a
    node (the element owns them, as it owns its pressure functions); ``space`` if not wanted.
    ``folded`` (n_interfaces, 2) bool: fold the first / last end's tangential functions into
    their neighbours (``fold_tangential``)."""
    if not wanted:
        return space
    tnode = np.empty((space.n_multipliers, 3), dtype=np.int64)
    tslot = np.empty((space.n_multipliers, 3), dtype=np.int64)
    nodes = list(space.node_element)
    SLOTS = space.node_slots
    for e in np.unique(space.element):
        idx = np.flatnonzero(space.element == e)
        k = np.arange(3 * len(idx))
        tnode[idx] = (len(nodes) + k // SLOTS).reshape(-1, 3)
        tslot[idx] = (k % SLOTS).reshape(-1, 3)
        nodes += [e] * -(-len(k) // SLOTS)
    return fold_tangential(replace(space, node_element=np.asarray(nodes, dtype=np.int64), tnode=tnode,
                                   tslot=tslot), folded)


def fold_tangential(space: MultiplierSpace, folded: np.ndarray | None) -> MultiplierSpace:
    """The tangential functions: the pressure's, with the end axial function of each ``folded``
    (interface, end) added to its neighbour along (φ₁ ← φ₁ + φ₀ for every function across; its
    A_k, Φ and so its bound ∫ φ p⁺ dA summed) and the end's own emptied (dropped, its vector
    held at zero).  Both live on the end segment, so the segments' lists stay as they are."""
    M = space.n_multipliers
    into = np.arange(M)
    for k in np.flatnonzero(np.any(folded, axis=1)) if folded is not None and space.degrees[0] >= 1 else ():
        ids, nc = np.flatnonzero(space.interface == k), int(space.n_across[k])
        if folded[k, 0] and len(ids) >= 2 * nc:
            into[ids[:nc]] = ids[nc:2 * nc]
        if folded[k, 1] and len(ids) >= 3 * nc:
            into[ids[-nc:]] = ids[-2 * nc:-nc]
    drop = into != np.arange(M)
    if not drop.any():
        return replace(space, tPhi=space.Phi, tarea=space.area, tdense=space.dense, tdrop=drop)
    C = sp.csr_matrix((np.ones(M), (into, np.arange(M))), shape=(M, M))
    W = C @ sp.diags(space.area) @ space.Phi                     # rows w_p φ_k(p), folded
    tarea = np.asarray(W.sum(axis=1)).ravel()
    tPhi = (sp.diags(np.where(drop, 0.0, 1.0 / np.where(drop, 1.0, tarea))) @ W).tocsr()
    sm = space.seg_mults
    real = sm >= 0
    wd = space.dense * np.where(real, space.area[np.maximum(sm, 0)], 0.0)[:, :, None]
    for s, j in zip(*np.nonzero(real & drop[np.maximum(sm, 0)])):   # two per folded end
        wd[s, np.flatnonzero(sm[s] == into[sm[s, j]])[0]] += wd[s, j]
        wd[s, j] = 0.0
    scale = np.where(real & ~drop[np.maximum(sm, 0)], tarea[np.maximum(sm, 0)], np.inf)
    return replace(space, tPhi=tPhi, tarea=np.where(drop, 0.0, tarea), tdense=wd / scale[:, :, None],
                   tdrop=drop)


def reference_modulus(beam) -> float:
    """E [Pa]: the beam's small-strain Young's modulus (from μ and K where no E is given)."""
    mat = beam.material
    E = getattr(mat, "E", None)
    return float(9.0 * mat.K * mat.mu / (3.0 * mat.K + mat.mu) if E is None else E)


def reference_size(beam) -> float:
    """h [m] = min(element length, √area): the length over which a contact force spreads."""
    k = beam.layout.block.axial_nodes - 1                  # the element's last node
    return float(min(beam.x_nodes[k] - beam.x_nodes[0], np.sqrt(beam.section.area)))


def reference_beam(interfaces):
    """The softest beam of the interfaces: the least E h (``reference_modulus``, ``reference_size``)."""
    return min((b for itf in interfaces for b in (itf.a, itf.b)),
               key=lambda b: reference_modulus(b) * reference_size(b))


def reference_stiffness(interfaces) -> float:
    """k_s = E_min h [N/m]: E the small-strain Young's modulus of the softer beam, h = min(element
    length, √area).  It only scales the multiplier unknowns (the constraint rows then have the
    size of the stiffness rows); the answer does not depend on it."""
    beam = reference_beam(interfaces)
    return reference_modulus(beam) * reference_size(beam)


def reference_shear_ratio(interfaces) -> float:
    """G/E of the beam that sets k_s (``reference_beam``): μ / E at small strain, 1/3 for a nearly
    incompressible solid.  A tangential traction meets the shear stiffness G h of the structure
    beneath it, not E h: the Coulomb law's default augmentation (friction.py)."""
    beam = reference_beam(interfaces)
    return float(beam.material.mu / reference_modulus(beam))


def _axial_functions(xi: np.ndarray, degree: int, per_element: bool) -> tuple[np.ndarray, int]:
    """Values (n, degree + 1) of one element's axial functions at ξ and the offset between
    consecutive elements' first function (``degree``: they share an end; degree + 1 when each
    element has its own functions, as constants always do)."""
    if degree == 0:
        return np.ones((len(xi), 1)), 1
    return bernstein(xi, degree), degree + 1 if per_element else degree


def _fold_ends(n_axial: int, nc: int, ends) -> np.ndarray:
    """(n_axial·nc,) the local function each of an interface's functions is folded into: itself,
    or for a merged end (``ends`` = (first, last)) the end axial function's neighbour along."""
    into = np.arange(n_axial * nc)
    if ends is not None and n_axial >= 2:
        if ends[0]:
            into[:nc] += nc
        if ends[1] and n_axial >= 3:
            into[-nc:] -= nc
    return into


def _merge(into: np.ndarray, rows: np.ndarray, seg_mults: np.ndarray, dense: np.ndarray,
           element: np.ndarray) -> tuple:
    """Fold each function k into ``into[k]`` (φ_into ← φ_into + φ_k) and number the remaining
    ones consecutively: the rows of w_p φ_k(p), each segment's list (the folded entries' values
    added to their survivor's, the −1 padding moved last), the owning A element (the lowest of
    the two) and which of the old functions remain."""
    keep = into == np.arange(len(into))
    new = np.cumsum(keep) - 1
    final = new[into]
    owner = np.full(int(keep.sum()), np.iinfo(np.int64).max)
    np.minimum.at(owner, final, element)
    folded = np.any((seg_mults >= 0) & ~keep[np.maximum(seg_mults, 0)], axis=1)
    seg_mults = np.where(seg_mults >= 0, final[np.maximum(seg_mults, 0)], -1)
    dense = dense.copy()
    for s in np.flatnonzero(folded):          # the segments at merged ends (two per interface)
        ids = [m for m in dict.fromkeys(seg_mults[s].tolist()) if m >= 0]
        vals = [dense[s, seg_mults[s] == m].sum(axis=0) for m in ids]
        seg_mults[s], dense[s] = -1, 0.0
        seg_mults[s, :len(ids)], dense[s, :len(ids)] = ids, vals
    return final[rows], seg_mults, dense, owner, keep


def build_space(points, interfaces, degrees: tuple[int, int], stiffness: float,
                per_element: bool = False, group: int = 1,
                merged: np.ndarray | None = None, spans: int = 1) -> MultiplierSpace:
    """Multipliers of ``degrees`` (axial, curve) on every interface of ``points``; with
    ``per_element`` the pressure is discontinuous between A elements.  That space repeats
    constraints (in the reference state its gaps vanish together with the continuous ones, so
    some multipliers are not unique) and needs the factorisation's null-pivot detection; it is
    the space of the former penalty formulation, kept to compare with it.  ``group`` > 1 spans
    the axial functions over groups of that many A elements (the space of a coarser mesh on
    this one's displacements: ``ContactSpec.group``, set in code, no config key).  ``merged``
    (n_interfaces, 2) bool: fold the first / last axial function of those interfaces into its
    neighbour (supported ends: interfaces.supported_ends; only for axial degree ≥ 2, the
    trace space and richer: a linear space has fewer functions than the trace has values).
    A multiplier node has as many slots as the beams' node block has DOFs (Model.dofs_per_node)."""
    ka, kc = degrees
    node_slots = interfaces[0].a.layout.block.dofs_per_node
    S = points.n_segments
    K = (ka + 1) * (kc + spans)
    P_max = int(points.seg_size.max(initial=0))
    seg_mults = np.full((S, K), -1, dtype=np.int64)
    dense = np.zeros((S, K, P_max))
    rows, cols, vals, itf_of, elem_of = [], [], [], [], []
    into = []                      # per interface: the function each one is folded into
    n_across = []
    first = 0
    for k, itf in enumerate(interfaces):
        segs = np.flatnonzero(points.seg_itf == k)         # one per A element, in order
        p0 = points.seg_start[segs[0]]
        n = int(points.seg_size[segs[0]])
        xi, tau = points.xi[p0:p0 + n], points.tau[p0:p0 + n]
        distinct = len(np.unique(np.round(tau, 12)))          # no more than the points tell apart
        ds = max(1, min(spans, distinct - kc))
        dc = min(kc, distinct - ds)
        across = across_functions(tau, dc, ds)
        ax, step = _axial_functions(xi, ka, per_element)
        phi = (ax[:, :, None] * across[:, None, :]).reshape(n, -1)   # (n, na·nc)
        na, nc = ax.shape[1], across.shape[1]
        n_across.append(nc)
        if len(segs) % group:
            raise ValueError(f"{len(segs)} elements do not fall into groups of {group}")
        n_axial = step * (len(segs) // group - 1) + na
        for e, s in enumerate(segs):
            if group > 1:                # the group's functions at the segment's points
                ax_g, _ = _axial_functions((e % group + 0.5 * (xi + 1.0)) * 2.0 / group - 1.0, ka,
                                           per_element)
                phi = (ax_g[:, :, None] * across[:, None, :]).reshape(n, -1)
            # the segment's functions: axial dofs g·step … g·step + na − 1 (g = e // group), all
            # across dofs
            ids = first + (((e // group) * step + np.arange(na))[:, None] * nc + np.arange(nc)).ravel()
            seg_mults[s, :len(ids)] = ids
            sl = points.seg_start[s] + np.arange(n)
            rows.append(np.repeat(ids, n))
            cols.append(np.tile(sl, len(ids)))
            wphi = (points.w[sl][:, None] * phi).T                    # w_p φ_k(p), divided below
            vals.append(wphi.ravel())
            dense[s, :len(ids), :n] = wphi
        m_here = n_axial * nc
        axial_dof = np.arange(m_here) // nc
        shared = step < na                                          # neighbours share an end
        owner = (np.maximum(axial_dof - 1, 0) if shared else axial_dof) // step * group
        owner = np.minimum(owner, len(segs) - 1)                      # lowest element it lives on
        itf_of.append(np.full(m_here, k))
        elem_of.append(points.seg_eA[segs][owner])
        into.append(first + _fold_ends(n_axial, nc, None if merged is None or ka < 2 else merged[k]))
        first += m_here
    element, interface = np.concatenate(elem_of), np.concatenate(itf_of)
    rows, keep = np.concatenate(rows), np.ones(first, dtype=bool)
    if merged is not None and np.any(merged) and ka >= 2:
        rows, seg_mults, dense, element, keep = _merge(np.concatenate(into), rows, seg_mults, dense, element)
        interface = interface[keep]
    M = int(keep.sum())
    W = sp.csr_matrix((np.concatenate(vals), (rows, np.concatenate(cols))),
                      shape=(M, points.n_points))
    area = np.asarray(W.sum(axis=1)).ravel()
    Phi = sp.diags(1.0 / area) @ W
    dense /= np.where(seg_mults >= 0, area[seg_mults], 1.0)[:, :, None]
    # pack each A element's multipliers into nodes of node_slots slots, interface by interface
    node = np.empty(M, dtype=np.int64)
    slot = np.empty(M, dtype=np.int64)
    node_element = []
    for e in np.unique(element):
        fill = node_slots
        for k in np.unique(interface[element == e]):
            idx = np.flatnonzero((element == e) & (interface == k))
            if fill + len(idx) > node_slots:
                node_element.append(e)
                fill = 0
            node[idx], slot[idx] = len(node_element) - 1, fill + np.arange(len(idx))
            fill += len(idx)
    return MultiplierSpace(Phi=Phi.tocsr(), area=area, interface=interface, element=element,
                           node=node, slot=slot, node_element=np.asarray(node_element, dtype=np.int64),
                           seg_mults=seg_mults, dense=dense, degrees=degrees, stiffness=float(stiffness),
                           n_across=np.asarray(n_across, dtype=np.int64), node_slots=node_slots)
