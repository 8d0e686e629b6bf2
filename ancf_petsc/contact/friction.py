"""Coulomb friction between subtendons with tangential multipliers: exact stick (issue 27).

The tangential traction is a field of the pressure's functions (multipliers.py), t(x) =
Σ_k φ_k(x) λ_T,k, unknown like the pressure p(x) = Σ_k φ_k(x) λ_k and scaled like it:
λ_T,k = k_s y_k / A_k with y_k [m] three more unknowns per function (``with_tangential``).  At
a contact point it acts in B's tangent plane at the closest point, σ_p = (I − n nᵀ) t(x_p), and
adds ω N_Aᵀσ on A and −ω N_B(ζ₀)ᵀσ on the reference partner (partners.py).  Coulomb's law holds
per function, in the weighted (mortar) sense of the normal constraints, with the weighted slip
increment of the function

    U_k = Σ_p Φ_kp ω'_p (I − n_p n_pᵀ)(d_p − d₀_p),    n̄_k = m_k / |m_k|,  m_k = Σ_p Φ_kp ω'_p n_p

(d the relative displacement of the point and its partner, d₀ at the last accepted increment,
ω' the points' weights) as the Alart–Curnier equation (Alart & Curnier 1991; the mortar form of
Gitterle, Popp, Gee & Wall, IJNME 84, 2010, eq. 43):

    R_k = y_k − proj_{|·| ≤ μ ẑ_k} (P̄_k (y_k + c U_k)),    P̄_k = I − n̄_k n̄_kᵀ,

zero where the function sticks (P̄ U = 0 exactly: no stick stiffness, no regularisation; the
normal part of y vanishes) and where it slips (|y| = μ ẑ against the slip).  The bound is the
function's share of the pressing normal force, ẑ_k = ∫ φ_k p⁺ dA / k_s = A_k Σ_p Φ_kp ω'_p
(Φᵀz)_p⁺ / w_p, not z_k⁺: the Bernstein coefficients z_k of a positive pressure oscillate in
sign (the pressed strips: z_k from −84 to 219 Pa where p is 57 … 158 Pa), and Σ_k μ z_k⁺ let
the strips carry 1.18 μN.  Σ_k ẑ_k is the pressing normal force, so a sliding interface carries
μN exactly where p ≥ 0.  The sliding law's pulled parts (p < 0) and an open unilateral interface
carry none.  c (``augmentation``, in units of k_s / A_k) is the stiffness of the structure
under a function's traction: by default G/E of the beam that sets k_s (1/3 for a nearly
incompressible solid, a shear traction meets G h, not E h; until 2026-12-02 it was 1, with which
the 39 μ = 0.3 walking strides cut back in 12 frames against 4: docs/gait.md).  It only steers
the semi-smooth Newton iteration: where the increment has one solution the answer does not
depend on it (the strips: c = 0.1, 0.01, 0.001 agree to 4e-9 μN); where it has several, c can
pick another (docs/interface.md, Limits).  At rest (no pressure, no slip) the sticking
derivative is taken, so Newton's first step holds the interface.
The residual rows are k_s R_k; the Jacobian (friction_blocks.py) is the generalised derivative of
R and of the forces, with the rotation of n and n̄ (gap.normal_gradient) and the bounds' coupling
to the pressures, unsymmetric (MUMPS LU).  ``hold_bounds`` turns the law into Tresca's for a
while: the bounds μ ẑ_k held at the last evaluation's (no coupling to the pressures), the
fixed point by which a failed increment is solved again (solving/newton.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import friction_blocks
from .multipliers import reference_shear_ratio
from .oscillation import pull_within_elements
from .partners import PartnerTerm, tangential
from .reports import output_signs

EYE = np.eye(3)


@dataclass
class FrictionEvaluation:
    """Friction at the local points (P) and the local multipliers (M, ``Contact.mults``).
    Points: d, Δd = d − d₀ (P, 3), the traction σ [Pa] (P, 3), the weighted tangential
    multipliers Y = Σ_k Φ_kp y_k (P, 3), stick (P,), ω (P,) [m²], pressure (P,) [Pa].
    Multipliers: y, a = y + c U, n̄ (M, 3), |m| (M,), T = −∂proj/∂trial (M, 3, 3), g = ∂R/∂bound
    and the slip direction (M, 3), bound μ ẑ (M,) [m], stick and slide (M,), R (M, 3), this
    rank's share, ∂R/∂n̄ (M, 3, 3); whether each point presses (P,)."""
    d: np.ndarray
    du: np.ndarray
    sigma: np.ndarray
    Y: np.ndarray
    stick: np.ndarray
    omega: np.ndarray
    pressure: np.ndarray
    y: np.ndarray
    a: np.ndarray
    nbar: np.ndarray
    mnorm: np.ndarray
    T: np.ndarray
    g: np.ndarray
    direction: np.ndarray
    bound: np.ndarray
    m_stick: np.ndarray
    slide: np.ndarray
    R: np.ndarray
    share: np.ndarray
    dRdn: np.ndarray
    positive: np.ndarray


def return_map(a: np.ndarray, nbar: np.ndarray, bound: np.ndarray, held=True) -> tuple:
    """proj_{|·| ≤ bound}(P̄ a) per multiplier and its derivative S with respect to P̄ a:
    (projection, S, direction, stick, slide).  At the kink a = 0 with no bound (at rest) the
    generalised derivative taken is the sticking one (``held``): Newton's first step from rest
    then holds the interface instead of letting it slide freely (``held``: bool or per multiplier;
    without a bound and not held, R = y: the vector is held at zero)."""
    trial = a - np.einsum("ki,ki->k", nbar, a)[:, None] * nbar
    size = np.linalg.norm(trial, axis=1)
    stick = ((size <= bound) & (bound > 0.0)) | (held & (bound == 0.0) & (size <= 1e-12))
    slide = (bound > 0.0) & ~stick
    direction = np.zeros_like(trial)
    direction[slide] = trial[slide] / size[slide, None]
    proj = np.where(stick[:, None], trial, bound[:, None] * direction)
    ratio = np.where(slide, bound / np.where(slide, size, 1.0), 0.0)
    S = (stick[:, None, None] * EYE
         + ratio[:, None, None] * (EYE - direction[:, :, None] * direction[:, None, :]))
    return proj, S, direction, stick, slide


#: a trial within this share of its bound sits on it (rounding: a level with no increment)
AT_BOUND = 1e-8


def reported_stick(a: np.ndarray, nbar: np.ndarray, bound: np.ndarray, stick: np.ndarray) -> np.ndarray:
    """The stick flags the reports give: the return map's, and a pressed function whose trial
    sits on its bound to within ``AT_BOUND`` (a level with no slip increment, where the side of
    the bound it lands on is rounding's: a stride's rest frames read 0.07 or 0.40 of mg_sol
    sticking on states equal to 5e-17 m).  Newton's own classification is not changed."""
    trial = a - np.einsum("ki,ki->k", nbar, a)[:, None] * nbar
    return stick | ((bound > 0.0) & (np.linalg.norm(trial, axis=1) <= bound * (1.0 + AT_BOUND)))


def stick_fraction(tPhi, area: np.ndarray, m_stick: np.ndarray, tPhiT=None) -> np.ndarray:
    """Per point the share of its tangential functions that stick, each weighted by its value
    φ_k at the point (tΦ_kp = φ_k(x_p) w_p / A_k, ``area`` the functions' A_k); 0 where none.
    ``tPhiT``: tΦᵀ as CSR, if kept (the same sums as tΦ.T's)."""
    T = tPhi.T if tPhiT is None else tPhiT
    weight = T @ area
    return np.divide(T @ (area * m_stick), weight, out=np.zeros(len(weight)), where=weight > 0.0)


def reference_axial(model, points) -> np.ndarray:
    """Reference x [m] of every contact point on its A element (beams straight along x)."""
    x = np.zeros(len(points.eA))
    for b in model.beams:
        m = (points.eA >= b.element_offset) & (points.eA < b.element_offset + b.n_elements)
        e = points.eA[m] - b.element_offset
        k = b.layout.block.axial_nodes - 1          # nodes k e … k e + k of element e
        x0, x1 = b.x_nodes[k * e], b.x_nodes[k * e + k]
        x[m] = x0 + 0.5 * (points.xi[m] + 1.0) * (x1 - x0)
    return x


class CoulombFriction(PartnerTerm):
    """Coulomb friction |t| ≤ μ p⁺ with tangential multipliers (module docstring)."""
    law = "coulomb"
    symmetric = False
    multipliers = True
    bounded = True
    #: per point: the relative displacement d₀ [m] of the last accepted increment
    history = ("anchor",)
    #: the fade weights' derivatives are in the Jacobian (``contact.fade: newton``, the default)
    differentiates_weights = True
    #: the semi-smooth Newton iteration takes the l2 line search (bt stalls at the kinks of the
    #: projection); from rest at mu = 3 it needs up to ~100 iterations to settle the statuses
    #: (a cut-back cannot help there: Coulomb's law is homogeneous in the load)
    options = {"snes_max_it": "200", "snes_linesearch_type": "l2"}

    def __init__(self, coefficient: float, augmentation: float, model, points, projector,
                 free_zone: float = 0.0):
        super().__init__(model, points, projector)
        self.mu = float(coefficient)
        #: a diagnostic: no friction on the functions whose support is centred (the points' mean
        #: reference x, weighted by their weights) below ``free_zone`` [m]: their bound μ ẑ is 0
        self.free_zone = float(free_zone)
        self.x_ref = reference_axial(model, points) if free_zone > 0.0 else None
        self.augmentation = float(augmentation)
        self.n_nodes = model.n_nodes
        self.node_dofs = model.dofs_per_node
        self.tdof = np.zeros((0, 3), dtype=np.int64)       # PETSc DOF of every y_k (M, 3)
        self.seg_tblocks = np.zeros((0, 0), dtype=np.int64)  # each segment's y blocks (S, 3K)
        self.tPhi = self.tPhiT = None
        #: the local multipliers' bounds μ ẑ of the last evaluation (M,) and, while Tresca's
        #: problem is solved (``hold_bounds``), the bounds held fixed (else None)
        self.live_bound = np.zeros(0)
        self.held_bound: np.ndarray | None = None

    @classmethod
    def from_spec(cls, spec, model, points, projector, reference: float,
                  scaling: float = 1.0) -> "CoulombFriction":
        """From ``contact.tangential`` (``friction`` μ, ``augmentation`` c's factor, default G/E
        of the beam that sets k_s: module docstring).  c is in units of the unscaled k_s:
        ``contact.scaling`` s divides y by s, so c / s keeps y + c U the same physical trial
        traction and the iteration the same (with c as given, s = 1000 ran the increments of
        c × 1000 and ended 17 % off on the paper's tendon at μ = 0.3: another solution)."""
        aug = spec.augmentation
        if aug is None:
            aug = reference_shear_ratio(projector.interfaces)
        return cls(spec.friction, aug / scaling, model, points, projector, spec.free_zone)

    # ------------------------------------------------------------------ numbering
    def set_numbering(self, c, perm: np.ndarray) -> None:
        """The PETSc DOFs of the tangential multipliers (block numbering ``perm``)."""
        sp = c.space
        #: the tangential functions' Φ over the local multipliers and points (fold_tangential)
        self.tPhi = c.Phi if sp.tPhi is sp.Phi else sp.tPhi[c.mults][:, c.local].tocsr()
        #: its transpose as CSR: its products are summed as tΦ.T's are, without a transpose per use
        self.tPhiT = c.PhiT if self.tPhi is c.Phi else self.tPhi.T.tocsr()
        self.tdof = self.node_dofs * perm[self.n_nodes + sp.tnode] + sp.tslot
        sm = sp.seg_mults
        blocks = perm[self.n_nodes + sp.tnode[np.maximum(sm, 0)]]                # (S, K, 3)
        self.seg_tblocks = np.where((sm >= 0)[:, :, None], blocks, -1).reshape(len(sm), -1)

    def required_blocks(self, c) -> np.ndarray:
        """The node blocks of the local multipliers' tangential components."""
        return np.unique(self.tdof[c.mults] // self.node_dofs)

    def local_positions(self, c, st) -> np.ndarray:
        """Positions of the local y_k (M, 3) in the local DOF array."""
        D = self.node_dofs
        return D * st.lpos(self.tdof[c.mults] // D) + self.tdof[c.mults] % D

    # ------------------------------------------------------------------ evaluation
    def evaluate(self, c, st, x_of) -> FrictionEvaluation:
        """The law at the local points and multipliers of the ``Contact`` c in its evaluation
        ``st`` (collective with the parallel hooks set: the weighted slips span ranks)."""
        idx, n, w = c.local, st.pr.n, st.weight
        d = self.relative(c, st, x_of)
        du = d - self.state["anchor"][idx]
        u = tangential(du, n)
        wp = self.points.w[idx]
        zl = st.z * st.rows.load
        pz = c.PhiT @ zl
        positive = pz > 0.0                            # the points that press (p > 0)
        tPhi = self.tPhi                               # the tangential functions (folded ends)
        sums = np.hstack([tPhi @ (w[:, None] * u), tPhi @ (w[:, None] * n),
                          tPhi @ (w * positive * pz / wp)[:, None]])
        if c.sum_over_ranks is not None:
            sums = c.sum_over_ranks(sums)
        U, m = sums[:, :3], sums[:, 3:6]
        zhat = c.space.tarea[c.mults] * sums[:, 6]     # ∫ φ_k p⁺ dA / k_s
        mnorm = np.linalg.norm(m, axis=1)
        nbar = np.where(mnorm[:, None] > 0.0, m / np.where(mnorm > 0.0, mnorm, 1.0)[:, None], EYE[0])
        y = st.xl.reshape(-1)[self.local_positions(c, st)]
        self.live_bound = self.mu * zhat
        held_bound = self.held_bound is not None   # Tresca's problem: the bounds do not follow z
        bound = self.held_bound if held_bound else self.live_bound
        probe = c.law.phase.probe                   # the bodies alone: friction held, rows decoupled
        if probe:
            bound = np.zeros_like(bound)
        free = self._free(c, wp)
        if free is not None:
            bound = np.where(free, 0.0, bound)
        a = y + self.augmentation * U
        held = ~c.space.tdrop[c.mults] & (not probe)    # a folded function's y is held at zero
        proj, S, direction, m_stick, slide = return_map(a, nbar, bound, held=held)
        m_stick = reported_stick(a, nbar, bound, m_stick)     # reports only (fields, stick_share)
        R, T, g = y - proj, -S, (0.0 if held_bound else -1.0) * direction
        if free is not None:
            g[free] = 0.0
        na = np.einsum("ki,ki->k", nbar, a)
        dRdn = -T @ (na[:, None, None] * EYE + nbar[:, :, None] * a[:, None, :])
        Y = self.tPhiT @ y
        sigma = c.stiffness * tangential(Y, n) / wp[:, None]
        # a point sticks where most of its functions (by their value φ_k there) stick; tΦ_kp is
        # φ_k(x_p) w_p / A_k, so the weights are tΦ_kp A_k (not tΦ_kp: their sum is not 1)
        on = stick_fraction(tPhi, c.space.tarea[c.mults], m_stick, self.tPhiT)
        pressure = c.stiffness * pz / wp
        share = c.Phi @ np.ones(len(idx)) if c.sum_over_ranks is not None else np.ones(len(c.mults))
        return FrictionEvaluation(d=d, du=du, sigma=sigma, Y=Y, stick=on > 0.5, omega=wp * w,
                                  pressure=pressure, y=y, a=a, nbar=nbar, mnorm=mnorm, T=T, g=g,
                                  direction=direction, bound=bound, m_stick=m_stick, slide=slide,
                                  R=R, share=share, dRdn=dRdn, positive=positive)

    def _free(self, c, wp: np.ndarray) -> np.ndarray | None:
        """(M,) the local functions centred below ``free_zone``, or None without a free zone."""
        if self.x_ref is None:
            return None
        sums = np.column_stack([c.Phi @ wp, c.Phi @ (wp * self.x_ref[c.local])])
        if c.sum_over_ranks is not None:
            sums = c.sum_over_ranks(sums)
        weight = sums[:, 0]
        return (weight > 0.0) & (sums[:, 1] < self.free_zone * np.where(weight > 0.0, weight, 1.0))

    def hold_bounds(self) -> float:
        """Tresca's problem (the bounds μ ẑ held at the last evaluation's; module docstring):
        the largest change of a bound since the last hold relative to the largest (inf the
        first time; 0 without local multipliers), this rank's."""
        new, old = self.live_bound.copy(), self.held_bound
        self.held_bound = new
        if old is None or len(old) != len(new):
            return float("inf") if len(new) else 0.0
        top = np.abs(new).max() if len(new) else 0.0
        return float(np.abs(new - old).max() / top) if top > 0.0 else 0.0

    def release_bounds(self) -> None:
        """Coulomb's law again: the bounds follow the pressures."""
        self.held_bound = None

    def kept(self, ev: FrictionEvaluation) -> dict:
        """The next increment's slips start from this state's relative displacements."""
        return {"anchor": ev.d}

    def add_forces(self, c, st, floc: np.ndarray) -> None:
        """ω N_Aᵀ σ on A's DOFs, −ω N_B(ζ₀)ᵀ σ on the partners' and k_s R_k on the rows of y_k
        (each rank its share of a function living on two ranks)."""
        ev = st.terms[self.name]
        force = ev.omega[:, None] * ev.sigma
        self.add_point_forces(c, st, floc, self.grad_d(c)[:, :, None] * force[:, None, :])
        pos = self.local_positions(c, st)
        floc[pos] += c.stiffness * ev.share[:, None] * ev.R

    def jacobian_blocks(self, c, st, fixed_mask: np.ndarray) -> list:
        """The generalised Jacobian's blocks (friction_blocks.py)."""
        return friction_blocks.jacobian_blocks(self, c, st, fixed_mask)

    def couplings(self, c) -> list[np.ndarray]:
        """Per (local segment, B element of its closest points): A's nodes, the partner's, that
        element's, the segment's pressure and tangential multiplier nodes, all with all."""
        nodes = self.segment_nodes(c)
        srow = np.searchsorted(c.segments, c.points.seg[c.local])
        pair = np.unique(np.stack([srow, c.projected_elements()], 1), axis=0)
        seg = c.segments[pair[:, 0]]
        return [np.concatenate([nodes[pair[:, 0]], c.conn[pair[:, 1]], c.seg_blocks[seg],
                                self.seg_tblocks[seg]], axis=1)]

    # ------------------------------------------------------------------ reports
    def fields(self, c, st) -> dict[str, np.ndarray]:
        """The base's per-point fields, the tangential slip in the level's last load increment
        [m] (u_first − u_second, as ``tangential_slip``; what decides stick or slip) and per
        owned multiplier the tangential traction coefficient λ_T = k_s y / A_k [Pa] (the first
        beam's on the second, as ``shear_stress``) and whether the function sticks."""
        ev, own = st.terms[self.name], c.owned
        area = c.space.tarea[c.mults]
        sign = output_signs(c, c.space.interface[c.mults])
        lam = c.stiffness * sign[:, None] * ev.y / np.where(area > 0.0, area, 1.0)[:, None]
        return super().fields(c, st) | {
            "slip_increment": output_signs(c, c.points.itf[c.local])[:, None] * tangential(ev.du, st.pr.n),
            "multiplier_shear": lam[own], "multiplier_stick": ev.m_stick[own].astype(np.int8)}

    columns = PartnerTerm.columns + (("max_slip_increment", "max"), ("pull_within_elements", "sum"))

    def sums(self, c, st, on: np.ndarray) -> list[float]:
        """The base's statistics, the largest slip in the level's last load increment and the
        pull that cancels within elements (oscillation.py)."""
        du = tangential(st.terms[self.name].du[on], st.pr.n[on])
        return super().sums(c, st, on) + [float(np.linalg.norm(du, axis=1).max(initial=0.0)),
                                          pull_within_elements(c, st, on)]

    @staticmethod
    def report(values: dict, sign: float) -> dict:
        """The base's entries, ``max_slip_increment`` [m] and ``pull_within_elements`` [N]."""
        return PartnerTerm.report(values, sign) | {"max_slip_increment": values["max_slip_increment"],
                                                   "pull_within_elements": values["pull_within_elements"]}

    def describe(self) -> str:
        return (f"Coulomb friction, mu = {self.mu:g} (tangential multipliers, exact stick; "
                f"augmentation {self.augmentation:g})")
