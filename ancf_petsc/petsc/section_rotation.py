"""A Newton step that turns the sections instead of shearing them (``solver.section_update``).

Newton's step adds δ to the nodal vectors.  Where a section turns by ω, its direction vectors
r_y, r_z change by ω × r_y, ω × r_z to first order, and the straight update r + ω × r stretches
them by |ω|²/2: the nearly incompressible section (κ = 0.86 GPa on the paper's tendon) then
carries a spurious volume change of second order, which the next iterate has to remove.  This is
part of the slow second step of the walking stride's loading frames (|F| 2.8 → 1.4e-2 → 5.0e-6 →
4.0e-8 N while the sections turn by ~3e-4 rad, docs/gait.md).

With ``rotation`` each beam node's step is split into the rotation ω that best explains its
director steps (least squares, ``director_rotation``) and the rest, and the directors and the
section's higher vectors are turned by the exact rotation R(ω) instead of I + [ω]×:

    r_k ← R(ω) r_k + (δ_k − ω × r_k)    (k = r_y, r_z, r_yy, r_yz, r_zz),

i.e. δ_k plus the second-order part R(ω) r_k − r_k − ω × r_k.  The update agrees with Newton's to
first order, so the iteration keeps its quadratic convergence, and it is exact for a rigid turn
of a section.  It is applied where it is a small correction of a step in Newton's asymptotic
regime: turned steps are held to direction-vector changes of ``step_limits.MAX_STEP_TURN`` (0.1,
about the turn in radians), and a step is turned when no node turns by more than
``ROTATION_MAX`` (the correction is then under |ω|/2 = 10 % of the step); a larger fit is
taken as it is (one that explains the director steps poorly: before the turn limit, on the
traced subject at 90° a 2500 N increment's first steps fitted turns of up to 3 rad, and turning
them cost two cut-backs; the gate was 0.05 rad, which left the soft GOH sets' 0.08–0.1 rad
steps of their first levels unturned, docs/gait.md, thirty-fourth session).  Nodes with a held
director component keep the plain step (a turn would move it), and held higher vectors (3333's)
keep theirs.  Each rank
updates its own nodes from their own values only: the update is the same on any number of ranks.

Only whole steps are turned (``StepLimits.configure``: the line search ``basic``): a line
search's step λ·Y would scale the second-order part by λ instead of λ².  A fibre model's load
predictions (the tangent predictor's step, the complementarity predictor's) are turned by the
same update (``StepLimits.turned``).

The default for a model with a fibre-reinforced law (config/parse.py ``default_section_update``):
the director stretch |ω|²/2 of a linear turn meets the fibres' exponential stiffness (the soft
sets' first levels rose by 0.1–1 N every other iteration).  Not for the others (``linear``): on
the neo-Hookean gait envelope without friction (gate 0.05, no turn limit) it cut the Newton
iterations of the columns at ψ ≤ 90° to 0.82–0.86 (median) but moved the strongly twisted
unilateral columns and strides both ways, and the failing cells over the grids rose from 32 to
36 (docs/running.md, "Newton steps that turn the sections").
"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI
from scipy.spatial.transform import Rotation

#: largest turn [rad] of any node for which a Newton step is turned (module docstring)
ROTATION_MAX = 0.2


def director_rotation(directors: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """ω (n, 3) minimising Σ_k |ω × a_k − b_k|² over the directors a_k (n, 2, 3) and their
    steps b_k (n, 2, 3): (Σ_k |a_k|² I − a_k a_kᵀ) ω = Σ_k a_k × b_k."""
    a, b = directors, steps
    G = np.matmul(a.transpose(0, 2, 1), a)                          # Σ_k a_k a_kᵀ
    M = np.trace(G, axis1=1, axis2=2)[:, None, None] * np.eye(3) - G
    return np.linalg.solve(M, np.cross(a, b).sum(axis=1)[:, :, None])[:, :, 0]


def second_order_part(omega: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """R(ω) v − v − ω × v (n, m, 3) of the vectors v (n, m, 3) of each node."""
    K = np.zeros((len(omega), 3, 3))                                # ω × v = K v
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -omega[:, 2], omega[:, 1], -omega[:, 0]
    K -= K.transpose(0, 2, 1)
    part = Rotation.from_rotvec(omega).as_matrix() - np.eye(3) - K
    return np.matmul(vectors, part.transpose(0, 2, 1))


class SectionTurns:
    """The turned Newton steps of ``problem``'s beam nodes whose directors are free (its held
    DOFs are fixed for the run): ``__call__(X, Y)`` changes the step Y (the update is X − Y) as
    the module docstring says and returns whether it did; collective."""

    def __init__(self, problem):
        V, D = problem.model.block.vectors_per_node, problem.model.dofs_per_node
        lo, hi = problem.layout.owned_nodes
        held = problem.fixed_mask[D * lo:D * hi].reshape(-1, V, 3)
        self.nodes = np.flatnonzero(problem.owned_physical & ~held[:, 1:3].any(axis=(1, 2)))
        self.free = ~held[self.nodes, 1:]          # held higher vectors (3333's) keep the plain step
        self.vectors = V
        self.comm = problem.comm.tompi4py()

    def __call__(self, X, Y) -> bool:
        nodes, V = self.nodes, self.vectors
        x = X.getArray(readonly=True).reshape(-1, V, 3)[nodes]
        y = Y.getArray().reshape(-1, V, 3)
        step = -y[nodes]
        turn, omega = np.inf, None
        if np.all(np.isfinite(step)):
            omega = director_rotation(x[:, 1:3], step[:, 1:3])
            turn = float(np.sqrt(np.max(np.einsum("ni,ni->n", omega, omega), initial=0.0)))
        if self.comm.allreduce(turn, op=MPI.MAX) > ROTATION_MAX or len(nodes) == 0:
            return False
        y[nodes, 1:] -= second_order_part(omega, x[:, 1:]) * self.free
        return True
