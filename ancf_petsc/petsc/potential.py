"""The total potential of a Problem (without contact multipliers; at a converged contact state,
``constrained_potential``), the rounding floor of its
residual, and the rigid-body modes of its reference configuration (the Jacobian's near null
space)."""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from ..physics import kernels
from ..physics.rigid import rigid_modes
from ..linalg import logging


def total_potential(problem, X: PETSc.Vec) -> float:
    """Π = Σ ∫Ψ dV − f_ext(λ)·q (the residual is its gradient), +inf when an element is inverted;
    the same on every rank (collective).  Not defined with contact: the residual is then the
    gradient of a Lagrangian, whose stationary point is a saddle (``Problem.has_potential``)."""
    if not problem.has_potential:
        raise RuntimeError("no potential with contact multipliers; use the residual merit")
    return constrained_potential(problem, X)


def constrained_potential(problem, X: PETSc.Vec) -> float:
    """Π at X without the contact multipliers' term: with a frictionless law, the Lagrangian's
    value at a converged state (its gaps closed or its multipliers zero), which compares two
    equilibria at one load (solving/branch_switch.py); collective."""
    logging.stage(logging.ASSEMBLY).push()
    try:
        def local_energy(xl):
            local = 0.0
            for blk in problem.blocks:
                qe = blk.element_vectors(xl)
                local += sum(float(np.sum(kernels.energy(qe, G, w, material)))
                             for G, w, material in blk.parts)
            return local
        total = problem.comm.tompi4py().allreduce(problem.exchange.evaluate(X, local_energy))
        total -= problem.loads.work(X, problem.load_factor)
        return total if np.isfinite(total) else np.inf
    finally:
        logging.stage(logging.ASSEMBLY).pop()


def rounding_floor(problem) -> float:
    """‖F(q0, λ = 0)‖: zero in exact arithmetic, so it measures the residual's rounding floor
    (collective)."""
    lam = problem.load_factor
    problem.load_factor = 0.0
    X, F = problem.q0.copy(), problem.F.duplicate()
    problem.residual(None, X, F)
    problem.load_factor = lam
    value = F.norm()
    X.destroy()
    F.destroy()
    return value


def rigid_body_modes(problem) -> list[PETSc.Vec]:
    """Orthonormal rigid-body modes of the reference configuration (``physics.rigid``), given to
    the Jacobian as its near null space (used by GAMG, ignored by LU); collective."""
    x = problem.q0.getArray(readonly=True).reshape(-1, problem.model.block.vectors_per_node, 3)
    out = []
    for v in rigid_modes(x):                # modified Gram-Schmidt (collective dots)
        w = problem.X.duplicate()
        w.setArray((v * problem.owned_physical[:, None, None]).ravel())
        for u in out:
            w.axpy(-w.dot(u), u)
        w.scale(1.0 / w.norm())
        out.append(w)
    return out


def set_near_null_space(problem) -> None:
    """Give the problem's Jacobian its rigid-body modes as near null space."""
    modes = rigid_body_modes(problem)
    null_space = PETSc.NullSpace().create(vectors=modes, comm=problem.comm)
    problem.J.setNearNullSpace(null_space)
    for obj in modes + [null_space]:        # J keeps its own reference
        obj.destroy()
