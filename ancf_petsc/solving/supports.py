"""Rigid-body motions the supports and the sliding contact leave free (checked before solving).

A model in which some beam, or some group of beams tied only by frictionless contact, can move
as a rigid body has no unique equilibrium: Newton wanders or fails "at load factor 0.0002".
Here the six rigid modes of every beam (translations of r; an infinitesimal rotation ω× acting
on all six nodal vectors) are tested against the constraints at the reference state: the held
DOFs (their rows of the Jacobian are unit rows) and the contact constraints (their rows are the
constraint gradients), both read off J·v at zero load.  Rigid modes give no strain, so J·v is
exactly the constraint violation of v; combinations of modes with J·v = 0 (the null space of the
Gram matrix of J·R) are the free motions.  Unilateral contact is counted as holding (it stops a
beam from moving into its neighbour, not from lifting off).
"""
from __future__ import annotations

import numpy as np

from ..physics.element3363 import DOFS_PER_NODE
from ..physics.rigid import rigid_modes

#: a combination of unit modes is free when its constraint violation (held DOFs in metres or
#: slope units, contact rows divided by k_s) is below this.  Measured: a supported beam ≈ 0.33;
#: a strand held only by sliding contact in a twisted hexagonal bundle: its screw motion 5e-8
#: (the interpolated helicoid is nearly screw-symmetric), the next mode 3.6e-3
FREE_TOLERANCE = 1e-4
AXES = ("x", "y", "z")


def _modes(problem) -> tuple[np.ndarray, list[tuple[str, str, int]]]:
    """Local rows (owned DOFs) of the unit rigid modes of every beam: (n_local, 6 n_beams), and
    (beam, kind, axis) per column."""
    P = problem
    lo, hi = P.layout.owned_nodes
    model_block = np.argsort(P.layout.perm)[lo:hi]
    x = P.q0.getArray(readonly=True).reshape(-1, 6, 3)
    cols, labels = [], []
    for beam in P.model.beams:
        mine = ((model_block >= beam.node_offset)
                & (model_block < beam.node_offset + beam.n_nodes))[:, None, None]
        for m, v in enumerate(rigid_modes(x)):
            cols.append((v * mine).ravel())
            labels.append((beam.name, "translation" if m < 3 else "rotation", m % 3))
    return np.array(cols).T, labels


def free_rigid_motions(problem) -> list[str]:
    """Descriptions of the rigid motions nothing holds (collective; empty when supported)."""
    P = problem
    comm = P.comm.tompi4py()
    R, labels = _modes(P)
    norms = np.sqrt(comm.allreduce(np.sum(R * R, axis=0)))
    R = R / np.where(norms > 0, norms, 1.0)
    P.load_factor = 0.0
    X = P.q0.copy()
    P.residual(None, X, P.F)                 # the contact projections of the reference state
    P.jacobian(None, X, P.J, P.J)
    lo, hi = P.layout.owned_nodes
    held = P.fixed_mask[DOFS_PER_NODE * lo:DOFS_PER_NODE * hi]
    constraint = np.repeat(~P.owned_physical, DOFS_PER_NODE) & ~held
    scale = np.where(held, 1.0, 0.0) + np.where(constraint, 1.0 / (P.contact.stiffness if P.contact else 1.0), 0.0)
    v, y = X.duplicate(), X.duplicate()
    Y = np.empty_like(R)
    for j in range(R.shape[1]):
        v.setArray(R[:, j])
        P.J.mult(v, y)
        Y[:, j] = y.getArray(readonly=True) * scale       # rigid modes: no strain, only these rows
    for obj in (X, v, y):
        obj.destroy()
    gram = comm.allreduce(Y.T @ Y)
    w, V = np.linalg.eigh(gram)
    free = w <= FREE_TOLERANCE ** 2
    return _summary([_describe(V[:, i], labels) for i in np.flatnonzero(free)])


def _summary(motions: list[tuple[tuple[str, ...], str]]) -> list[str]:
    """One entry per group of beams: 'bar (free: translation along x, rotation about z)'."""
    groups: dict[tuple[str, ...], list[str]] = {}
    for beams, motion in motions:
        groups.setdefault(beams, []).append(motion)
    return [f"{' + '.join(beams)} (free: {', '.join(m)})" for beams, m in groups.items()]


def _describe(c: np.ndarray, labels: list) -> tuple[tuple[str, ...], str]:
    """(the beams that move, 'translation along x with rotation about x') of a null vector."""
    beams: dict[str, np.ndarray] = {}
    for coef, (name, kind, k) in zip(c, labels):
        beams.setdefault(name, np.zeros(6))[(3 if kind == "rotation" else 0) + k] = coef
    biggest = max(np.linalg.norm(b) for b in beams.values())
    moving = [name for name, b in beams.items() if np.linalg.norm(b) >= 0.2 * biggest]
    total = sum(beams[name] for name in moving)
    t, w = total[:3], total[3:]
    motion = []
    if np.linalg.norm(t) > 0.05 * np.linalg.norm(total):
        motion.append("translation along " + _direction(t))
    if np.linalg.norm(w) > 0.05 * np.linalg.norm(total):
        motion.append("rotation about " + _direction(w))
    return tuple(moving), " with ".join(motion) or "a rigid motion"


def _direction(d: np.ndarray) -> str:
    d = d / np.linalg.norm(d)
    k = int(np.argmax(np.abs(d)))
    if abs(d[k]) > 0.99:
        return AXES[k]
    return "(" + ", ".join(f"{x:+.2f}" for x in d) + ")"
