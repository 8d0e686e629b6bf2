"""The fitted parameters: config values by key path, their bounds and scale, and the optimiser's
coordinates u: log10 p for a log-scaled parameter, p / scale otherwise (scale: the start's size),
so that every coordinate moves by O(1) over its range and one finite-difference step suits all."""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from ..sweep.base import Token, format_key_path, set_key_path


def pow10(x: float) -> float:
    """10 ** x, inf beyond the largest float (no overflow warning: an undetermined parameter's
    interval reaches it)."""
    return math.inf if x > 308.25 else 10.0 ** float(x)


@dataclass
class Parameter:
    """One fitted parameter.  ``keys``: the config values it sets (one value at all of them, or,
    with ``factor``, a factor on each one's value in the model config, ``base``)."""
    name: str
    keys: list[tuple[Token, ...]]
    lower: float
    upper: float
    start: float
    log: bool = False
    factor: bool = False
    base: tuple[float, ...] = ()
    unit: str = ""

    @property
    def scale(self) -> float:
        """p per unit of u (linear parameters)."""
        return max(abs(self.start), abs(self.lower), abs(self.upper)) or 1.0

    def to_u(self, p: float) -> float:
        return math.log10(p) if self.log else p / self.scale

    def from_u(self, u: float) -> float:
        return pow10(u) if self.log else u * self.scale

    def fd_step_u(self, u: float, h: float) -> float:
        """The finite-difference step in u at u: h (log-scaled: relative in p), else h times the
        size of p (near 0: its smallest nonzero start or bound) in u, never h times the scale."""
        if self.log:
            return h
        typical = min((abs(v) for v in (self.start, self.lower, self.upper) if v), default=1.0)
        return h * max(abs(self.from_u(u)), typical) / self.scale

    @property
    def bounds_u(self) -> tuple[float, float]:
        return self.to_u(self.lower), self.to_u(self.upper)

    def dp_du(self, p: float) -> float:
        """dp/du at p (standard errors in p from those in u, to first order)."""
        return p * math.log(10.0) if self.log else self.scale

    def key_text(self) -> str:
        return ", ".join(format_key_path(k) for k in self.keys)

    def values_at(self, p: float) -> list[float]:
        """The config value at each key for the parameter value p."""
        return [b * p for b in self.base] if self.factor else [p] * len(self.keys)


def apply(raw: dict, params: list[Parameter], values) -> dict:
    """A copy of the model config with the parameters set to ``values`` (physical units)."""
    out = copy.deepcopy(raw)
    for par, p in zip(params, values):
        for key, v in zip(par.keys, par.values_at(float(p))):
            set_key_path(out, key, float(v))
    return out


def to_u(params: list[Parameter], values) -> np.ndarray:
    return np.array([par.to_u(float(p)) for par, p in zip(params, values)])


def from_u(params: list[Parameter], u) -> np.ndarray:
    return np.array([par.from_u(float(x)) for par, x in zip(params, u)])


def bounds_u(params: list[Parameter]) -> tuple[np.ndarray, np.ndarray]:
    lo, hi = zip(*(par.bounds_u for par in params))
    return np.array(lo), np.array(hi)


def describe(params: list[Parameter], values) -> str:
    """``name = value`` for each parameter (log)."""
    return ", ".join(f"{par.name} = {p:.6g}" for par, p in zip(params, values))
