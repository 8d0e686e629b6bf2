"""Limits on a Newton step before the line search takes it (SNES line-search pre-check): a step
that moves a node by more than a few section sizes is scaled down (a near-singular tangent gives
absurd steps; with contact the closest-point pairing holds only for steps small beside a
section), then halved until no Gauss point has det F below a floor (inverted elements)."""
from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from ..physics import kernels

#: largest node move of one Newton step, in section sizes; full Newton steps with contact are
#: held to fewer (solving/stepper.py): a step of several sections makes the closest-point pairing
#: meaningless (the paper's tendon in fixed steps of 100 N from rest wandered to |F| ~ 1e8 and
#: failed with 10)
MAX_STEP_SECTIONS = 10.0
MAX_STEP_SECTIONS_CONTACT = 2.0


def min_jacobian(problem, X: PETSc.Vec) -> float:
    """Smallest det F over every Gauss point of every rank (collective)."""
    xl = problem.exchange.local_state(X)
    local = np.inf
    for blk in problem.blocks:
        F = kernels.deformation_gradient(blk.element_vectors(xl), blk.G)
        local = min(local, float(np.min(np.linalg.det(F))))
    val = problem.comm.tompi4py().allreduce(local, op=MPI.MIN)
    return val if np.isfinite(val) else -np.inf


class StepLimits:
    """The pre-check of ``problem``'s Newton steps: at most ``sections`` section sizes per node,
    det F ≥ ``j_min`` (halved up to ``halvings`` times)."""

    def __init__(self, problem, j_min: float = 0.1, halvings: int = 12):
        self.problem, self.j_min, self.halvings = problem, j_min, halvings
        self.sections = MAX_STEP_SECTIONS
        self.size = min(np.sqrt(b.section.area) for b in problem.model.beams)

    def precheck(self, X: PETSc.Vec, Y: PETSc.Vec) -> bool:
        """Line-search pre-check (collective): scale the step X − Y down to ``sections``
        section sizes, then halve it until no Gauss point has det F below ``j_min``; if that
        fails, Y is filled with NaN so that SNES reports a domain failure and the load step is
        cut back.  Returns whether Y was changed."""
        P = self.problem
        y = Y.getArray(readonly=True).reshape(-1, 6, 3)[P.owned_physical]
        big = P.comm.tompi4py().allreduce(float(np.abs(y[:, 0]).max(initial=0.0)), op=MPI.MAX) / (
            self.sections * self.size)
        changed = False
        if big > 1.0:
            Y.scale(1.0 / big)
            changed = True
        trial = X.duplicate()
        try:
            for _ in range(self.halvings):
                X.copy(trial)
                trial.axpy(-1.0, Y)
                if min_jacobian(P, trial) >= self.j_min:
                    return changed
                Y.scale(0.5)
                changed = True
            Y.set(np.nan)
            return True
        finally:
            trial.destroy()
