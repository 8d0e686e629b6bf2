"""Which linear solver a run uses (``solver.linear``): one LDLᵀ factorisation of the whole
Jacobian (``direct``, MUMPS) or the fascicle-parallel Schur solver (``fieldsplit``,
linalg/fieldsplit.py), and the rule ``auto`` follows (docs/parallel.md, "Which solver").
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..physics.rigid import rigid_modes
from .database import option

#: ``solver.linear: auto`` takes the fascicle Schur solver from this many contact multipliers
#: on; below, one LDLᵀ of the whole Jacobian is as fast (scripts/bench_growth.py: 7 fascicles,
#: 792 multipliers, direct 0.11 s vs fieldsplit 0.14 s per Newton iteration; 19 fascicles,
#: 2 772 multipliers, 0.94 s vs 0.40 s; log-log crossing at ~1 040 multipliers)
AUTO_MIN_MULTIPLIERS = 1000


def not_self_supported(model) -> list[str]:
    """Names of the beams whose own supports leave a rigid-body motion free (their K_f is then
    singular without the neighbours): the six rigid modes of the reference configuration,
    restricted to the beam's held DOFs, must have rank 6."""
    D = model.dofs_per_node
    fixed = np.zeros(D * model.n_nodes, dtype=bool)
    fixed[model.fixed_dofs] = True
    free = []
    for beam in model.beams:
        nodes = beam.node_offset + np.arange(beam.n_nodes)
        dofs = (D * nodes[:, None] + np.arange(D)).ravel()
        R = np.stack([m.reshape(-1) for m in rigid_modes(model.q0[nodes])], axis=1)[fixed[dofs]]
        scale = np.abs(R).max(axis=0, initial=0.0)
        if len(R) < 6 or np.linalg.matrix_rank(R / np.where(scale > 0, scale, 1.0), tol=1e-8) < 6:
            free.append(beam.name)
    return free


def _why_not_fieldsplit(model, contact, petsc_options: dict, prefix: str) -> str | None:
    """Why the fascicle Schur solver cannot run on this model (None: it can)."""
    chosen = [k for k in ("pc_type", "ksp_type") if option(k, prefix) is not None or k in petsc_options]
    if contact is None or contact.n_multipliers == 0:
        return "it needs contact multipliers (the fascicles' coupling)"
    if not contact.symmetric:
        return ("its factorisations are LDLᵀ, and the Jacobian is unsymmetric (friction of "
                "contact.tangential)")
    if len(model.beams) < 2:
        return "it needs at least two beams"
    if chosen:
        return f"the PETSc options choose the solver (-{prefix}{chosen[0]})"
    free = not_self_supported(model)
    if free:
        return f"beam {free[0]} is not held by its own supports (its stiffness alone is singular)"
    return None


def choose(choice: str, model, contact, petsc_options: dict, prefix: str = "") -> tuple[str, str]:
    """The linear solver for ``solver.linear`` = ``choice`` (auto | direct | fieldsplit) and why:
    ('direct' | 'fieldsplit', reason).  ``fieldsplit`` needs contact multipliers between at
    least two beams, each held by its own supports, and no PC/KSP chosen through PETSc options;
    ``auto`` takes it from ``AUTO_MIN_MULTIPLIERS`` multipliers on, unless a tangential law
    couples the beams' displacements directly (the elastic matrix: a K_× that is not small).
    Raises InputError when ``fieldsplit`` is asked for and cannot run (the same on every rank)."""
    if choice == "direct":
        return "direct", "solver.linear: direct"
    why_not = _why_not_fieldsplit(model, contact, petsc_options, prefix)
    if choice == "fieldsplit":
        if why_not:
            raise InputError("solver.linear", f"fieldsplit cannot run here: {why_not}; use direct or auto")
        return "fieldsplit", "solver.linear: fieldsplit"
    if why_not:
        return "direct", f"auto: direct, fieldsplit not possible: {why_not}"
    coupling = [t.describe() for t in contact.terms if t.couples_beams]
    if coupling:
        return "direct", (f"auto: direct, the {coupling[0]} ties the fascicles to each other outside "
                          "their blocks (fieldsplit leaves that to FGMRES, which fails on a stiff matrix)")
    m = contact.n_multipliers
    if m < AUTO_MIN_MULTIPLIERS:
        return "direct", f"auto: {m} contact multipliers < {AUTO_MIN_MULTIPLIERS}"
    return "fieldsplit", f"auto: {m} contact multipliers >= {AUTO_MIN_MULTIPLIERS}"
