"""Discretisation variants, Richardson extrapolation and the refinement ladder (``accuracy:``).

A *discretisation* is the part of a config that sets how finely a model is resolved: elements
per beam, axial Gauss points, section cubature degree and element type.  ``apply`` writes one
into a raw config (every beam alike; a ``bundle:`` block is set once).  ``richardson`` estimates
the limit of a quantity from three solutions on meshes refined by a factor 2; ``choose``
applies it to a ladder of solutions to find the coarsest one within a relative tolerance.
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass

from ..io.levels import step_at

COMPONENTS = ("x", "y", "z", "norm")


@dataclass(frozen=True)
class Discretisation:
    """None keeps the config's own value."""
    elements: int | None = None
    axial_points: int | None = None
    cubature_degree: int | None = None
    element: str | None = None

    def label(self) -> str:
        parts = [self.element and f"{self.element}", self.elements and f"{self.elements} el",
                 self.axial_points and f"{self.axial_points} ax", self.cubature_degree and f"deg {self.cubature_degree}"]
        return ", ".join(p for p in parts if p)


def apply(raw: dict, d: Discretisation) -> dict:
    """A copy of ``raw`` with the discretisation ``d`` set on every beam (or the bundle)."""
    out = copy.deepcopy(raw)
    if "bundle" in out:
        b = out["bundle"]
        for key, val in (("elements", d.elements), ("axial_points", d.axial_points),
                         ("cubature_degree", d.cubature_degree), ("element", d.element)):
            if val is not None:
                b[key] = val
        return out
    for beam in out["beams"]:
        if d.elements is not None:
            beam["elements"] = d.elements
        if d.axial_points is not None:
            beam["axial_points"] = d.axial_points
        if d.cubature_degree is not None:
            beam["section"]["cubature_degree"] = d.cubature_degree
        if d.element is not None:
            beam["element"] = d.element
    return out


def level_step(summary: dict, level: float | None = None) -> dict | None:
    """The converged step at ``level`` (``io.levels.step_at``: also a level passed over in a gap
    of the load path), or the last one; None when there is none."""
    steps = summary["steps"]
    return step_at(steps, level) if level is not None else (steps[-1] if steps else None)


def quantity(summary: dict, probe: str, component: str = "norm", level: float | None = None) -> float:
    """The probe's displacement component (or its norm) at ``level`` (default: the last step; a
    level passed over in a gap of the load path at the load factor it was reported at)."""
    step = level_step(summary, level)
    if step is None:
        return math.nan
    u = step["probes"][probe]["displacement"]
    return math.sqrt(sum(c * c for c in u)) if component == "norm" else u["xyz".index(component)]


@dataclass
class Extrapolation:
    limit: float          # estimated converged value
    order: float          # observed order p (nan: no monotone convergence seen)
    reliable: bool        # monotone convergence with p > 0.5, all three equal, or a plateau
    kind: str = "richardson"   # richardson | constant | plateau (see ``choose``)


def richardson(q1: float, q2: float, q3: float, ratio: float = 2.0, tiny: float = 1e-12) -> Extrapolation:
    """Limit of q(h) from q(h), q(h/r), q(h/r²): q∞ = q3 + (q3 − q2)/(r^p − 1), p from the
    ratio of successive differences.  Oscillating or diverging sequences are flagged unreliable
    (limit = q3)."""
    d1, d2 = q2 - q1, q3 - q2
    scale = max(abs(q1), abs(q2), abs(q3), 1e-300)
    if abs(d1) <= tiny * scale and abs(d2) <= tiny * scale:
        return Extrapolation(q3, math.inf, True, "constant")
    if abs(d2) <= tiny * scale or d1 * d2 <= 0.0 or abs(d1) <= abs(d2):
        return Extrapolation(q3, math.nan, False)
    p = math.log(abs(d1 / d2)) / math.log(ratio)
    return Extrapolation(q3 + d2 / (ratio ** p - 1.0), p, p > 0.5)


def choose(values: list[float], rtol: float) -> tuple[int | None, list[float], Extrapolation | None]:
    """Coarsest rung of a ladder (values on meshes refined by 2) within ``rtol`` of the
    Richardson limit of the last three finite rungs.  Returns (index or None, estimated relative
    errors per rung (nan where unknown), the extrapolation).

    A *plateau* counts too: when the last three rungs no longer converge monotonically but all
    lie within rtol/2 of their mean, they have converged to within the tolerance (what is left
    is the noise of the discretisation, e.g. of reduced integration), and the mean is the limit.
    """
    ok = [i for i, v in enumerate(values) if math.isfinite(v)]
    if len(ok) < 3 or ok[-3:] != list(range(ok[-1] - 2, ok[-1] + 1)):
        return None, [math.nan] * len(values), None
    i3 = ok[-1]
    last = values[i3 - 2:i3 + 1]
    ex = richardson(*last)
    if not ex.reliable:
        mean = sum(last) / 3.0
        if mean != 0.0 and max(abs(v - mean) for v in last) <= 0.5 * rtol * abs(mean):
            ex = Extrapolation(mean, math.nan, True, "plateau")
        else:
            return None, [math.nan] * len(values), ex
    scale = abs(ex.limit) or max(abs(v) for v in last)     # a limit 0 (a held component): the rungs' size
    errs = [math.nan if not math.isfinite(v) else abs(v - ex.limit) / scale if scale else
            (0.0 if v == ex.limit else math.inf) for v in values]
    for i, e in enumerate(errs):
        if i >= i3 - 2 and e <= rtol:       # trust the estimate only on the rungs it was fitted to
            return i, errs, ex
    return None, errs, ex
