"""The fit file (YAML): the model config, the parameters (config values by key path), the data, the
objective, the optimiser, the identifiability analysis, where results go; every error names its
key in the fit file and the fix.  Format: docs/calibration.md.

    model: ../achilles_type3_psi0.yaml            # the model config, relative to this file
    parameters:
      - {key: beams[0].material.mu, bounds: [20e6, 500e6], log: true}
      - {name: mu_scale, keys: [beams[1].material.mu, beams[2].material.mu], factor: true,
         bounds: [0.2, 5]}                        # one factor on both values of the config
    data:
      - {file: table1.csv, load: load_N, value: psi0_mm, value_scale: 1e-3, sigma: 1e-6,
         quantity: elongation, probe: soleus}
    optimizer: {method: trf}                      # trf | differential_evolution
    output: fits/table1
"""
from __future__ import annotations

import copy
import os
import re
from dataclasses import dataclass, field
from typing import Any

from ... import yamlio
from ...config.parse import parse_config
from ...config.values import ConfigError
from ...config.conditions import STEP_RESOLUTION
from ..sweep.base import SweepLoader, format_key_path, load_yaml, path_exists, parse_key_path
from ..sweep.spec import SlurmSpec, slurm_spec
from .data import DataSet, parse_data
from .errors import CalibrationError, expect, number, integer
from .parameters import Parameter, apply

FIT_KEYS = ("model", "name", "parameters", "data", "objective", "optimizer", "identifiability",
            "output", "slurm")
PARAMETER_KEYS = ("key", "keys", "name", "bounds", "start", "log", "factor", "unit")
OPTIMIZER_KEYS = ("method", "max_evaluations", "fd_step", "xtol", "ftol", "gtol", "seed",
                  "popsize", "generations", "polish", "starts")
METHODS = ("trf", "differential_evolution")
LOSSES = ("linear", "soft_l1", "huber", "cauchy", "arctan")
IDENT_KEYS = ("profiles", "points", "span", "reoptimise", "max_evaluations")


@dataclass
class OptimizerSpec:
    method: str = "trf"
    max_evaluations: int = 200           # samples of the local fit (finite differences included)
    fd_step: float = 1e-5                # finite-difference step in u (log10 p, or p / scale)
    xtol: float = 1e-8
    ftol: float = 1e-8
    gtol: float = 1e-8
    seed: int = 0
    popsize: int = 10                    # differential evolution: population = popsize x parameters
    generations: int = 30
    polish: bool = True                  # differential evolution: finish with trf
    starts: int = 1                      # local fits from this many starts (a SLURM array's tasks)


@dataclass
class IdentifiabilitySpec:
    profiles: bool = True
    points: int = 9                      # profile points per parameter (odd: the optimum in the middle)
    span: float = 3.0                    # profile half-width in standard errors (clipped at the bounds)
    reoptimise: bool = True              # the other parameters re-fitted at each profile point
    max_evaluations: int = 60            # samples per profile point's re-fit


@dataclass
class FitSpec:
    file: str
    name: str
    model_path: str
    model_raw: dict
    model_dir: str
    parameters: list[Parameter]
    data: list[DataSet]
    levels: list[float]                  # load factors solved: every data set's levels
    loss: str = "linear"
    penalty: float = 1e3                 # residual (in sigmas) of a level a failed sample missed
    absolute_sigma: bool = False         # the sigmas are the data's errors: s² = 1 (identify.py)
    optimizer: OptimizerSpec = field(default_factory=OptimizerSpec)
    identifiability: IdentifiabilitySpec = field(default_factory=IdentifiabilitySpec)
    output: str = ""
    slurm: SlurmSpec = field(default_factory=SlurmSpec)

    def config(self, values) -> dict:
        """The model config (raw) at parameter values ``values``, solved at ``levels``."""
        raw = apply(self.model_raw, self.parameters, values)
        raw["steps"] = list(self.levels)
        return raw


def _model(doc: dict, here: str) -> tuple[str, dict]:
    expect("model" in doc, "model", "missing: the model config to fit (relative to the fit file)")
    expect(isinstance(doc["model"], str), "model", "expected a file name")
    path = os.path.normpath(os.path.join(here, doc["model"]))
    raw = load_yaml(path, "model")
    expect(isinstance(raw, dict), "model", f"{path}: not a model config (expected a mapping)")
    try:
        parse_config(copy.deepcopy(raw), base_dir=os.path.dirname(path), source=path)
    except ConfigError as exc:
        raise CalibrationError("model", f"{path}: config error: {exc}") from None
    return path, raw


def _keys(item: dict, where: str, raw: dict) -> list[tuple]:
    expect(("key" in item) != ("keys" in item), where, "give key (one config value) or keys (a list)")
    texts = [item["key"]] if "key" in item else item["keys"]
    expect(isinstance(texts, list) and texts and all(isinstance(t, str) for t in texts),
           f"{where}.keys", "expected a list of key paths like beams[0].material.mu")
    out = []
    for i, text in enumerate(texts):
        at = f"{where}.key" if "key" in item else f"{where}.keys[{i}]"
        try:
            tokens = parse_key_path(text)
            found = path_exists(raw, tokens)
        except ValueError as exc:
            raise CalibrationError(at, str(exc)) from None
        if not found and item.get("factor"):
            raise CalibrationError(at, f"{text} is not in the model config: a factor needs its value there")
        out.append(tokens)
    return out


def _base_values(raw: dict, keys: list[tuple], where: str) -> tuple[float, ...]:
    out = []
    for k in keys:
        node = raw
        for t in k:
            node = node[t]
        try:
            out.append(float(node))
        except (TypeError, ValueError):
            raise CalibrationError(f"{where}.keys", f"the model's value there is not a number "
                                                    f"({node!r}): a factor needs one") from None
    return tuple(out)


def _parameter(item: Any, i: int, raw: dict) -> Parameter:
    where = f"parameters[{i}]"
    expect(isinstance(item, dict), where, "expected a mapping with key (or keys) and bounds")
    for k in item:
        expect(k in PARAMETER_KEYS, f"{where}.{k}", "unknown key; allowed: " + ", ".join(PARAMETER_KEYS))
    keys = _keys(item, where, raw)
    factor = item.get("factor", False)
    expect(isinstance(factor, bool), f"{where}.factor", "expected true or false")
    log = item.get("log", False)
    expect(isinstance(log, bool), f"{where}.log", "expected true or false")
    b = item.get("bounds")
    expect(isinstance(b, list) and len(b) == 2, f"{where}.bounds", "expected [lower, upper]")
    lo, hi = number(b[0], f"{where}.bounds[0]"), number(b[1], f"{where}.bounds[1]")
    expect(lo < hi, f"{where}.bounds", f"lower must be below upper; got [{lo:g}, {hi:g}]")
    expect(not log or lo > 0, f"{where}.bounds", f"a log-scaled parameter needs lower > 0; got {lo:g}")
    base = _base_values(raw, keys, where) if factor else ()
    if "start" in item:
        start = number(item["start"], f"{where}.start")
    elif factor:
        start = 1.0
    else:
        vals = _base_values(raw, keys, where) if all(path_exists(raw, k) for k in keys) else ()
        expect(len(set(vals)) == 1, f"{where}.start", "missing: the model config has no single "
               "value at the key(s) to start from; give start")
        start = vals[0]
    expect(lo <= start <= hi, f"{where}.start", f"{start:g} is outside the bounds [{lo:g}, {hi:g}]")
    name = item.get("name", item.get("key", ""))
    expect(isinstance(name, str) and re.fullmatch(r"[A-Za-z0-9_.\[\]\-]+", name or "-") is not None
           and name != "", f"{where}.name", "expected a name of letters, digits, '_', '.', '-' "
           "(required with keys)")
    unit = item.get("unit", "")
    expect(isinstance(unit, str), f"{where}.unit", "expected a unit name like Pa")
    _si_unit(unit, f"{where}.unit", start)
    return Parameter(name, keys, lo, hi, start, log, factor, base, unit)


_SI_BASES = ("Pa", "N", "m", "J", "W", "s", "g", "rad")
_PREFIX = {"k": 1e3, "M": 1e6, "G": 1e9, "T": 1e12, "c": 1e-2, "m": 1e-3, "u": 1e-6, "\u00b5": 1e-6,
           "n": 1e-9}


def _si_unit(unit: str, path: str, start: float) -> None:
    """``unit`` only names the unit of the values, which are the model config's (SI): a prefixed
    unit (MPa, mm, N/mm) would label Pa as MPa, or mean bounds the model reads in Pa."""
    factor, si = 1.0, unit
    for k, part in enumerate(unit.strip().split("/")):
        for word in re.split(r"[*\u00b7 ]", part):
            stem, power = re.fullmatch(r"(.*?)\^?(\d*)", word).groups()
            if stem[:1] in _PREFIX and stem[1:] in _SI_BASES and stem != "kg":
                factor *= _PREFIX[stem[0]] ** (int(power or 1) * (-1 if k else 1))
                si = si.replace(stem, stem[1:])
    expect(factor == 1.0, path, f"{unit!r}: bounds and start are values of the model config, in SI "
           f"units; give them in {si} ({start:g} {unit} = {start * factor:g} {si}) and unit: {si}")


def _parameters(doc: dict, raw: dict, model_dir: str) -> list[Parameter]:
    items = doc.get("parameters")
    expect(isinstance(items, list) and items, "parameters",
           "expected a list of parameters, e.g. [{key: beams[0].material.mu, bounds: [1e7, 1e9]}]")
    params = [_parameter(item, i, raw) for i, item in enumerate(items)]
    names = [p.name for p in params]
    for i, n in enumerate(names):
        expect(names.index(n) == i, f"parameters[{i}].name", f"{n!r} names two parameters")
    owner: dict[tuple, int] = {}
    for i, p in enumerate(params):       # one config value, one parameter
        for k in p.keys:
            expect(tuple(k) not in owner, f"parameters[{i}]", f"{format_key_path(k)} is also set by "
                   f"parameters[{owner.get(tuple(k))}]: give each config value to one parameter")
            owner[tuple(k)] = i
    for i, p in enumerate(params):       # the key itself: the model config takes it at the start
        try:
            parse_config(apply(raw, [p], [p.start]), base_dir=model_dir)
        except ConfigError as exc:
            if all(path_exists(raw, k) for k in p.keys):
                raise CalibrationError(f"parameters[{i}].start", f"the model config refuses "
                                       f"{p.name} = {p.start:g}: {exc}; change start") from None
            raise CalibrationError(f"parameters[{i}].{'key' if len(p.keys) == 1 else 'keys'}",
                                   f"{p.key_text()} is not a value of the model config and the "
                                   f"config refuses it ({exc}); check the key path") from None
    for i, p in enumerate(params):       # the model config must accept each bound
        for edge in (p.lower, p.start, p.upper):
            values = [edge if j == i else q.start for j, q in enumerate(params)]
            try:
                parse_config(apply(raw, params, values), base_dir=model_dir)
            except ConfigError as exc:
                raise CalibrationError(f"parameters[{i}]", f"the model config refuses "
                                       f"{p.name} = {edge:g}: {exc}; change the bounds") from None
    return params


def _options(doc: dict, key: str, allowed: tuple) -> dict:
    value = doc.get(key) or {}
    expect(isinstance(value, dict), key, "expected a mapping with keys " + ", ".join(allowed))
    for k in value:
        expect(k in allowed, f"{key}.{k}", "unknown key; allowed: " + ", ".join(allowed))
    return value


def _optimizer(doc: dict) -> OptimizerSpec:
    o = _options(doc, "optimizer", OPTIMIZER_KEYS)
    spec = OptimizerSpec()
    method = o.get("method", spec.method)
    expect(method in METHODS, "optimizer.method", f"must be one of {', '.join(METHODS)}; got {method!r}")
    spec.method = method
    for k in ("max_evaluations", "seed", "popsize", "generations", "starts"):
        if k in o:
            setattr(spec, k, integer(o[k], f"optimizer.{k}", lo=0 if k == "seed" else 1))
    for k in ("fd_step", "xtol", "ftol", "gtol"):
        if k in o:
            setattr(spec, k, number(o[k], f"optimizer.{k}", positive=True))
    if "polish" in o:
        expect(isinstance(o["polish"], bool), "optimizer.polish", "expected true or false")
        spec.polish = o["polish"]
    return spec


def _identifiability(doc: dict) -> IdentifiabilitySpec:
    o = _options(doc, "identifiability", IDENT_KEYS)
    spec = IdentifiabilitySpec()
    for k in ("profiles", "reoptimise"):
        if k in o:
            expect(isinstance(o[k], bool), f"identifiability.{k}", "expected true or false")
            setattr(spec, k, o[k])
    if "points" in o:
        spec.points = integer(o["points"], "identifiability.points", lo=3)
    if "max_evaluations" in o:
        spec.max_evaluations = integer(o["max_evaluations"], "identifiability.max_evaluations", lo=1)
    if "span" in o:
        spec.span = number(o["span"], "identifiability.span", positive=True)
    return spec


def merged_levels(values: list[float]) -> list[float]:
    """The load levels to solve, increasing: values within the config's step resolution of the
    last kept one are that level (two files' 0.3 and 0.1 x 3 = 0.30000000000000004 made steps
    the model config refuses, and every sample a config error)."""
    out: list[float] = []
    for x in sorted(values):
        if not out or x > out[-1] * (1.0 + STEP_RESOLUTION):
            out.append(x)
    return out


def load_fit(path: str) -> FitSpec:
    """Read and check a fit file; every problem raises ``CalibrationError`` naming its key."""
    path = os.path.abspath(path)
    doc = load_yaml(path, "", SweepLoader)
    expect(isinstance(doc, dict), "", yamlio.not_a_mapping(doc, FIT_KEYS))
    for k in doc:
        expect(k in FIT_KEYS, str(k), "unknown key; allowed: " + ", ".join(FIT_KEYS))
    here = os.path.dirname(path)
    name = doc.get("name", os.path.splitext(os.path.basename(path))[0])
    expect(isinstance(name, str) and re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._\-]*", name) is not None,
           "name", f"use letters, digits, '.', '_' and '-' only; got {name!r}")
    model_path, raw = _model(doc, here)
    params = _parameters(doc, raw, os.path.dirname(model_path))
    data = parse_data(doc.get("data"), here, raw)
    levels = merged_levels([float(x) for d in data for x in d.all_levels])
    obj = _options(doc, "objective", ("loss", "penalty", "absolute_sigma"))
    absolute = obj.get("absolute_sigma", False)
    expect(isinstance(absolute, bool), "objective.absolute_sigma", "expected true or false")
    n_data = sum(len(d.levels) for d in data)
    expect(absolute or n_data > len(params), "objective.absolute_sigma",
           f"{n_data} data point(s) for {len(params)} parameter(s) leave no residual to estimate the "
           "errors from: set absolute_sigma: true (the sigmas are the data's errors) or add data")
    loss = obj.get("loss", "linear")
    expect(loss in LOSSES, "objective.loss", f"must be one of {', '.join(LOSSES)}; got {loss!r}")
    penalty = number(obj.get("penalty", 1e3), "objective.penalty", positive=True)
    output = doc.get("output", os.path.join("fits", name))
    expect(isinstance(output, str) and output, "output", "expected a directory (relative to the fit file)")
    spec = FitSpec(file=path, name=name, model_path=model_path, model_raw=raw,
                   model_dir=os.path.dirname(model_path), parameters=params, data=data, levels=levels,
                   loss=loss, penalty=penalty, absolute_sigma=absolute, optimizer=_optimizer(doc),
                   identifiability=_identifiability(doc), output=os.path.normpath(os.path.join(here, output)),
                   slurm=slurm_spec(doc.get("slurm"), here))
    try:                                 # the data's levels as the model's steps (a history has its frames)
        parse_config(spec.config([p.start for p in params]), base_dir=spec.model_dir)
    except ConfigError as exc:
        raise CalibrationError("data", f"the model config refuses the data's load levels as its steps: "
                                       f"{exc}; fit a model solved at load levels (steps)") from None
    return spec
