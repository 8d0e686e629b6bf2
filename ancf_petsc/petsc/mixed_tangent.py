"""``solver.tangent: mixed``: element tangents whose initial-stress part takes the stress of the
strain linearised along the last Newton step (physics/mixed_point.py), at the iterates of one
SNES solve.

The first iterate of a solve (and every tangent formed outside a Newton solve: the stability
check's, the predictors', the supports') is the displacement model's own tangent; from the second
on, each element part keeps the previous iterate's F and adds the correction.  A tangent skipped
by a chord step (solving/chord.py) breaks the chain: the next one is the plain tangent again.  A
converged state's stability is read from its own plain tangent (``SNESSolver.factor_at``), not
from a corrected one.  After a failed sub-step the retries to the same level use the plain tangent
(``paused``, set and cleared by solving/stepper.py): the corrected iterates take another course,
not a safer one, and the plain tangent's is the default's."""
from __future__ import annotations

import numpy as np

from ..physics.kernels import deformation_gradient
from ..physics.mixed_point import initial_stress_correction


class MixedTangent:
    """The previous Newton iterate's deformation gradients per (block, part), and the step."""

    def __init__(self) -> None:
        self.iterate: tuple[int, int] | None = None    # (solve, Newton iteration) being assembled
        self.solves = 0
        self._previous: dict = {}                     # (block, part) → ((solve, it), F)
        #: the last tangent assembled was corrected: its inertia is not the state's own
        self.corrected = False
        #: the plain tangent for now (after a failed sub-step, until the level is reached)
        self.paused = False

    def start_solve(self) -> None:
        """A new SNES solve: its first tangent is the plain one."""
        self.solves += 1
        self._previous.clear()

    def correct(self, key: int, qe: np.ndarray, parts: list, K: np.ndarray) -> np.ndarray:
        """K (E, 3S, 3S) of block ``key`` at nodal vectors qe, corrected when the tangent is a
        Newton iterate's and the previous iterate's F is known."""
        if self.iterate is None or self.paused:
            self.corrected = False
            return K
        solve, it = self.iterate
        if key == 0:
            self.corrected = False
        for k, (G, w, material) in enumerate(parts):
            F = deformation_gradient(qe, G)
            prev = self._previous.get((key, k))
            self._previous[(key, k)] = (self.iterate, F)
            if prev is not None and prev[0] == (solve, it - 1) and prev[1].shape == F.shape:
                K = K + initial_stress_correction(F, prev[1], G, w, material)
                self.corrected = True
        return K


def mixed_tangent(kind: str) -> MixedTangent | None:
    """The holder for ``solver.tangent`` (None: the displacement model's tangent)."""
    return MixedTangent() if kind == "mixed" else None
