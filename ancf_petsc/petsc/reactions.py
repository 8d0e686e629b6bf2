"""Reactions of the supports: the force each boundary condition puts on the held components of
r, read from the internal and contact forces at its held DOFs (loads on held components are
refused by the model)."""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc



def support_rows(model, layout) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per support (model.supports): the positions in this rank's owned array of its held
    components of r, and their components (0, 1, 2)."""
    lo, hi = layout.owned_nodes
    out = []
    for sup in model.supports:
        D = model.dofs_per_node
        r = sup.dofs[(sup.dofs % D) < 3]
        p = layout.petsc_dofs(r) - D * lo
        mine = (p >= 0) & (p < D * (hi - lo))
        out.append((p[mine], r[mine] % 3))
    return out


def reactions(problem, X: PETSc.Vec) -> np.ndarray:
    """(supports, 3) at X, the same on every rank (collective)."""
    F = problem.F.duplicate()
    floc = problem.local_forces(X)
    problem.exchange.add_to(floc, F)
    f = F.getArray(readonly=True)
    out = np.zeros((len(problem.support_rows), 3))
    for k, (rows, comp) in enumerate(problem.support_rows):
        np.add.at(out[k], comp, f[rows])
    F.destroy()
    return problem.comm.tompi4py().allreduce(out)
