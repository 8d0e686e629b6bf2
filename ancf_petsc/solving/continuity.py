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
names its size and where it acts (a beam's node, or a contact multiplier's row)."""
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
    def at(s: float) -> np.ndarray:
        A.copy(Y)
        Y.axpy(s, d)
        if problem.contact is not None:
            problem.contact.allow_update = False          # the status held
        problem.residual(None, Y, F)
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
    return Jump(size=size, scale=scale, where=_where(problem, np.abs(f_hi - f_lo), comm))


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
    return (f"; the residual jumps by {jump.size:.3g} N (max |F| {jump.scale:.3g} N along the step) "
            f"between two states of Newton's last steps closer than 1e-13 of a step, at {jump.where}: "
            "a discontinuity of the discrete model, not a limit point (please report it with the config)")
