"""Is the residual continuous where Newton failed?  A failed level's cause (solver_messages).

A Newton iteration that cycles or wanders may be near a limit or bifurcation point, or it may
straddle a jump of the residual: a discontinuity of the discrete model, which no increment,
line search or predictor passes.  Measured 2026-11-29 on the soleus-biased unilateral stride at
twist 90° (frame 46.8): a contact point's weight derivatives were cut off at one value of its
projection's conditioning, and its force switched by 0.87 N between states 5e-13 apart; Newton
cycled with period 5 at every increment down to 6e-5 of a frame, and the message named only the
cycle (contact/weights.conditioned now fades them in).

So on a level's final failure the stepper scans |F| along the steps between the last iterates of
the failing solve (``IterateTrail``, kept by the SNES monitor), at most ``SEGMENTS`` of them,
those along which |F| rose most: ``SAMPLES`` states each, then ``BISECTIONS`` halvings of the
interval of the largest change, keeping the half that changes more.  A change that stays above
``JUMP_SHARE`` of the residual's size and above Newton's absolute tolerance as the two states
close to rounding is a jump (below the tolerance: the closest points' own convergence leaves
jumps of 4e-10 N at |F| 1e-6 N, measured on the traced subject at twist 120°); the message
names its size and where it acts (a beam's node, or a contact multiplier's row), and what the
contact's projections at the two states show changing there (``contact_cause``): a closest point
on another B element (B's surface is only C⁰ across its element boundaries: the point's normal
and force turn there; docs/contact.md, "Limits"), or a point's weight.  Each projection starts
from the last one, so where a point has two closest points the state evaluated last decides;
the scan then says so (the two states evaluated again one after the other do not jump).
Measured 2026-11-29 on the 26 failing cells of the gait envelope (docs/gait.md): 8 jump, each
where a point's closest point changes B element and each with two closest points; in 3 at the
common node of two elements (normals 4–5° apart, Newton cycling at |F| 0.15–0.21 N: the C⁰
surface), in 5 at two places of B far apart (normals 59–160° apart; in 4 of them on iterates
far from equilibrium)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

#: iterates of the last SNES solve kept for the scan
TRAIL = 6
#: steps scanned at most (those along which |F| rose most)
SEGMENTS = 3
#: states sampled along a step, ends included
SAMPLES = 17
#: halvings of the interval with the largest change (2^-45 ≈ 3e-14 of the step)
BISECTIONS = 45
#: a change of F between the bisected states above this share of max |F| along the step is a jump
#: (a continuous residual leaves ~1e-12 of it)
JUMP_SHARE = 1e-4
#: a closest point this near (in ξ) to the ends of two neighbouring B elements sits at their
#: common node, where B's surface is C⁰ (``contact_cause``)
NODE_XI = 0.01
#: units in the last place by which ``rounding_noise`` moves every unknown of a state
NOISE_ULPS = 4.0


class IterateTrail:
    """The last ``TRAIL`` iterates of the current SNES solve and their |F| (``record``, from the
    monitor: iteration 0 starts the trail again)."""

    def __init__(self, size: int = TRAIL):
        self.size = size
        self.vecs: list[PETSc.Vec] = []
        self.norms: list[float] = []
        self._next = 0

    def record(self, its: int, X: PETSc.Vec, fnorm: float) -> None:
        if its == 0:
            self.norms, self._next = [], 0
        if len(self.vecs) < self.size:
            self.vecs.append(X.duplicate())
        slot = self._next % self.size
        X.copy(self.vecs[slot])
        self.norms.append(float(fnorm))
        self._next += 1

    def steps(self) -> list[tuple[PETSc.Vec, PETSc.Vec, float]]:
        """(start, end, rise of |F|) of the kept consecutive iterates, oldest first."""
        n = min(self._next, self.size)
        slots = [(self._next - n + k) % self.size for k in range(n)]
        norms = self.norms[-n:]
        return [(self.vecs[a], self.vecs[b], norms[k + 1] - norms[k])
                for k, (a, b) in enumerate(zip(slots, slots[1:]))]

    def destroy(self) -> None:
        for v in self.vecs:
            v.destroy()
        self.vecs = []


@dataclass
class Jump:
    size: float        # max |ΔF| over the DOFs between the two closest states [N]
    scale: float       # max |F| along the step [N]
    where: str         # the DOF it acts on, in words
    cause: str = ""    # what the contact's projections show changing there, in words
    kind: str = "residual_jump"   # its code (failure_cause.JUMP_CAUSES, or rounding_noise)
    noise: float = 0.0  # with kind rounding_noise: max |ΔF| when the state moves by its rounding [N]


def residual_jump(problem, trail: IterateTrail, load_factor: float, tolerance: float = 0.0) -> Jump | None:
    """The largest jump of the residual at ``load_factor`` along the trail's steps, or None when
    it is continuous there or jumps by no more than ``tolerance`` (Newton's absolute tolerance:
    a smaller jump cannot stop it; the projections' own tolerances leave ~1e-10 N) (collective;
    the contact's status is held, and its state and the problem's load factor are the caller's
    to restore)."""
    steps = sorted(trail.steps(), key=lambda s: -s[2])[:SEGMENTS]
    if not steps:
        return None
    problem.load_factor = load_factor
    F, Y, d = problem.F.duplicate(), problem.X.duplicate(), problem.X.duplicate()
    comm = problem.comm.tompi4py()
    best = None
    try:
        for A, B, _ in steps:
            B.copy(d)
            d.axpy(-1.0, A)
            found = _scan(problem, A, d, Y, F, comm, tolerance)
            if found is not None and (best is None or found.size > best.size):
                best = found
    finally:
        for v in (F, Y, d):
            v.destroy()
    return best


def _scan(problem, A, d, Y, F, comm, tolerance: float) -> Jump | None:
    projections = {}

    def at(s: float) -> np.ndarray:
        A.copy(Y)
        Y.axpy(s, d)
        if problem.contact is not None:
            problem.contact.allow_update = False          # the status held
        problem.residual(None, Y, F)
        if problem.contact is not None:
            projections[s] = _projection(problem, Y)
        return F.getArray().copy()

    def largest(a: np.ndarray, b: np.ndarray) -> float:
        return comm.allreduce(float(np.max(np.abs(a - b), initial=0.0)), op=MPI.MAX)

    s = np.linspace(0.0, 1.0, SAMPLES)
    values = [at(x) for x in s]
    scale = max(comm.allreduce(float(np.max(np.abs(v), initial=0.0)), op=MPI.MAX) for v in values)
    if not np.isfinite(scale) or scale == 0.0:
        return None
    k = int(np.argmax([largest(a, b) for a, b in zip(values, values[1:])]))
    lo, hi, f_lo, f_hi = s[k], s[k + 1], values[k], values[k + 1]
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        f_mid = at(mid)
        if largest(f_mid, f_lo) >= largest(f_hi, f_mid):
            hi, f_hi = mid, f_mid
        else:
            lo, f_lo = mid, f_mid
    size = largest(f_hi, f_lo)
    if not np.isfinite(size) or size <= max(JUMP_SHARE * scale, tolerance):
        return None
    where = _where(problem, np.abs(f_hi - f_lo), comm)
    noise = np.inf                      # at the step's ends, away from the jump (a state within
    for end, f_end in ((0.0, values[0]), (1.0, values[-1])):    # rounding of it would cross it)
        A.copy(Y)
        Y.axpy(end, d)
        noise = min(noise, rounding_noise(problem, Y, F, f_end, comm))
    if size <= noise:
        return Jump(size=size, scale=scale, where=where, kind="rounding_noise", noise=noise)
    cause, kind = "", "residual_jump"
    if problem.contact is not None:
        kind, cause = contact_cause(problem.contact, projections[lo], projections[hi], comm)
        again = at(lo)
        if largest(at(hi), again) < 0.5 * size:
            cause += ("; evaluated again one after the other the two states agree: each projection "
                      "starts from the last one, and a contact point has two closest points there")
    return Jump(size=size, scale=scale, where=where, cause=cause, kind=kind)


def rounding_noise(problem, Y: PETSc.Vec, F: PETSc.Vec, f_Y: np.ndarray, comm) -> float:
    """max |ΔF| over the DOFs when every unknown of the state Y moves by ``NOISE_ULPS`` units in
    its last place, up or down by a fixed pseudo-random sign per model DOF (the same on any rank
    count): the residual's rounding at Y, below which no |F| is meaningful.  It grows with the
    stiffness that multiplies the positions' rounding: an elastic interface of k_t = 1e12 Pa/m
    between bars of E = 1 MPa (configs/shear_lag_sandwich.yaml) 3.6e-10 N, where the rounding
    at rest |F(q0, 0)| is 1.5e-13 N and Newton stalled at 1.1-1.9e-10 N.  Y and F are
    overwritten; ``f_Y`` is F(Y)'s local array (collective)."""
    D = Y.getBlockSize()
    lo, hi = Y.getOwnershipRange()
    node = np.argsort(problem.layout.perm)[np.arange(lo, hi) // D]      # PETSc → model node
    dof = node * D + np.arange(lo, hi) % D
    sign = np.where(np.modf(np.sin(dof * 12.9898) * 43758.5453)[0] > 0.0, 1.0, -1.0)
    y = Y.getArray()
    y += sign * NOISE_ULPS * np.spacing(np.abs(y))
    if problem.contact is not None:
        problem.contact.allow_update = False
    problem.residual(None, Y, F)
    return comm.allreduce(float(np.max(np.abs(F.getArray() - f_Y), initial=0.0)), op=MPI.MAX)


def _projection(problem, Y: PETSc.Vec):
    """The projections of the contact's evaluation at Y, the one its residual just made (the
    contact keeps it), the status held."""
    problem.contact.allow_update = False
    return problem.contact.evaluate(problem.exchange.local_state(Y).copy(), problem.exchange.needed).pr


def contact_cause(contact, a, b, comm) -> tuple[str, str]:
    """What changes between the projections ``a`` and ``b`` (of this rank's points) of two states
    a rounding apart: (its code, failure_cause.JUMP_CAUSES; in words): the point whose closest
    point is on another B element, with the largest turn of its normal, else the point whose
    weight changes most (collective)."""
    switched = np.flatnonzero((a.eB != b.eB) & (a.valid | b.valid))
    turn = np.nan_to_num(np.degrees(np.arccos(np.clip(np.einsum("pi,pi->p", a.n, b.n), -1.0, 1.0))))
    dw = np.nan_to_num(np.abs(a.weight - b.weight))
    if switched.size:
        k = int(switched[np.argmax(turn[switched])])
        key = 2.0 + float(turn[k])                      # above any change of a weight
    else:
        k = int(np.argmax(dw)) if dw.size else -1
        key = min(float(dw[k]), 1.0) if dw.size else 0.0
    best, rank = comm.allreduce((key, comm.rank), op=MPI.MAXLOC)
    text, kind = "", "residual_jump"
    if comm.rank == rank and best > 1e-9:
        p = int(a.idx[k])
        itf = contact.interfaces[int(contact.points.itf[p])]
        point = f"contact point {p} (on {itf.a.name}) of interface {itf.name}"
        if best >= 2.0:
            off = itf.b.element_offset
            step = int(b.eB[k]) - int(a.eB[k])          # a common node: ξ = ±1 toward each other
            at_node = abs(step) == 1 and min(step * a.xiB[k], -step * b.xiB[k]) > 1.0 - NODE_XI
            why = ("B's surface is only C0 across its element boundaries, and the point's normal "
                   "turns by {:.3g} deg there (docs/contact.md, \"Limits\")" if at_node else
                   "two places of B about as near to the point, their normals {:.3g} deg apart")
            kind = "c0_kink" if at_node else "two_closest_points"
            text = (f"; there {point} has its closest point on {itf.b.name}'s element "
                    f"{int(a.eB[k]) - off} at xi = {a.xiB[k]:+.4f} on one side and on element "
                    f"{int(b.eB[k]) - off} at xi = {b.xiB[k]:+.4f} on the other: " + why.format(turn[k]))
        else:
            kind = "fade_weight_jump"
            text = f"; there the weight of {point} changes from {a.weight[k]:.4g} to {b.weight[k]:.4g}"
    return comm.bcast((kind, text), root=rank)


def _where(problem, change: np.ndarray, comm) -> str:
    """The DOF of the largest change, in words (the rank that holds it says; collective)."""
    local = float(np.max(change, initial=-1.0))
    value, rank = comm.allreduce((local, comm.rank), op=MPI.MAXLOC)
    text = ""
    if comm.rank == rank:
        D = problem.X.getBlockSize()
        lo = problem.X.getOwnershipRange()[0] // D
        row = int(np.argmax(change))
        node = int(np.argsort(problem.layout.perm)[lo + row // D])       # PETSc → model node
        model = problem.model
        text = "a contact multiplier's row"
        if node < model.n_nodes:
            beam = model.beams[model.node_beam()[node]]
            text = f"beam {beam.name}, node {node - beam.node_offset}"
    return comm.bcast(text, root=rank)


def jump_detail(jump: Jump | None) -> str:
    """The failure message's part for a jump (empty without one)."""
    if jump is None:
        return ""
    if jump.kind == "rounding_noise":
        return (f"; |F| is at the residual's rounding there: moving every unknown of the state by "
                f"{NOISE_ULPS:g} units in the last place changes F by up to {jump.noise:.2g} N, more than "
                f"any change found along Newton's last steps ({jump.size:.2g} N at {jump.where}); stiff "
                f"terms (e.g. contact.tangential's stiffness k_t) magnify the rounding of the positions, "
                f"so the run's absolute tolerance, set from the rounding at rest, cannot be reached: "
                f"give -snes_atol {2.0 * jump.noise:.1e} or more (e.g. petsc: {{snes_atol: "
                f"{2.0 * jump.noise:.1e}}})")
    explained = "has its closest point on" in jump.cause
    return (f"; the residual jumps by {jump.size:.3g} N (max |F| {jump.scale:.3g} N along the step) "
            f"between two states of Newton's last steps closer than 1e-13 of a step, at {jump.where}"
            f"{jump.cause}: a discontinuity of the discrete model, not a limit point"
            + ("" if explained else " (please report it with the config)"))
