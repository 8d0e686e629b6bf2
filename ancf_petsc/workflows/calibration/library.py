"""Warm starts: the converged states of solved parameter sets, and a start for a new one.

For a parameter set u the library takes the nearest solved set a and, when others lie around it,
the affine prediction of every level's state from them: x(u) ≈ x_a + Σ_j c_j (x_j − x_a) with c the
least-squares (minimum-norm) solution of Σ_j c_j (u_j − u_a) = u − u_a.  Right after a
finite-difference Jacobian (the set and its n neighbours one step along each axis) this is the
linear interpolation (a first-order Taylor step) of the states in every direction, so a
trust-region step of a few per cent starts within O(step²) of its solution instead of O(step).
Beyond ``AFFINE_DISTANCE`` from the nearest set, or where u lies outside the neighbours' span and
the nearest set is beyond ``NEAREST_DISTANCE``, the sample is solved cold (load stepping from the
reference): from far away, Newton from another equilibrium costs more than the load path
(Achilles column, μ of all three subtendons changed together, Newton iterations for 13 levels:
cold 47; nearest state 35 at +1 %, 53 at +10 %; affine prediction from a finite-difference cloud
20 at +1 %, 33 at +10 %, 41 at +20 %).

Only completed samples with every level are kept; the library is the same on every rank (it is
updated from the gathered results after each batch), so a sample's start depends only on the
samples solved before its batch, not on the rank that solves it.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

#: farthest (in u: log10 p, or p / scale) the nearest state alone is used from
NEAREST_DISTANCE = 0.03
#: farthest an affine prediction is used from (0.1 in log10: a factor 1.26)
AFFINE_DISTANCE = 0.1
#: states kept (the oldest are dropped first)
CAPACITY = 64


class StateLibrary:
    """Solved parameter sets (u) and their level states (module docstring)."""

    def __init__(self, capacity: int = CAPACITY, neighbours: int | None = None):
        self.capacity = capacity
        self.neighbours = neighbours            # sets an affine prediction uses (default 2 n)
        self.us: list[np.ndarray] = []
        self.states: list[list] = []              # per set: solving.samples.LevelState per level

    def __len__(self) -> int:
        return len(self.us)

    def add(self, u: np.ndarray, states: list) -> None:
        self.us.append(np.asarray(u, dtype=float))
        self.states.append(states)
        if len(self.us) > self.capacity:
            del self.us[0], self.states[0]

    def start_for(self, u: np.ndarray) -> tuple[list | None, str]:
        """A start state per level for ``u`` (None: solve cold) and how it was made
        (``cold``, ``nearest``, ``affine``)."""
        if not self.us:
            return None, "cold"
        U = np.array(self.us)
        d = np.linalg.norm(U - u, axis=1)
        a = int(np.argmin(d))
        if d[a] > AFFINE_DISTANCE:
            return None, "cold"
        m = self.neighbours or 2 * len(u)
        others = [j for j in np.argsort(d) if j != a][:m]
        c = None
        if others and d[a] > 0.0:
            dU = (U[others] - U[a]).T                       # (n, m)
            c, *_ = np.linalg.lstsq(dU, u - U[a], rcond=1e-10)
            if not np.allclose(dU @ c, u - U[a], rtol=1e-6, atol=1e-12 * max(1.0, d[a])):
                c = None                                    # u outside their span
        if c is None:
            return (self.states[a], "nearest") if d[a] <= NEAREST_DISTANCE else (None, "cold")
        return [self._predict(k, a, others, c) for k in range(len(self.states[a]))], "affine"

    def _predict(self, k: int, a: int, others: list[int], c: np.ndarray):
        """Level k's affine prediction; the contact state is the nearest set's."""
        base = self.states[a][k]
        x = base.x.copy()
        for j, cj in zip(others, c):
            x += cj * (self.states[j][k].x - base.x)
        return replace(base, x=x)
