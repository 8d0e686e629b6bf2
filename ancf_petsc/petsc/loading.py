"""The loads and prescribed displacements of a Problem, by load group (model/loading.py), as
PETSc vectors: f_ext(λ) = Σ_g m_g(λ) f_g and q̄(λ) = q̄₀ + Σ_g m_g(λ) ū_g at the held DOFs."""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc



def held_dofs(model, layout, contact=None) -> tuple[np.ndarray, np.ndarray]:
    """The held DOFs (supports, and the unused multiplier slots): a mask over every PETSc DOF and
    the sorted positions of this rank's own in its owned array."""
    lo, hi = layout.owned_nodes
    held = model.fixed_dofs if contact is None else np.concatenate([model.fixed_dofs, contact.padding_dofs()])
    fixed = layout.petsc_dofs(held)
    D = model.dofs_per_node
    mask = np.zeros(D * layout.n_blocks, dtype=bool)
    mask[fixed] = True
    owned = np.sort(fixed[(fixed >= D * lo) & (fixed < D * hi)])
    return mask, owned - D * lo


def every_block(model, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Model-ordered arrays over all ``n`` DOFs (multiplier blocks after the nodes, zero): the
    reference state, and per load group its forces and prescribed displacements (multiplier 1)."""
    q0 = np.zeros(n)
    q0[:model.n_dofs] = model.q0.reshape(-1)
    forces, moved = np.zeros((len(model.loading), n)), np.zeros((len(model.loading), n))
    for k, g in enumerate(model.loading):
        forces[k, :model.n_dofs], moved[k, :model.n_dofs] = g.forces, g.moves
    return q0, forces, moved


class AppliedLoads:
    """Forces f_g and prescribed displacements ū_g of every load group (multiplier 1, global
    vectors) and the reference state q̄₀; ``groups`` the model's LoadGroups."""

    def __init__(self, groups: list, forces: list[PETSc.Vec], moves: list[PETSc.Vec], q0: PETSc.Vec):
        self.groups, self.forces, self.moves, self.q0 = groups, forces, moves, q0
        #: the groups with a force or a prescribed displacement (collective: global norms)
        self.acting = np.array([f.norm() > 0.0 or u.norm() > 0.0 for f, u in zip(forces, moves)], dtype=bool)

    def multipliers(self, lam: float) -> np.ndarray:
        """m_g(λ) of every group."""
        return np.array([g.multiplier(lam) for g in self.groups])

    def unchanged(self, lam0: float, lam1: float) -> bool:
        """Whether every load and prescribed displacement is the same at λ₁ as at λ₀ (a load
        history's frames that repeat their forces, e.g. a stride's swing)."""
        return bool(np.array_equal(self.multipliers(lam0)[self.acting], self.multipliers(lam1)[self.acting]))

    def subtract(self, F: PETSc.Vec, lam: float) -> None:
        """F −= f_ext(λ)."""
        for m, f in zip(self.multipliers(lam), self.forces):
            F.axpy(-m, f)

    def work(self, X: PETSc.Vec, lam: float) -> float:
        """f_ext(λ)·X (collective)."""
        return sum(m * f.dot(X) for m, f in zip(self.multipliers(lam), self.forces))

    def held_values(self, lam: float) -> np.ndarray:
        """q̄(λ) of the owned DOFs (meaningful at the held ones)."""
        out = self.q0.getArray(readonly=True).copy()
        for m, u in zip(self.multipliers(lam), self.moves):
            out += m * u.getArray(readonly=True)
        return out

    def scale(self, max_level: float) -> float:
        """Σ_g max |m_g| ‖f_g‖ over load factors 0 … ``max_level`` (curve points included):
        the size of the loads (collective)."""
        out = 0.0
        for g, f in zip(self.groups, self.forces):
            lams = [0.0, max_level] + ([p[0] for p in g.curve.points if p[0] < max_level] if g.curve else [])
            out += max(abs(g.multiplier(x)) for x in lams) * f.norm()
        return out

    def destroy(self) -> None:
        for v in self.forces + self.moves:
            v.destroy()
