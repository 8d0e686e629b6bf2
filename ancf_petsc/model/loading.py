"""How the loads and prescribed displacements follow the load factor λ.

By default a load (force, end traction) or a prescribed displacement is its config value times λ.
A ``curve`` [[λ₀, m₀], [λ₁, m₁], ...] makes it the value times m(λ), piecewise linear through
those points: a preload held while another load grows, or a displacement that goes out and back
(loading and unloading of a path-dependent interface: Coulomb friction)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class LoadCurve:
    """m(λ), piecewise linear through ``points`` ((λ, m) with λ increasing)."""
    points: tuple[tuple[float, float], ...]
    # the points as arrays, made once: a stride's curves have ~100 points and are read a few
    # times per residual (zip and conversion were 20 µs a call, 2.5 % of the walking stride's solve)
    _lams: np.ndarray = field(init=False, repr=False, compare=False)
    _values: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        lams, values = zip(*self.points)
        object.__setattr__(self, "_lams", np.asarray(lams, dtype=float))
        object.__setattr__(self, "_values", np.asarray(values, dtype=float))

    def __call__(self, lam: float) -> float:
        return float(np.interp(lam, self._lams, self._values))


@dataclass
class LoadGroup:
    """Loads and prescribed displacements that follow one curve (None: λ itself): generalised
    forces (n_dofs,) and displacements of held DOFs (n_dofs,) at multiplier 1."""
    curve: LoadCurve | None
    forces: np.ndarray
    moves: np.ndarray

    def multiplier(self, lam: float) -> float:
        return float(lam) if self.curve is None else self.curve(lam)


def group_for(groups: list[LoadGroup], curve: LoadCurve | None, n_dofs: int) -> LoadGroup:
    """The group of ``curve`` in ``groups``, added (with zero forces and moves) when new."""
    for g in groups:
        if g.curve == curve:
            return g
    groups.append(LoadGroup(curve, np.zeros(n_dofs), np.zeros(n_dofs)))
    return groups[-1]
