"""Reactions of the supports: the force each boundary condition puts on the held components of
r, read from the internal and contact forces at its held DOFs (loads on held components are
refused by the model), and its moment about the support node's section centroid, from the
generalised reactions on every held nodal vector (r, r_y, r_z, r_yy, r_zz, r_yz)."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from petsc4py import PETSc


class SupportRows(NamedTuple):
    """A support's DOFs in this rank's owned array."""
    rows: np.ndarray      # positions of its held components of r
    comp: np.ndarray      # their components (0, 1, 2)
    block: np.ndarray     # positions of its node's whole block (D,); empty on other ranks
    held: np.ndarray      # (D,) bool: the block's DOFs the support holds


def support_rows(model, layout) -> list[SupportRows]:
    """Per support (model.supports): where its held DOFs and its node's block are in this
    rank's owned array (a node's block is owned whole by one rank)."""
    lo, hi = layout.owned_nodes
    D = model.dofs_per_node
    out = []
    for sup in model.supports:
        r = sup.dofs[(sup.dofs % D) < 3]
        p = layout.petsc_dofs(r) - D * lo
        mine = (p >= 0) & (p < D * (hi - lo))
        block = layout.petsc_dofs(D * sup.node + np.arange(D)) - D * lo
        held = np.zeros(D, dtype=bool)
        held[sup.dofs - D * sup.node] = True
        owned = block[0] >= 0 and block[0] < D * (hi - lo)
        out.append(SupportRows(p[mine], r[mine] % 3, block if owned else block[:0], held))
    return out


def centroid_moment(q: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Moment [N m] about the section centroid r = q_0 of generalised forces f (V, 3) on the
    nodal vectors q (V, 3): a rigid turn δθ moves every q_k by δθ × q_k, so M = Σ_k q_k × f_k
    about the origin and Σ_{k≥1} q_k × f_k about r."""
    return np.cross(q[1:], f[1:]).sum(axis=0)


def reaction_resultants(problem, X: PETSc.Vec) -> tuple[np.ndarray, np.ndarray]:
    """(forces, moments), each (supports, 3), at X, the same on every rank (collective): the
    force on r [N] and the moment about the support node's centroid [N m]."""
    F = problem.F.duplicate()
    floc = problem.local_forces(X)
    problem.exchange.add_to(floc, F)
    f = F.getArray(readonly=True)
    x = X.getArray(readonly=True)
    out = np.zeros((2, len(problem.support_rows), 3))
    for k, sr in enumerate(problem.support_rows):
        np.add.at(out[0, k], sr.comp, f[sr.rows])
        if len(sr.block):
            held = np.where(sr.held, f[sr.block], 0.0)
            out[1, k] = centroid_moment(x[sr.block].reshape(-1, 3), held.reshape(-1, 3))
    F.destroy()
    out = problem.comm.tompi4py().allreduce(out)
    return out[0], out[1]


def reactions(problem, X: PETSc.Vec) -> np.ndarray:
    """(supports, 3) forces at X, the same on every rank (collective)."""
    return reaction_resultants(problem, X)[0]


def reaction_entries(problem, X: PETSc.Vec) -> tuple[dict, np.ndarray]:
    """A level's ``reactions`` and ``reaction_moments`` entries ({support name: [x, y, z]}) and
    the forces (supports, 3) (collective)."""
    forces, moments = reaction_resultants(problem, X)
    names = [s.name for s in problem.model.supports]
    return {"reactions": dict(zip(names, forces.tolist())),
            "reaction_moments": dict(zip(names, moments.tolist()))}, forces
