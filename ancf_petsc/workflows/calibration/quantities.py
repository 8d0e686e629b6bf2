"""What a data set measures, as a function of the model's probes (the registry ``QUANTITIES``).

A quantity reads the displacements of probes of the model config (``probes:``) at the data's load
levels.  Each entry names the data-set keys it takes, checks them against the model config, says
which load levels it needs besides the data's own, and evaluates itself on a solved sample:

* ``probe``       a component (x, y, z or norm) of a probe's displacement [m]
* ``elongation``  the x-displacement of a probe (the paper's elongation: the subtendon's last node
                  moves along the tendon while its root is held), or the mean over ``probes`` [m]
* ``difference``  a component of ``probes[0]``'s displacement minus ``probes[1]``'s [m] (a
                  subtendon displacement difference, as speckle tracking measures it)
* ``stiffness``   the secant stiffness (F − F_lower) / (u − u_lower) of the elongation between the
                  load level ``lower`` (default 0, the reference) and the data's level [N/m]; F is the
                  load factor times ``force`` (N per unit load factor; default: the size of the
                  config's total load at that level, load curves included)

A new quantity is one entry here (a reaction force, say, once probes carry one).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .errors import CalibrationError, expect, number

COMPONENTS = {"x": 0, "y": 1, "z": 2}


def _probe_names(raw: dict) -> list[str]:
    return [p.get("name") for p in raw.get("probes", []) or [] if isinstance(p, dict)]


def _probe(name, where: str, raw: dict) -> str:
    names = _probe_names(raw)
    expect(name in names, where, f"no probe {name!r} in the model config (its probes: "
                                 f"{', '.join(map(str, names)) or 'none'}; add one under probes:)")
    return name


def _component(opts: dict, where: str, default: str) -> str:
    c = opts.get("component", default)
    expect(c in tuple(COMPONENTS) + ("norm",), f"{where}.component",
           f"must be x, y, z or norm; got {c!r}")
    return c


def _of(u: np.ndarray, component: str) -> np.ndarray:
    return np.linalg.norm(u, axis=1) if component == "norm" else u[:, COMPONENTS[component]]


def _probes(opts: dict, where: str, raw: dict, pair: bool = False) -> list[str]:
    """``probe: a`` or ``probes: [a, b, ...]``; with ``pair`` exactly ``probes: [a, b]``."""
    if not pair and "probe" in opts:
        expect("probes" not in opts, where, "give probe (one) or probes (a list), not both")
        return [_probe(opts["probe"], f"{where}.probe", raw)]
    names = opts.get("probes")
    expect(isinstance(names, list) and len(names) >= 1 and (not pair or len(names) == 2),
           f"{where}.probes", "expected probes: [a, b] (two probe names)" if pair
           else "missing: probe (a probe name) or probes (a list of them)")
    return [_probe(n, f"{where}.probes[{k}]", raw) for k, n in enumerate(names)]


def _model_loads(raw: dict, where: str) -> list:
    """The config's loads as [curve points or None (× λ), force at multiplier 1]; a load that
    reads a history column has no force per load factor (refused: give ``force``)."""
    out = []
    for i, ld in enumerate(raw.get("loads", []) or []):
        if isinstance(ld, dict):
            expect("column" not in ld, f"{where}.force", f"the model's loads[{i}] follows a history column: "
                   "its force is no function of the load factor alone; give force (N per load factor)")
            f = ld.get("force", ld.get("traction_force", [0, 0, 0]))
            out.append([ld.get("curve"), [float(x) for x in f]])
    return out


def load_at(loads: list, lam: float) -> float:
    """|Σ m(λ) F| of ``_model_loads`` at load factor λ (m = λ, or a load's curve through its points)."""
    total = np.zeros(3)
    for curve, f in loads:
        m = lam if curve is None else np.interp(lam, *np.asarray(curve, dtype=float).T)
        total += m * np.asarray(f)
    return float(np.linalg.norm(total))


@dataclass
class Quantity:
    name: str
    keys: tuple[str, ...]
    check: Callable            # (options, where, raw, levels, load_scale) -> options
    evaluate: Callable         # (options, displacements: probe -> (L, 3), rows, levels) -> (n,)
    unit: str = "m"

    def extra_levels(self, options: dict, levels: np.ndarray) -> list[float]:
        lower = options.get("lower", 0.0)
        return [lower] if lower > 0 and lower not in levels else []


def _at(disp: dict, names: list[str], rows: list[int]) -> np.ndarray:
    """(probes, n, 3) displacements at ``rows`` (NaN where a level was not reached)."""
    return np.stack([disp[n][rows] for n in names])


def _check_probe(o, where, raw, levels, scale):
    expect("probe" in o, f"{where}.probe", "missing: the probe (a name under the model's probes:)")
    return {"probes": _probes(o, where, raw), "component": _component(o, where, "norm")}


#: probe vectors that are positions (a displacement in m): ``elongation`` and ``stiffness`` read their x
POSITIONS = ("r", "mean")


def _positions(names: list[str], o: dict, where: str, raw: dict) -> list[str]:
    """``names``, each a probe of a position (``POSITIONS``), not of a direction vector's change."""
    vectors = {p.get("name"): p.get("vector", "r") for p in raw.get("probes", []) or [] if isinstance(p, dict)}
    for k, n in enumerate(names):
        key = f"{where}.probe" if "probe" in o else f"{where}.probes[{k}]"
        expect(vectors.get(n, "r") in POSITIONS, key,
               f"probe {n!r} measures {vectors.get(n)} (a direction vector's change, not a displacement "
               f"in m): an elongation needs a probe of r or mean; got {n!r}")
    return names


def _check_elongation(o, where, raw, levels, scale):
    return {"probes": _positions(_probes(o, where, raw), o, where, raw)}


def _check_difference(o, where, raw, levels, scale):
    names = _probes(o, where, raw, pair=True)
    vectors = {p.get("name"): p.get("vector", "r") for p in raw.get("probes", []) or [] if isinstance(p, dict)}
    kinds = ["position" if vectors[n] in POSITIONS else vectors[n] for n in names]
    expect(kinds[0] == kinds[1], f"{where}.probes", f"{names[0]!r} measures {vectors[names[0]]} and {names[1]!r} "
           f"{vectors[names[1]]}: their difference mixes units; give two probes of one vector; got {names}")
    return {"probes": names, "component": _component(o, where, "x")}


def _check_stiffness(o, where, raw, levels, scale):
    out = {"probes": _positions(_probes({k: v for k, v in o.items() if k in ("probe", "probes")}, where, raw),
                                o, where, raw)}
    if "force" in o:
        out["force"] = number(o["force"], f"{where}.force", positive=True)
    else:                                   # the config's loads; proportional ones: one force per λ
        loads = _model_loads(raw, where)
        expect(any(np.any(f) for _, f in loads), f"{where}.force", "the model config has no load; give force (N per load factor)")
        if any(curve is not None for curve, _ in loads):
            out["loads"] = loads
        else:
            out["force"] = load_at(loads, 1.0)
    lower = number(o.get("lower", 0.0), f"{where}.lower") * scale
    if lower < 0 or np.any(levels <= lower):
        raise CalibrationError(f"{where}.lower", f"must be >= 0 and below every load level of the data; "
                                                 f"got {lower:g}")
    out["lower"] = lower
    return out


def _component_of(o, disp, rows, levels):
    return _of(_at(disp, o["probes"], rows(levels))[0], o["component"])


def _elongation(o, disp, rows, levels):
    return np.mean(_at(disp, o["probes"], rows(levels))[:, :, 0], axis=0)


def _difference(o, disp, rows, levels):
    u = _at(disp, o["probes"], rows(levels))
    return _of(u[0] - u[1], o["component"])


def _force(o: dict, lam) -> np.ndarray:
    """F at load factors ``lam``: λ × ``force``, or the config's loads there (their curves)."""
    lam = np.asarray(lam, dtype=float)
    if "force" in o:
        return lam * o["force"]
    return np.array([load_at(o["loads"], x) for x in lam])


def _stiffness(o, disp, rows, levels):
    u = _elongation(o, disp, rows, levels)
    u0 = _elongation(o, disp, rows, [o["lower"]])[0] if o["lower"] > 0 else 0.0
    f0 = _force(o, [o["lower"]])[0] if o["lower"] > 0 else 0.0     # the reference carries no load
    return (_force(o, levels) - f0) / (u - u0)


#: the quantities a data set can measure, by name (module docstring)
QUANTITIES = {
    "probe": Quantity("probe", ("probe", "component"), _check_probe, _component_of),
    "elongation": Quantity("elongation", ("probe", "probes"), _check_elongation, _elongation),
    "difference": Quantity("difference", ("probes", "component"), _check_difference, _difference),
    "stiffness": Quantity("stiffness", ("probe", "probes", "force", "lower"), _check_stiffness,
                          _stiffness, "N/m"),
}


def evaluate(name: str, options: dict, disp: dict, levels: np.ndarray, solved: list[float]) -> np.ndarray:
    """The quantity at ``levels`` from a sample's probe displacements at its ``solved`` levels
    (every level of the fit; rows of levels a failed sample did not reach are NaN)."""
    solved = np.asarray(solved, dtype=float)        # a level is the solved one nearest (spec.merged_levels)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.asarray(QUANTITIES[name].evaluate(
            options, disp, lambda ls: [int(np.argmin(np.abs(solved - float(x)))) for x in ls], levels), dtype=float)
