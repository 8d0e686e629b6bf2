"""Parameter sweeps over a base config: expansion into run directories, local execution,
SLURM job-array scripts and collection into one CSV (no argument parsing; see apps/ancf_sweep.py).

A sweep file (YAML)::

    base: configs/achilles_type3_psi45.yaml   # the model config, relative to the sweep file
    name: twist_sweep                         # default: the sweep file's stem
    mode: grid                                # grid (Cartesian product) | list (zip, equal lengths)
    parameters:                               # dotted key paths into the base config
      geometry.twist_deg: [0, 15, 45]
      beams[0].material.bulk_modulus: [0.5e9, 0.86e9]
    run: {ranks: 1, jobs: 2, petsc: ["-snes_rtol", "1e-9"], timeout: 3600, mpiexec: mpirun}
    output: sweeps/twist_sweep                # root directory, relative to the sweep file
    slurm:                                    # only for --slurm (all optional)
      throttle: 20                            # at most 20 array tasks at once (--array=0-N%20)
      cpus_per_task: 1
      mem: 4G                                 # per node, SLURM's syntax
      time: "02:00:00"                        # default: run.timeout plus 2 minutes, else none
      partition: short
      account: myproject
      venv: ../.venv                          # relative to the sweep file (or absolute)
      logs: append                            # append | numbered: log.txt on resubmission

Every run gets ``<output>/<run id>/`` with ``config.yaml`` (the base config with the values
substituted, ``output.dir`` set to the run directory and relative section ``file:`` paths made
absolute), ``params.json`` and, once run, ``log.txt``, ``run.json`` (status, reason, wall time),
plus the solver's own ``summary.json``, ``results.h5`` and VTU files.
"""
from __future__ import annotations

import copy
import csv
import hashlib
import itertools
import json
import os
import re
import shlex
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import yaml

from ..errors import InputError
from ..io.files import atomic_write

SWEEP_KEYS = ("base", "name", "mode", "parameters", "run", "output", "slurm")
RUN_KEYS = ("ranks", "jobs", "petsc", "timeout", "mpiexec")
SLURM_KEYS = ("throttle", "cpus_per_task", "mem", "time", "partition", "account", "venv", "logs")
LOG_MODES = ("append", "numbered")
MODES = ("grid", "list")
# final states of one attempt, then the states collection reports for unfinished runs;
# completed and unstable runs are done (a rerun would give the same answer), the others are redone
FINAL_STATUSES = ("completed", "unstable", "failed", "config_error", "timeout", "interrupted",
                  "crashed")
DONE_STATUSES = ("completed", "unstable")
FAILED_STATUSES = ("failed", "config_error", "timeout", "interrupted", "crashed")
STATUS_ORDER = FINAL_STATUSES + ("running", "missing")
#: ancf-solve's exit codes (docs/running.md)
EXIT_INPUT, EXIT_FAILED, EXIT_UNSTABLE = 2, 3, 4


class SweepError(InputError):
    """A problem with a sweep file; ``path`` is the key in the sweep file (e.g. ``run.jobs``)."""

    def __init__(self, path: str, message: str):
        super().__init__(path, message)
        self.message = message


class _Loader(yaml.SafeLoader):
    """SafeLoader that also reads ``1e6`` and ``0.86e9`` as floats (YAML 1.2 style)."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."))


# ------------------------------------------------------------------------------ key paths
Token = str | int
_SEGMENT = re.compile(r"([A-Za-z_][A-Za-z0-9_\-]*)((?:\[\d+\])*)")


def parse_key_path(text: str) -> tuple[Token, ...]:
    """``beams[0].material.mu`` -> ``('beams', 0, 'material', 'mu')``; raises ValueError."""
    if not isinstance(text, str) or not text:
        raise ValueError("a key path is a non-empty string like beams[0].material.mu")
    tokens: list[Token] = []
    for part in text.split("."):
        m = _SEGMENT.fullmatch(part)
        if m is None:
            raise ValueError(f"bad key path {text!r}: write keys separated by dots and list "
                             "indices in brackets, e.g. loads[0].force[0]")
        tokens.append(m.group(1))
        tokens.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return tuple(tokens)


def format_key_path(tokens: tuple[Token, ...]) -> str:
    """Inverse of :func:`parse_key_path`."""
    out = ""
    for t in tokens:
        out += f"[{t}]" if isinstance(t, int) else (f".{t}" if out else t)
    return out


def _kind(value: Any) -> str:
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    return f"the value {value!r}"


def _path_exists(raw: Any, tokens: tuple[Token, ...]) -> bool:
    """True if ``tokens`` addresses a value of ``raw``; False if only mapping keys are missing
    (they can be created); raises ValueError for indices out of range or wrong container types."""
    node = raw
    for i, tok in enumerate(tokens):
        where = format_key_path(tokens[:i]) or "the top level"
        if isinstance(tok, int):
            if not isinstance(node, list):
                raise ValueError(f"{where} is {_kind(node)} in the base config, not a list; "
                                 f"cannot take [{tok}]")
            if tok >= len(node):
                raise ValueError(f"index [{tok}] out of range: {where} has {len(node)} item(s) "
                                 "in the base config")
            node = node[tok]
        else:
            if not isinstance(node, dict):
                raise ValueError(f"{where} is {_kind(node)} in the base config, not a mapping; "
                                 f"cannot take key {tok!r}")
            if tok not in node:
                if any(isinstance(t, int) for t in tokens[i + 1:]):
                    raise ValueError(f"{where} has no key {tok!r} in the base config")
                return False
            node = node[tok]
    return True


def set_key_path(raw: Any, tokens: tuple[Token, ...], value: Any) -> None:
    """Set ``raw[tokens] = value`` in place, creating missing mappings on the way."""
    node = raw
    for tok in tokens[:-1]:
        if isinstance(tok, str) and tok not in node:
            node[tok] = {}
        node = node[tok]
    node[tokens[-1]] = copy.deepcopy(value)


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
        sl.throttle = _int(value["throttle"], f"{path}.throttle")
    if value.get("cpus_per_task") is not None:
        sl.cpus_per_task = _int(value["cpus_per_task"], f"{path}.cpus_per_task")
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
            setattr(sl, key, _str(value[key], f"{path}.{key}"))
    if value.get("venv") is not None:
        sl.venv = os.path.normpath(os.path.join(here, _str(value["venv"], f"{path}.venv")))
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


def _load_yaml(path: str, key: str, loader: type = yaml.SafeLoader) -> Any:
    """Load a YAML file; errors name ``key`` (and the path, unless it is the sweep file itself)."""
    where = f"{path}: " if key else ""
    if not os.path.isfile(path):
        raise SweepError(key, f"no such file: {path}" if key else "no such file")
    try:
        with open(path) as fh:
            return yaml.load(fh, Loader=loader)  # noqa: S506 (SafeLoader subclasses only)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise SweepError(key, f"{where}YAML syntax error{at}: {problem}") from None
    except OSError as exc:
        raise SweepError(key, f"{where}cannot read: {exc.strerror}") from None


def _int(value: Any, path: str, lo: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < lo:
        raise SweepError(path, f"expected an integer >= {lo}; got {value!r}")
    return value


def _str(value: Any, path: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise SweepError(path, f"expected a non-empty string; got {value!r}")
    return value


def _petsc_args(value: Any) -> list[str]:
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
    from ..config.values import ConfigError
    from ..config.parse import parse_config
    raw = copy.deepcopy(sweep_base)
    set_key_path(raw, param.tokens, param.values[0])
    try:
        parse_config(raw, base_dir=base_dir)
    except ConfigError as exc:
        p = exc.path
        if "unknown key" in str(exc) and (param.path == p or param.path.startswith(p + ".")
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
    raw = _load_yaml(path, "", _Loader)
    if not isinstance(raw, dict):
        raise SweepError("", f"expected a mapping with keys {', '.join(SWEEP_KEYS)}")
    for k in raw:
        if k not in SWEEP_KEYS:
            raise SweepError(str(k), "unknown key; allowed: " + ", ".join(SWEEP_KEYS))
    here = os.path.dirname(path)
    if raw.get("base") is None:
        raise SweepError("base", "missing: the base config file (relative to the sweep file)")
    base = os.path.normpath(os.path.join(here, _str(raw["base"], "base")))
    stem = os.path.splitext(os.path.basename(path))[0]
    name = _str(raw.get("name", stem), "name")
    if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._\-]*", name):
        raise SweepError("name", f"use letters, digits, '.', '_' and '-' only (it names the output "
                                 f"directory and the SLURM job); got {name!r}")
    mode = raw.get("mode", "grid")
    if mode not in MODES:
        raise SweepError("mode", f"must be one of {', '.join(MODES)}; got {mode!r}")
    output = os.path.normpath(os.path.join(here, _str(raw.get("output", os.path.join("sweeps", name)),
                                                      "output")))

    run = raw.get("run", {}) or {}
    if not isinstance(run, dict):
        raise SweepError("run", "expected a mapping with keys " + ", ".join(RUN_KEYS))
    for k in run:
        if k not in RUN_KEYS:
            raise SweepError(f"run.{k}", "unknown key; allowed: " + ", ".join(RUN_KEYS))
    ranks = _int(run.get("ranks", 1), "run.ranks")
    jobs = _int(run.get("jobs", 1), "run.jobs")
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
    base_raw = _load_yaml(base, "base")
    if not isinstance(base_raw, dict):
        raise SweepError("base", f"{base}: not a model config (expected a mapping)")
    from ..config.values import ConfigError
    from ..config.parse import parse_config
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
        p = Parameter(norm, tokens, values)
        try:
            exists = _path_exists(base_raw, tokens)
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


# ------------------------------------------------------------------------------- expansion
def format_value(value: Any) -> str:
    """Compact, filesystem-safe text of a value for run ids (``8.6e+08``, ``45``, ``1,0,0``)."""
    if isinstance(value, bool):
        s = "true" if value else "false"
    elif isinstance(value, int):
        s = str(value)
    elif isinstance(value, float):
        s = f"{value:.6g}"
        if float(s) != value:
            s = repr(value)
    elif value is None:
        s = "null"
    elif isinstance(value, list):
        s = ",".join(format_value(v) for v in value)
    elif isinstance(value, str):
        s = value
    else:
        s = json.dumps(value, sort_keys=True, separators=(",", ":"))
    s = re.sub(r"[^A-Za-z0-9.,+\-]", "_", s)
    return s if len(s) <= 32 else s[:32]


def expand(sweep: Sweep) -> list[RunSpec]:
    """All runs of the sweep, in a fixed order (grid: the first parameter varies slowest)."""
    if sweep.mode == "list":
        combos = list(zip(*(p.values for p in sweep.parameters)))
    else:
        combos = list(itertools.product(*(p.values for p in sweep.parameters)))
    width = max(4, len(str(len(combos) - 1)))
    varying = [len({json.dumps(v, sort_keys=True, default=str) for v in p.values}) > 1
               for p in sweep.parameters]
    runs = []
    for i, combo in enumerate(combos):
        parts = [f"run_{i:0{width}d}"]
        parts += [f"{p.label}={format_value(v)}"
                  for p, v, var in zip(sweep.parameters, combo, varying) if var]
        run_id = "__".join(parts)
        params = {p.path: v for p, v in zip(sweep.parameters, combo)}
        if len(run_id) > 150:
            digest = hashlib.sha1(json.dumps(params, sort_keys=True, default=str).encode()).hexdigest()
            run_id = run_id[:140].rstrip("_") + "__" + digest[:8]
        runs.append(RunSpec(i, run_id, params, os.path.join(sweep.output, run_id)))
    return runs


def run_config(sweep: Sweep, run: RunSpec) -> dict:
    """The run's model config: base + values, output.dir = run dir, absolute section files."""
    raw = copy.deepcopy(sweep.base_raw)
    for p in sweep.parameters:
        set_key_path(raw, p.tokens, run.params[p.path])
    out = raw.get("output")
    if not isinstance(out, dict):
        out = raw["output"] = {}
    out["dir"] = run.dir
    for beam in raw.get("beams") or []:
        sec = beam.get("section") if isinstance(beam, dict) else None
        f = sec.get("file") if isinstance(sec, dict) else None
        if isinstance(f, str) and f and not os.path.isabs(f):
            sec["file"] = os.path.normpath(os.path.join(sweep.base_dir, f))
    return raw


def config_text(sweep: Sweep, run: RunSpec) -> str:
    """The exact text of the run's config.yaml (deterministic, so reruns can compare it)."""
    head = [f"# generated by ancf-sweep: sweep {sweep.name}, run {run.run_id}",
            f"# base config: {sweep.base}"]
    head += [f"#   {k} = {json.dumps(v, default=str)}" for k, v in run.params.items()]
    return "\n".join(head) + "\n" + yaml.safe_dump(run_config(sweep, run), sort_keys=False)


def _read_text(path: str) -> str | None:
    try:
        with open(path) as fh:
            return fh.read()
    except OSError:
        return None


def _read_json(path: str) -> dict | None:
    try:
        with open(path) as fh:
            data = json.load(fh)
        return data if isinstance(data, dict) else None
    except (OSError, ValueError):
        return None


def _remove(*paths: str) -> None:
    for p in paths:
        try:
            os.remove(p)
        except FileNotFoundError:
            pass


def is_done(sweep: Sweep, run: RunSpec) -> bool:
    """Completed (or unstable: a rerun gives the same), with exactly the config this sweep would
    write now."""
    summary = _read_json(os.path.join(run.dir, "summary.json"))
    return (summary is not None and summary.get("status") in DONE_STATUSES
            and _read_text(os.path.join(run.dir, "config.yaml")) == config_text(sweep, run))


def prepare_run(sweep: Sweep, run: RunSpec) -> bool:
    """Write ``config.yaml`` and ``params.json``; True if a completed result of this config exists.

    A run directory whose config differs from the current one (the sweep or base config was
    edited) loses its summary.json/run.json, so neither this tool nor a SLURM task skips it."""
    os.makedirs(run.dir, exist_ok=True)
    cfg_path = os.path.join(run.dir, "config.yaml")
    text = config_text(sweep, run)
    old = _read_text(cfg_path)
    if old != text:
        if old is not None:
            _remove(os.path.join(run.dir, "summary.json"), os.path.join(run.dir, "run.json"))
        atomic_write(cfg_path, text)
    params = {"sweep": sweep.name, "sweep_file": sweep.file, "base": sweep.base,
              "run_id": run.run_id, "index": run.index, "parameters": run.params}
    atomic_write(os.path.join(run.dir, "params.json"),
                  json.dumps(params, indent=1, default=str) + "\n")
    return is_done(sweep, run)


# ------------------------------------------------------------------------- running one run
@dataclass
class Outcome:
    """How one attempt ended."""
    status: str                     # one of FINAL_STATUSES
    reason: str = ""
    wall_time: float | None = None
    returncode: int | None = None


def solver_command() -> list[str]:
    """The ancf-solve command: beside this interpreter, else on PATH, else ``python -m``."""
    exe = os.path.join(os.path.dirname(sys.executable), "ancf-solve")
    if os.path.isfile(exe) and os.access(exe, os.X_OK):
        return [exe]
    import shutil
    found = shutil.which("ancf-solve")
    return [found] if found else [sys.executable, "-m", "apps.ancf_solve"]


#: statuses of an attempt that stopped early but kept its converged levels: continued with
#: ``ancf-solve --restart`` (a task killed at the time limit, or by the node)
RESTARTABLE = ("interrupted", "running")


def can_restart(run_dir: str) -> bool:
    """The run in ``run_dir`` stopped early with converged levels on disk (same config)."""
    summary = _read_json(os.path.join(run_dir, "summary.json"))
    return (summary is not None and summary.get("status") in RESTARTABLE and bool(summary.get("steps"))
            and os.path.exists(os.path.join(run_dir, "results.h5")))


def solve_command(sweep: Sweep, run: RunSpec) -> list[str]:
    """Full command of one local run (``mpiexec -n ranks`` in front when ranks > 1); a run that
    stopped early is continued from its last converged level."""
    where = ["--restart", run.dir] if can_restart(run.dir) else ["--output-dir", run.dir]
    cmd = solver_command() + [os.path.join(run.dir, "config.yaml")] + where
    cmd += sweep.petsc
    if sweep.ranks > 1:
        cmd = sweep.mpiexec + ["-n", str(sweep.ranks)] + cmd
    return cmd


_PY_EXC = re.compile(r"^[A-Za-z_][\w.]*(Error|Exception|Interrupt|Exit|Warning)\b")


def failure_reason(lines: list[str]) -> str:
    """The one-line reason in ancf-solve's stderr (MPI launcher noise and paths trimmed)."""
    lines = [ln.strip() for ln in lines if ln.strip()]
    for ln in reversed(lines):
        if ln.startswith("ancf-solve:"):
            msg = ln[len("ancf-solve:"):].strip()
            return re.sub(r"; (converged steps are in|results in|\d+ converged level\(s\) kept in) .*$",
                          "", msg)
    for ln in reversed(lines):
        if _PY_EXC.match(ln):
            return ln
    for ln in reversed(lines):
        if re.search(r"[A-Za-z0-9]", ln):
            return ln
    return ""


def _signal_name(returncode: int) -> str:
    try:
        return signal.Signals(-returncode).name
    except ValueError:
        return f"signal {-returncode}"


def classify(run_dir: str, returncode: int | None, stderr_lines: list[str],
             timed_out: bool = False, timeout: float | None = None) -> tuple[str, str]:
    """(status, reason) of a finished attempt from its exit code, stderr and summary.json."""
    summary = _read_json(os.path.join(run_dir, "summary.json")) or {}
    sstat = summary.get("status")
    reason = failure_reason(stderr_lines)
    if timed_out:
        steps = summary.get("steps") or []
        last = f"; last converged load factor {steps[-1].get('load_factor'):g}" if steps else ""
        return "timeout", f"timed out after {timeout:g} s{last}" if timeout else "timed out" + last
    if returncode == 0 and sstat == "completed":
        return "completed", ""
    if returncode == EXIT_UNSTABLE and sstat == "unstable":
        return "unstable", str(summary.get("message") or reason)
    if sstat == "interrupted" or returncode in (128 + signal.SIGTERM, 128 + signal.SIGINT):
        return "interrupted", reason or str(summary.get("message") or "interrupted")
    if returncode == EXIT_INPUT and summary.get("reason_code") == "OUTPUT_ERROR":
        return "failed", reason or str(summary.get("message") or "output error")
    if returncode == EXIT_INPUT:
        return "config_error", reason or "config error (exit code 2)"
    if sstat == "failed" or returncode == EXIT_FAILED:
        return "failed", reason or str(summary.get("message") or "a load level was not reached")
    if returncode is not None and returncode < 0:
        sig = f"killed by {_signal_name(returncode)}"
        return "crashed", f"{sig}: {reason}" if reason else sig
    if returncode == 0:
        return "crashed", f"exit code 0 but summary.json says status {sstat!r}"
    return "crashed", reason or f"exit code {returncode}"


def record_outcome(run_dir: str, returncode: int | None, wall_time: float,
                   stderr_lines: list[str] | None = None, timed_out: bool = False,
                   timeout: float | None = None, extra: dict | None = None,
                   verdict: tuple[str, str] | None = None) -> Outcome:
    """Classify a finished attempt (unless ``verdict`` gives (status, reason)) and write
    ``run.json``; ``stderr_lines`` defaults to the lines of log.txt."""
    if verdict is not None:
        status, reason = verdict
    else:
        if stderr_lines is None:
            stderr_lines = last_attempt((_read_text(os.path.join(run_dir, "log.txt")) or "").splitlines())
        status, reason = classify(run_dir, returncode, stderr_lines, timed_out, timeout)
    record = _read_json(os.path.join(run_dir, "run.json")) or {}
    record.update(extra or {})
    record.update({"status": status, "reason": reason, "wall_time": wall_time,
                   "returncode": returncode, "finished": time.strftime("%Y-%m-%dT%H:%M:%S")})
    atomic_write(os.path.join(run_dir, "run.json"), json.dumps(record, indent=1) + "\n")
    return Outcome(status, reason, wall_time, returncode)


#: first line of each attempt in an appended log.txt (SLURM resubmissions)
ATTEMPT_HEADER = "=== ancf-sweep attempt"


def last_attempt(lines: list[str]) -> list[str]:
    """The lines of the last attempt in a log that resubmissions append to."""
    starts = [i for i, ln in enumerate(lines) if ln.startswith(ATTEMPT_HEADER)]
    return lines[starts[-1] + 1:] if starts else lines


def finish_slurm_task(run_dir: str, returncode: int, wall_time: float,
                      timeout: float | None = None) -> Outcome:
    """Record a run executed by the SLURM script (exit code 124 of ``timeout`` = time limit)."""
    return record_outcome(run_dir, returncode, wall_time, None,
                          timed_out=timeout is not None and returncode == 124, timeout=timeout,
                          extra={"host": socket.gethostname(),
                                 "slurm_job": os.environ.get("SLURM_ARRAY_JOB_ID"),
                                 "slurm_task": os.environ.get("SLURM_ARRAY_TASK_ID")})


def _child_env() -> dict[str, str]:
    env = dict(os.environ)
    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
        env.setdefault(k, "1")      # ranks x jobs processes: BLAS threads would only contend
    env.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")   # jobs x ranks may exceed the cores
    return env


def _kill(proc: subprocess.Popen) -> None:
    """Terminate the run's process group (it was started in its own session), then kill it."""
    for sig, grace in ((signal.SIGTERM, 5.0), (signal.SIGKILL, 10.0)):
        try:
            os.killpg(proc.pid, sig)
        except (ProcessLookupError, PermissionError):
            pass
        try:
            proc.wait(timeout=grace)
            return
        except subprocess.TimeoutExpired:
            continue


class _Active:
    """The processes currently running, so an interrupt can stop them."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.procs: set[subprocess.Popen] = set()
        self.cancelled = threading.Event()

    def cancel(self) -> None:
        self.cancelled.set()
        with self.lock:
            procs = list(self.procs)
        for p in procs:
            _kill(p)


def execute_run(sweep: Sweep, run: RunSpec, active: _Active | None = None) -> Outcome:
    """Run one prepared run directory; writes log.txt and run.json, returns the outcome."""
    active = active or _Active()
    cmd = solve_command(sweep, run)              # decides on a restart from summary.json
    if "--restart" not in cmd:
        _remove(os.path.join(run.dir, "summary.json"))
    _remove(os.path.join(run.dir, "run.json"))
    atomic_write(os.path.join(run.dir, "run.json"), json.dumps(
        {"status": "running", "started": time.strftime("%Y-%m-%dT%H:%M:%S"),
         "host": socket.gethostname(), "sweep_pid": os.getpid(), "ranks": sweep.ranks,
         "command": shlex.join(cmd)}, indent=1) + "\n")
    stderr_lines: list[str] = []
    t0 = time.monotonic()
    with open(os.path.join(run.dir, "log.txt"), "wb", buffering=0) as log:
        log.write(("$ " + shlex.join(cmd) + "\n").encode())
        try:
            proc = subprocess.Popen(cmd, cwd=run.dir, env=_child_env(), stdin=subprocess.DEVNULL,
                                    stdout=log, stderr=subprocess.PIPE, start_new_session=True)
        except OSError as exc:
            msg = f"cannot start {cmd[0]}: {exc.strerror}"
            log.write((msg + "\n").encode())
            return record_outcome(run.dir, None, time.monotonic() - t0, verdict=("crashed", msg))
        with active.lock:
            active.procs.add(proc)

        def pump() -> None:
            for raw in proc.stderr:             # type: ignore[union-attr]
                log.write(raw)
                stderr_lines.append(raw.decode(errors="replace"))

        reader = threading.Thread(target=pump, daemon=True)
        reader.start()
        timed_out = False
        try:
            rc = proc.wait(timeout=sweep.timeout)
        except subprocess.TimeoutExpired:
            timed_out = True
            _kill(proc)
            rc = proc.returncode
        finally:
            with active.lock:
                active.procs.discard(proc)
        reader.join(timeout=10.0)
    wall = time.monotonic() - t0
    if active.cancelled.is_set() and not timed_out and rc != 0:
        return record_outcome(run.dir, rc, wall,
                              verdict=("crashed", "interrupted (ancf-sweep stopped)"))
    return record_outcome(run.dir, rc, wall, stderr_lines, timed_out=timed_out,
                          timeout=sweep.timeout)


# --------------------------------------------------------------------------- running a sweep
@dataclass
class SweepReport:
    """What one local execution did."""
    runs: list[RunSpec]
    outcomes: dict[str, Outcome]    # run id -> outcome, for the runs executed now
    skipped: list[str]              # run ids already completed
    interrupted: bool = False

    def counts(self) -> dict[str, int]:
        c = {s: 0 for s in FINAL_STATUSES}
        for o in self.outcomes.values():
            c[o.status] = c.get(o.status, 0) + 1
        return c

    def ok(self) -> bool:
        return not self.interrupted and all(o.status == "completed" for o in self.outcomes.values())

    def summary_line(self) -> str:
        """``12 runs: 10 completed, 1 failed, 1 skipped (already done)``."""
        c = self.counts()
        parts = [f"{c['completed']} completed"]
        parts += [f"{n} {s}" for s, n in c.items() if s != "completed" and n]
        if self.skipped:
            parts.append(f"{len(self.skipped)} skipped (already done)")
        not_run = len(self.runs) - len(self.outcomes) - len(self.skipped)
        if not_run:
            parts.append(f"{not_run} not run (interrupted)")
        return f"{len(self.runs)} runs: " + ", ".join(parts)


def progress_line(run: RunSpec, n: int, outcome: Outcome | None = None, event: str = "") -> str:
    """``[sweep] 3/12 run_0003__... completed in 4.2 s`` (or ``failed: <reason> (4.2 s)``)."""
    head = f"[sweep] {run.index + 1}/{n} {run.run_id}"
    if outcome is None:
        return f"{head} {event}"
    t = f"{outcome.wall_time:.1f} s" if outcome.wall_time is not None else "?"
    if outcome.status == "completed":
        return f"{head} completed in {t}"
    return f"{head} {outcome.status}: {outcome.reason or 'no reason given'} ({t})"


def run_sweep(sweep: Sweep, force: bool = False,
              log: Callable[[str], None] = print) -> SweepReport:
    """Run every run not already completed, ``sweep.jobs`` at a time; one line per start/end."""
    runs = expand(sweep)
    n = len(runs)
    os.makedirs(sweep.output, exist_ok=True)
    todo: list[RunSpec] = []
    report = SweepReport(runs, {}, [])
    for run in runs:
        done = prepare_run(sweep, run)
        if done and not force:
            report.skipped.append(run.run_id)
            log(progress_line(run, n, event="skipped (already done)"))
        else:
            todo.append(run)
    lock = threading.Lock()
    queue = list(reversed(todo))
    active = _Active()

    def say(line: str) -> None:
        with lock:
            log(line)

    def worker() -> None:
        while not active.cancelled.is_set():
            with lock:
                if not queue:
                    return
                run = queue.pop()
            ranks = f" on {sweep.ranks} ranks" if sweep.ranks > 1 else ""
            say(progress_line(run, n, event=f"started{ranks}"))
            try:
                outcome = execute_run(sweep, run, active)
            except OSError as exc:
                outcome = Outcome("crashed", f"ancf-sweep: {exc}", None, None)
            with lock:
                report.outcomes[run.run_id] = outcome
            say(progress_line(run, n, outcome))

    threads = [threading.Thread(target=worker, daemon=True)
               for _ in range(max(1, min(sweep.jobs, len(todo))))] if todo else []
    for t in threads:
        t.start()
    try:
        while any(t.is_alive() for t in threads):
            for t in threads:
                t.join(timeout=0.2)
    except KeyboardInterrupt:
        report.interrupted = True
        active.cancel()
        for t in threads:
            t.join(timeout=30.0)
    return report


# ------------------------------------------------------------------------------ collection
@dataclass
class RunState:
    """The state of one run directory as collection sees it."""
    run: RunSpec
    status: str                     # FINAL_STATUSES, 'running' or 'missing'
    reason: str = ""
    load_factor: float | None = None
    probes: dict[str, list] = field(default_factory=dict)
    newton_iterations: int | None = None
    wall_time: float | None = None


def run_state(run: RunSpec) -> RunState:
    """Combine summary.json (solver) and run.json (sweep) of one run directory."""
    summary = _read_json(os.path.join(run.dir, "summary.json"))
    record = _read_json(os.path.join(run.dir, "run.json"))
    st = RunState(run, "missing")
    sstat = summary.get("status") if summary else None
    rstat = record.get("status") if record else None
    if sstat in DONE_STATUSES:
        st.status = sstat
        st.reason = str(summary.get("message") or "") if sstat != "completed" else ""  # type: ignore[union-attr]
    elif rstat in FAILED_STATUSES:
        st.status, st.reason = rstat, str(record.get("reason") or "")  # type: ignore[union-attr]
    elif sstat in ("failed", "interrupted"):
        st.status, st.reason = sstat, str(summary.get("message") or "")  # type: ignore[union-attr]
    elif sstat == "running" or rstat == "running":
        st.status = "running"
        st.reason = "running, or died without a record (rerun the sweep to redo it)"
    elif os.path.isdir(run.dir):
        st.reason = "not run yet"
    else:
        st.reason = "run directory missing"
    if summary:
        steps = summary.get("steps") or []
        if steps:
            st.load_factor = steps[-1].get("load_factor")
            st.probes = {k: v.get("displacement") for k, v in (steps[-1].get("probes") or {}).items()}
        its = summary.get("newton_iterations")
        st.newton_iterations = its if its is not None else sum(s.get("iterations") or 0 for s in steps)
        st.wall_time = (summary.get("timings") or {}).get("total")
    if record and record.get("wall_time") is not None and rstat != "running":
        st.wall_time = record["wall_time"]
    return st


def _csv_value(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, str):
        return v
    return json.dumps(v, default=str)


@dataclass
class Collection:
    """Collected states with the paths of results.csv and failed.txt."""
    states: list[RunState]
    csv_path: str
    failed_path: str

    def counts(self) -> dict[str, int]:
        c = {s: 0 for s in STATUS_ORDER}
        for s in self.states:
            c[s.status] += 1
        return c

    def all_completed(self) -> bool:
        return all(s.status == "completed" for s in self.states)

    def summary_line(self) -> str:
        c = self.counts()
        parts = [f"{c['completed']} completed"] + [f"{n} {s}" for s, n in c.items()
                                                   if s != "completed" and n]
        return f"{len(self.states)} runs: " + ", ".join(parts)


def collect(sweep: Sweep) -> Collection:
    """Write ``<output>/results.csv`` (one row per run) and ``<output>/failed.txt``."""
    states = [run_state(r) for r in expand(sweep)]
    probes: list[str] = []
    for s in states:
        for name in s.probes:
            if name not in probes:
                probes.append(name)
    header = (["run_id"] + [p.path for p in sweep.parameters] + ["status", "reason", "load_factor"]
              + [f"{p}_{c}" for p in probes for c in ("dx", "dy", "dz")]
              + ["newton_iterations", "wall_time"])
    os.makedirs(sweep.output, exist_ok=True)
    csv_path = os.path.join(sweep.output, "results.csv")
    tmp = csv_path + f".tmp{os.getpid()}"
    with open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for s in states:
            row = [s.run.run_id] + [_csv_value(s.run.params[p.path]) for p in sweep.parameters]
            row += [s.status, s.reason, _csv_value(s.load_factor)]
            for p in probes:
                d = s.probes.get(p) or [None, None, None]
                row += [_csv_value(x) for x in d]
            row += [_csv_value(s.newton_iterations),
                    f"{s.wall_time:.3f}" if s.wall_time is not None else ""]
            w.writerow(row)
    os.replace(tmp, csv_path)
    failed_path = os.path.join(sweep.output, "failed.txt")
    lines = [f"{s.run.run_id}\t{s.status}\t{s.reason}" for s in states if s.status in FAILED_STATUSES]
    atomic_write(failed_path, "".join(ln + "\n" for ln in lines))
    return Collection(states, csv_path, failed_path)


# ----------------------------------------------------------------------------------- SLURM
def _slurm_time(sweep: Sweep) -> str | None:
    """``--time``: slurm.time, else the run's timeout plus a start-up margin, else none."""
    if sweep.slurm.time is not None:
        return sweep.slurm.time
    if sweep.timeout is None:
        return None
    minutes = int(sweep.timeout // 60) + 2
    return f"{minutes // 60:02d}:{minutes % 60:02d}:00"


def default_venv() -> str | None:
    """The virtual environment running this program, if it has ancf-solve."""
    prefix = sys.prefix
    if prefix != getattr(sys, "base_prefix", prefix) and \
            os.path.isfile(os.path.join(prefix, "bin", "ancf-solve")):
        return prefix
    return None


def write_slurm(sweep: Sweep, force: bool = False) -> tuple[str, str]:
    """Prepare every run directory and write ``sweep.slurm`` + ``runs.txt``; returns their paths.

    Array task i runs line i+1 of runs.txt; ``tasks/<i>`` links to that run directory so that
    SLURM's ``--output`` lands in the run directory itself.  Resources come from ``sweep.slurm``;
    the environment is ``$ANCF_VENV`` at submission, else slurm.venv, else the one running this."""
    runs = expand(sweep)
    os.makedirs(sweep.output, exist_ok=True)
    for run in runs:
        prepare_run(sweep, run)
        if force:
            _remove(os.path.join(run.dir, "summary.json"), os.path.join(run.dir, "run.json"))
    runs_txt = os.path.join(sweep.output, "runs.txt")
    atomic_write(runs_txt, "".join(r.dir + "\n" for r in runs))
    tasks = os.path.join(sweep.output, "tasks")
    os.makedirs(tasks, exist_ok=True)
    for old in os.listdir(tasks):
        if os.path.islink(os.path.join(tasks, old)):
            os.remove(os.path.join(tasks, old))
    for r in runs:
        os.symlink(os.path.join("..", r.run_id), os.path.join(tasks, str(r.index)))

    q = shlex.quote
    n = len(runs)
    sl = sweep.slurm
    throttle = f"%{sl.throttle}" if sl.throttle is not None and sl.throttle < n else ""
    venv = sl.venv or default_venv()
    petsc = (" " + shlex.join(sweep.petsc)) if sweep.petsc else ""
    sweep_cmd = f"ancf-sweep {q(sweep.file)} --collect"
    record = ("import sys; from ancf_petsc.workflows.sweep import finish_slurm_task as f; "
              "o = f(sys.argv[1], int(sys.argv[2]), float(sys.argv[4]) - float(sys.argv[3]), "
              f"{sweep.timeout!r}); print(vars(o))")
    lines = [
        "#!/bin/bash",
        f"#SBATCH --job-name={sweep.name}",
        f"#SBATCH --array=0-{n - 1}{throttle}",
        f"#SBATCH --ntasks={sweep.ranks}",
        f"#SBATCH --output={os.path.join(sweep.output, 'tasks', '%a', 'slurm-%A_%a.out')}",
    ]
    time_limit = _slurm_time(sweep)
    for option, value in (("time", time_limit), ("cpus-per-task", sl.cpus_per_task), ("mem", sl.mem),
                          ("partition", sl.partition), ("account", sl.account)):
        if value is not None:
            lines.append(f"#SBATCH --{option}={value}")
    lines += [
        f"# Sweep {sweep.name}: {n} runs ({sweep.shape()}) of {sweep.base}",
        f"# generated by ancf-sweep from {sweep.file}",
        "#",
        f"# Submit:   sbatch {q(os.path.join(sweep.output, 'sweep.slurm'))}",
        "#           (ANCF_VENV=/path/to/venv sbatch ... runs another environment's ancf-solve)",
        f"# Collect:  {sweep_cmd}",
        "#           (results.csv and failed.txt in the output directory; works while tasks still run)",
        "# Array task i runs the directory on line i+1 of runs.txt and skips it if its",
        "# summary.json already says completed (or unstable), so resubmitting only redoes what is",
        "# missing; log.txt " + ("gets one more section per attempt" if sl.logs == "append" else
                                 "is a link to log.N.txt, N counting the attempts") + ".",
        "set -u",
        "# at the time limit SLURM signals the tasks and this shell: the shell waits for ancf-solve",
        "# (which stops at its next safe point, status interrupted) and then records the outcome",
        "trap 'echo \"ancf-sweep: task signalled; waiting for ancf-solve to stop cleanly\" >&2' TERM INT",
        f"SWEEP_OUTPUT={q(sweep.output)}",
    ]
    if venv is not None:
        lines += [f'VENV="${{ANCF_VENV:-{venv}}}"',
                  'PYTHON="$VENV/bin/python"',
                  'ANCF_SOLVE=("$VENV/bin/ancf-solve")']
    else:
        lines += ['VENV="${ANCF_VENV:-}"',
                  f'if [ -n "$VENV" ]; then PYTHON="$VENV/bin/python"; ANCF_SOLVE=("$VENV/bin/ancf-solve"); '
                  f"else PYTHON={q(sys.executable)}; ANCF_SOLVE=({shlex.join(solver_command())}); fi"]
    lines += [
        f"RANKS={sweep.ranks}",
        'TASK="${SLURM_ARRAY_TASK_ID:?not running as a SLURM array task}"',
        'RUN_DIR=$(sed -n "$((TASK + 1))p" "$SWEEP_OUTPUT/runs.txt")',
        'if [ -z "$RUN_DIR" ] || [ ! -f "$RUN_DIR/config.yaml" ]; then',
        '  echo "ancf-sweep: array task $TASK has no run directory in $SWEEP_OUTPUT/runs.txt" >&2',
        "  exit 1",
        "fi",
        'if [ ! -x "${ANCF_SOLVE[0]}" ] && ! command -v "${ANCF_SOLVE[0]}" >/dev/null 2>&1; then',
        '  echo "ancf-sweep: no ancf-solve at ${ANCF_SOLVE[0]} (set ANCF_VENV or slurm.venv)" >&2',
        "  exit 1",
        "fi",
        "if \"$PYTHON\" -c 'import json, sys; sys.exit(json.load(open(sys.argv[1])).get(\"status\") "
        "not in (\"completed\", \"unstable\"))' \"$RUN_DIR/summary.json\" 2>/dev/null; then",
        '  echo "ancf-sweep: $RUN_DIR already done; skipping"',
        "  exit 0",
        "fi",
        'if command -v srun >/dev/null 2>&1; then LAUNCH=(srun --ntasks="${SLURM_NTASKS:-$RANKS}")',
        'else LAUNCH=(mpirun -n "$RANKS"); fi',
    ]
    if sweep.timeout is not None:
        lines.append(f"LAUNCH=(timeout --signal=TERM --kill-after=30 {sweep.timeout:g} "
                     '"${LAUNCH[@]}")')
    if sl.logs == "numbered":
        lines += ['N=1; while [ -e "$RUN_DIR/log.$N.txt" ]; do N=$((N + 1)); done',
                  'LOG="$RUN_DIR/log.$N.txt"; : > "$LOG"; ln -sfn "log.$N.txt" "$RUN_DIR/log.txt"']
    else:
        lines += ['LOG="$RUN_DIR/log.txt"']
    lines += [
        'export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"',
        'export OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"',
        'rm -f "$RUN_DIR/run.json"',
        'echo "ancf-sweep: task $TASK: $RUN_DIR on $(hostname), $RANKS rank(s)"',
        f'echo "{ATTEMPT_HEADER}: job ${{SLURM_ARRAY_JOB_ID:-?}}_$TASK on $(hostname) at '
        '$(date +%Y-%m-%dT%H:%M:%S) ===" >> "$LOG"',
        "START=$(date +%s.%N)",
        # a task killed at the time limit (interrupted) or with its node (running) goes on from
        # its last converged level when the array is submitted again
        'WHERE=(--output-dir "$RUN_DIR")',
        "if \"$PYTHON\" -c 'import json, os, sys; s = json.load(open(sys.argv[1])); "
        "sys.exit(not (s.get(\"status\") in (\"interrupted\", \"running\") and s.get(\"steps\") "
        "and os.path.exists(sys.argv[2])))' \"$RUN_DIR/summary.json\" \"$RUN_DIR/results.h5\" 2>/dev/null; then",
        '  WHERE=(--restart "$RUN_DIR"); echo "ancf-sweep: continuing $RUN_DIR from its last converged level"',
        "fi",
        '"${LAUNCH[@]}" "${ANCF_SOLVE[@]}" "$RUN_DIR/config.yaml" "${WHERE[@]}"'
        f'{petsc} >> "$LOG" 2>&1',
        "RC=$?",
        "END=$(date +%s.%N)",
        f"\"$PYTHON\" -c {q(record)} \"$RUN_DIR\" \"$RC\" \"$START\" \"$END\"",
        'exit "$RC"',
    ]
    script = os.path.join(sweep.output, "sweep.slurm")
    atomic_write(script, "\n".join(lines) + "\n")
    os.chmod(script, 0o755)
    return script, runs_txt
