"""The sweep file: base config, parameters (key paths and values), how runs are run, SLURM settings;
every error names its key in the sweep file."""
from __future__ import annotations

import copy
import os
import re
import shlex
from dataclasses import dataclass, field, replace
from typing import Any

from ...config.parse import parse_config
from ...config.values import ConfigError
from ...linalg.option_syntax import check_command_line, stray_words
from ... import yamlio
from ...errors import UNKNOWN_KEY
from .base import (LOG_MODES, MODES, RUN_KEYS, SLURM_KEYS, SWEEP_KEYS, SweepError, Token, as_int, load_yaml,
                   SweepLoader, path_exists, as_str, format_key_path, parse_key_path, set_key_path)


# --------------------------------------------------------------------------- sweep spec
@dataclass
class Parameter:
    """One swept key: normalised ``path``, its ``tokens`` and ``values``; ``label`` is used in ids."""
    path: str
    tokens: tuple[Token, ...]
    values: list
    label: str = ""


@dataclass
class RunSpec:
    """One run of a sweep."""
    index: int
    run_id: str
    params: dict[str, Any]          # normalised key path -> value
    dir: str                        # absolute run directory


@dataclass
class SlurmSpec:
    """``slurm:`` of a sweep file (or the matching ancf-sweep options): the job array's resources."""
    throttle: int | None = None     # most array tasks running at once (None: SLURM's limit)
    cpus_per_task: int | None = None
    mem: str | None = None
    time: str | None = None         # SLURM's time syntax; None: run.timeout + 2 min, else none
    partition: str | None = None
    account: str | None = None
    venv: str | None = None         # absolute; None: the environment running ancf-sweep
    logs: str = "append"            # append | numbered


_SLURM_TIME = re.compile(r"(\d+-)?\d+(:\d{1,2}){0,2}|\d+-\d+")


_SLURM_MEM = re.compile(r"\d+[KMGT]?B?", re.IGNORECASE)
_SLURM_NAME = re.compile(r"[A-Za-z0-9_.\-]+(?:,[A-Za-z0-9_.\-]+)*")


def slurm_spec(value: Any, here: str, path: str = "slurm") -> SlurmSpec:
    """Validate a ``slurm:`` mapping (``here``: the directory relative venv paths start from)."""
    value = value or {}
    if not isinstance(value, dict):
        raise SweepError(path, "expected a mapping with keys " + ", ".join(SLURM_KEYS))
    for k in value:
        if k not in SLURM_KEYS:
            raise SweepError(f"{path}.{k}", "unknown key; allowed: " + ", ".join(SLURM_KEYS))
    sl = SlurmSpec()
    if value.get("throttle") is not None:
        sl.throttle = as_int(value["throttle"], f"{path}.throttle")
    if value.get("cpus_per_task") is not None:
        sl.cpus_per_task = as_int(value["cpus_per_task"], f"{path}.cpus_per_task")
    if value.get("mem") is not None:
        sl.mem = str(value["mem"])
        if not _SLURM_MEM.fullmatch(sl.mem):
            raise SweepError(f"{path}.mem", f"expected SLURM's memory syntax, e.g. 4G or 500M; got {sl.mem!r}")
    if value.get("time") is not None:
        sl.time = str(value["time"])
        if not _SLURM_TIME.fullmatch(sl.time):
            raise SweepError(f"{path}.time", "expected SLURM's time syntax, e.g. 90, 02:00:00 or "
                                             f"1-12:00:00; got {sl.time!r}")
    for key in ("partition", "account"):
        if value.get(key) is not None:
            text = as_str(value[key], f"{path}.{key}")
            if not _SLURM_NAME.fullmatch(text):
                # written into '#SBATCH --partition=...' verbatim: a blank would end the option
                raise SweepError(f"{path}.{key}", f"a SLURM {key} name (several: comma-separated), "
                                 f"letters, digits, '_', '-', '.' only, e.g. short or short,long; "
                                 f"got {text!r}")
            setattr(sl, key, text)
    if value.get("venv") is not None:
        sl.venv = os.path.normpath(os.path.join(here, as_str(value["venv"], f"{path}.venv")))
    if value.get("logs") is not None:
        if value["logs"] not in LOG_MODES:
            raise SweepError(f"{path}.logs", f"must be one of {', '.join(LOG_MODES)}; got {value['logs']!r}")
        sl.logs = value["logs"]
    return sl


@dataclass
class Sweep:
    """A validated sweep file."""
    file: str                       # absolute path of the sweep file
    name: str
    mode: str
    base: str                       # absolute path of the base config
    base_raw: dict
    parameters: list[Parameter]
    output: str                     # absolute root directory
    ranks: int = 1
    jobs: int = 1
    petsc: list[str] = field(default_factory=list)
    timeout: float | None = None
    mpiexec: list[str] = field(default_factory=lambda: ["mpirun"])
    slurm: SlurmSpec = field(default_factory=SlurmSpec)

    @property
    def base_dir(self) -> str:
        return os.path.dirname(self.base)

    def with_overrides(self, jobs: int | None = None, ranks: int | None = None,
                       **slurm: Any) -> "Sweep":
        """A copy with ``run.jobs`` / ``run.ranks`` / ``slurm.*`` replaced (command-line
        overrides; a ``None`` keeps the file's value)."""
        sl = replace(self.slurm, **{k: v for k, v in slurm.items() if v is not None})
        return replace(self, jobs=jobs if jobs is not None else self.jobs,
                       ranks=ranks if ranks is not None else self.ranks, slurm=sl)

    def n_runs(self) -> int:
        if self.mode == "list":
            return len(self.parameters[0].values)
        n = 1
        for p in self.parameters:
            n *= len(p.values)
        return n

    def shape(self) -> str:
        """``grid of 3 x 2`` or ``list of 3``."""
        if self.mode == "list":
            return f"list of {self.n_runs()}"
        return "grid of " + " x ".join(str(len(p.values)) for p in self.parameters)


def _petsc_args(value: Any) -> list[str]:
    """run.petsc as ancf-solve's PETSc arguments, refused (SweepError) where every run would be: an
    option of ancf-solve's own (``--output-dir``), a stray word PETSc skips (``["snes_max_it", "3"]``: each run ignored it) or a value PETSc refuses."""
    args = _petsc_list(value)
    own = [a for a in args if a.startswith("--")]
    if own:                 # ancf-solve's: --output-dir sent every run into one directory
        raise SweepError("run.petsc", f"{own[0]!r} is ancf-solve's own option, not PETSc's (one dash): "
                                      "the sweep gives each run its own (--output-dir, --restart); "
                                      "leave it out")
    stray = stray_words(args)
    if stray:
        raise SweepError("run.petsc", f"{stray[0]!r} is neither an option nor an option's value (PETSc would "
                                      'skip it); write options with their dash, e.g. ["-snes_max_it", "30"]')
    problem = check_command_line(args)
    if problem:
        raise SweepError("run.petsc", f"PETSc option {problem}")
    return args


def _petsc_list(value: Any) -> list[str]:
    path = "run.petsc"
    if isinstance(value, dict):
        args: list[str] = []
        for k, v in value.items():
            if not isinstance(k, str) or isinstance(v, (dict, list)):
                raise SweepError(f"{path}.{k}", "PETSc options are name: scalar pairs, "
                                                "e.g. {snes_rtol: 1e-9}")
            args.append("-" + k.lstrip("-"))
            if v is not None and v is not True:
                args.append("0" if v is False else str(v))
        return args
    if isinstance(value, list):
        for i, v in enumerate(value):
            if isinstance(v, (dict, list)) or v is None:
                raise SweepError(f"{path}[{i}]", f"expected an option or value string; got {v!r}")
        return [v if isinstance(v, str) else str(v) for v in value]
    raise SweepError(path, 'expected a list like ["-snes_rtol", "1e-9"] or a mapping '
                           "like {snes_rtol: 1e-9}")


def _check_against_schema(sweep_base: dict, base_dir: str, param: Parameter, key: str) -> None:
    """A key missing from the base config must be one the config format knows (e.g. output.vtk)."""
    raw = copy.deepcopy(sweep_base)
    set_key_path(raw, param.tokens, param.values[0])
    try:
        parse_config(raw, base_dir=base_dir)
    except ConfigError as exc:
        p = exc.path
        if exc.kind == UNKNOWN_KEY and (param.path == p or param.path.startswith(p + ".")
                                        or param.path.startswith(p + "[")):
            raise SweepError(key, f"not in the base config, and not a config key ({exc})") from None


def _labels(params: list[Parameter]) -> None:
    """Short, unique labels: the last segment of each path, longer where they collide."""
    segs = []
    for p in params:
        s: list[str] = []
        for t in p.tokens:
            if isinstance(t, int):
                s[-1] += str(t)
            else:
                s.append(t)
        segs.append(s)
    depth = [1] * len(params)
    while True:
        labels = [".".join(s[-d:]) for s, d in zip(segs, depth)]
        clash = [i for i, lab in enumerate(labels) if labels.count(lab) > 1 and depth[i] < len(segs[i])]
        if not clash:
            break
        for i in clash:
            depth[i] += 1
    for p, lab in zip(params, labels):
        p.label = re.sub(r"[^A-Za-z0-9._\-]", "_", lab)


def load_sweep(path: str) -> Sweep:
    """Read and validate a sweep file; every problem raises :class:`SweepError` naming its key."""
    path = os.path.abspath(path)
    raw = load_yaml(path, "", SweepLoader)
    if not isinstance(raw, dict):
        raise SweepError("", yamlio.not_a_mapping(raw, SWEEP_KEYS))
    for k in raw:
        if k not in SWEEP_KEYS:
            raise SweepError(str(k), "unknown key; allowed: " + ", ".join(SWEEP_KEYS))
    here = os.path.dirname(path)
    if raw.get("base") is None:
        raise SweepError("base", "missing: the base config file (relative to the sweep file)")
    base = os.path.normpath(os.path.join(here, as_str(raw["base"], "base")))
    stem = os.path.splitext(os.path.basename(path))[0]
    name = as_str(raw.get("name", stem), "name")
    if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._\-]*", name):
        raise SweepError("name", f"use letters, digits, '.', '_' and '-' only (it names the output "
                                 f"directory and the SLURM job); got {name!r}")
    mode = raw.get("mode", "grid")
    if mode not in MODES:
        raise SweepError("mode", f"must be one of {', '.join(MODES)}; got {mode!r}")
    output = os.path.normpath(os.path.join(here, as_str(raw.get("output", os.path.join("sweeps", name)),
                                                      "output")))

    run = raw.get("run", {}) or {}
    if not isinstance(run, dict):
        raise SweepError("run", "expected a mapping with keys " + ", ".join(RUN_KEYS))
    for k in run:
        if k not in RUN_KEYS:
            raise SweepError(f"run.{k}", "unknown key; allowed: " + ", ".join(RUN_KEYS))
    ranks = as_int(run.get("ranks", 1), "run.ranks")
    jobs = as_int(run.get("jobs", 1), "run.jobs")
    petsc = _petsc_args(run.get("petsc", []) or [])
    timeout = run.get("timeout")
    if timeout is not None and (isinstance(timeout, bool) or not isinstance(timeout, (int, float))
                                or timeout <= 0):
        raise SweepError("run.timeout", f"expected seconds > 0 (or null for none); got {timeout!r}")
    mpiexec = run.get("mpiexec", "mpirun")
    if isinstance(mpiexec, str):
        mpiexec = shlex.split(mpiexec)
    if (not isinstance(mpiexec, list) or not mpiexec
            or not all(isinstance(x, str) and x for x in mpiexec)):
        raise SweepError("run.mpiexec", "expected a command like 'mpirun --oversubscribe'; "
                                        f"got {mpiexec!r}")

    slurm = slurm_spec(raw.get("slurm"), here)

    # base config: must itself be valid, so that every later config error is the sweep's doing
    base_raw = load_yaml(base, "base")
    if not isinstance(base_raw, dict):
        raise SweepError("base", f"{base}: not a model config (expected a mapping)")
    try:
        parse_config(base_raw, base_dir=os.path.dirname(base), source=base)
    except ConfigError as exc:
        raise SweepError("base", f"{base}: config error: {exc}") from None

    plist = raw.get("parameters")
    if not isinstance(plist, dict) or not plist:
        raise SweepError("parameters", "expected a non-empty mapping of key paths to value lists, "
                                       "e.g. {geometry.twist_deg: [0, 15, 45]}")
    params: list[Parameter] = []
    for key, values in plist.items():
        where = f"parameters.{key}"
        try:
            tokens = parse_key_path(key)
        except ValueError as exc:
            raise SweepError(where, str(exc)) from None
        norm = format_key_path(tokens)
        if tokens[0] == "output" and (len(tokens) == 1 or tokens[1] == "dir"):
            raise SweepError(where, "output.dir is set by the sweep (one directory per run); "
                                    "set the sweep's own 'output' instead")
        for other in params:
            a, b = sorted((other.tokens, tokens), key=len)
            if b[:len(a)] == a:
                raise SweepError(where, f"overlaps with parameter {other.path}; sweep one or the other")
        if not isinstance(values, list):
            raise SweepError(where, f"expected a list of values; got {values!r} "
                                    f"(write [{values!r}] for a single value)")
        if not values:
            raise SweepError(where, "empty list of values")
        twice = [(i, j) for j in range(len(values)) for i in range(j) if values[i] == values[j]]
        if mode == "grid" and twice:
            i, j = twice[0]
            raise SweepError(where, f"values {i + 1} and {j + 1} are equal ({values[i]!r}, {values[j]!r}): "
                                    "a grid would run each of their combinations twice; remove one")
        p = Parameter(norm, tokens, values)
        try:
            exists = path_exists(base_raw, tokens)
        except ValueError as exc:
            raise SweepError(where, f"{exc} ({base})") from None
        if not exists:
            _check_against_schema(base_raw, os.path.dirname(base), p, where)
        params.append(p)
    if mode == "list":
        n0 = len(params[0].values)
        for p in params[1:]:
            if len(p.values) != n0:
                raise SweepError(f"parameters.{p.path}", f"has {len(p.values)} values but "
                                 f"{params[0].path} has {n0}; mode: list pairs the lists element "
                                 "by element (use mode: grid for all combinations)")
    _labels(params)
    return Sweep(file=path, name=name, mode=mode, base=base, base_raw=base_raw, parameters=params,
                 output=output, ranks=ranks, jobs=jobs, petsc=petsc,
                 timeout=float(timeout) if timeout is not None else None, mpiexec=mpiexec,
                 slurm=slurm)
