"""A sweep's runs: the parameter values of each, its directory with the substituted config, and whether
it is already done."""
from __future__ import annotations

import contextlib
import copy
import hashlib
import itertools
import json
import os
import re
from typing import Any

import yaml

from ... import yamlio
from ...io.files import atomic_write, remove_quietly
from .base import DONE_STATUSES, SweepError, read_json, read_text, set_key_path
from .spec import RunSpec, Sweep


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


def check_values(sweep: Sweep, runs: list[RunSpec]) -> None:
    """Refuse a swept value the model config refuses (``elements: 0``, ``mu: -1``), before any run
    starts: such a value was found only when its runs ran, each a ``config_error`` after the others
    had taken their time (on a cluster, after the array was queued).  Each value of each parameter
    is parsed once, in the first run that has it (config.parse, no model built)."""
    from ...config.parse import parse_config
    from ...errors import InputError
    seen: set = set()
    for run in runs:
        new = {(p.path, repr(run.params[p.path])) for p in sweep.parameters} - seen
        if not new:
            continue
        seen |= new
        raw = copy.deepcopy(sweep.base_raw)
        for p in sweep.parameters:
            set_key_path(raw, p.tokens, run.params[p.path])
        try:
            parse_config(raw, base_dir=sweep.base_dir, source=f"run {run.run_id}")
        except InputError as exc:
            swept = next((p.path for p in sweep.parameters if exc.path.startswith(p.path)), None)
            values = ", ".join(f"{k}={v!r}" for k, v in run.params.items())
            raise SweepError(f"parameters.{swept}" if swept else "parameters",
                             f"run {run.run_id} ({values}) is no valid config: {exc}") from None


def run_config(sweep: Sweep, run: RunSpec) -> dict:
    """The run's model config: base + values, output.dir = run dir (every launch passes the run
    directory on the command line too), and the base's data files (``beams[].section.file``,
    ``file`` and ``source`` under ``geometry.sections``, ``history.file``) relative to the run
    directory, where
    config.yaml lives: a sweep directory moved with its data keeps working (``_relocate``)."""
    raw = copy.deepcopy(sweep.base_raw)
    for p in sweep.parameters:
        set_key_path(raw, p.tokens, run.params[p.path])
    out = raw.get("output")
    if not isinstance(out, dict):
        out = raw["output"] = {}
    out["dir"] = run.dir
    for beam in raw.get("beams") or []:
        sec = beam.get("section") if isinstance(beam, dict) else None
        if isinstance(sec, dict):
            _relocate(sec, ("file",), sweep.base_dir, run.dir)
    geo = raw.get("geometry")
    if isinstance(geo, dict) and geo.get("sections") is not None:
        geo["sections"] = _relocated_tree(geo["sections"], sweep.base_dir, run.dir)
    if isinstance(raw.get("history"), dict):
        _relocate(raw["history"], ("file",), sweep.base_dir, run.dir)
    return raw


def _relocate(mapping: dict, keys: tuple, base_dir: str, run_dir: str) -> None:
    """A relative file path of the base config, made relative to the run directory instead
    (absolute if the two share no directory but the root: no relative path survives a move)."""
    for key in keys:
        f = mapping.get(key)
        if isinstance(f, str) and f and not os.path.isabs(f):
            path = os.path.normpath(os.path.join(base_dir, f))
            shared = os.path.commonpath([path, os.path.abspath(run_dir)]) != os.sep
            mapping[key] = os.path.relpath(path, run_dir) if shared else path


def _relocated_tree(value: Any, base_dir: str, run_dir: str) -> Any:
    """``_relocate`` of every ``file`` / ``source`` in a ``geometry.sections`` value."""
    if isinstance(value, dict):
        value = {k: _relocated_tree(v, base_dir, run_dir) for k, v in value.items()}
        _relocate(value, ("file", "source"), base_dir, run_dir)
    elif isinstance(value, list):
        value = [_relocated_tree(v, base_dir, run_dir) for v in value]
    return value


def config_text(sweep: Sweep, run: RunSpec) -> str:
    """The exact text of the run's config.yaml (deterministic, so reruns can compare it)."""
    head = [f"# generated by ancf-sweep: sweep {sweep.name}, run {run.run_id}",
            f"# base config: {sweep.base}"]
    head += [f"#   {k} = {json.dumps(v, default=str)}" for k, v in run.params.items()]
    return "\n".join(head) + "\n" + yaml.safe_dump(run_config(sweep, run), sort_keys=False)


def _unplaced(text: str | None) -> Any:
    """A run's config.yaml without ``output.dir``, the one value a move of the sweep changes
    (data file paths are relative to the run directory; the head's comments are not read)."""
    try:
        raw = yaml.safe_load(text) if text is not None else None
    except yaml.YAMLError:
        return None
    if isinstance(raw, dict) and isinstance(raw.get("output"), dict):
        raw["output"].pop("dir", None)
    return raw


def input_files(sweep: Sweep, run: RunSpec) -> dict[str, str]:
    """The data files the run reads (``file`` / ``source`` of its config and of the geometry
    files it names), as the config names them from the run directory -> a digest of each."""
    found: dict[str, str] = {}
    _digest_named(run_config(sweep, run), run.dir, run.dir, found, 0)
    return found


def refresh_inputs(run_dir: str) -> str | None:
    """A SLURM task's check (it has no sweep file) that the data files its config.yaml names are
    the ones its result was solved with (params.json ``inputs``): if not, the result is cleared
    (the task solves it again) and the new digests are recorded; returns the first file edited."""
    params = read_json(os.path.join(run_dir, "params.json")) or {}
    raw = _unplaced(read_text(os.path.join(run_dir, "config.yaml")))
    if "inputs" not in params or raw is None:
        return None
    found: dict[str, str] = {}
    _digest_named(raw, run_dir, run_dir, found, 0)
    edited = _edited(params["inputs"], found)
    if not edited:
        return None
    remove_quietly(os.path.join(run_dir, "summary.json"), os.path.join(run_dir, "run.json"))
    atomic_write(os.path.join(run_dir, "params.json"),
                 json.dumps(dict(params, inputs=found), indent=1, default=str) + "\n")
    return edited[0]


def _edited(old: dict, now: dict) -> list[str]:
    """The files whose digest is not the recorded one (one unreadable now says nothing of a result
    on disk: a sweep copied without its data keeps its runs)."""
    return sorted(n for n in set(old) | set(now) if now.get(n, "missing") not in (old.get(n), "missing"))


def _digest_named(value: Any, here: str, run_dir: str, found: dict[str, str], depth: int) -> None:
    if isinstance(value, list):
        for v in value:
            _digest_named(v, here, run_dir, found, depth)
    elif isinstance(value, dict):
        for key, v in value.items():
            if key not in ("file", "source") or not isinstance(v, str) or not v:
                _digest_named(v, here, run_dir, found, depth)
                continue
            path = os.path.normpath(os.path.join(here, v))
            shared = os.path.commonpath([path, os.path.abspath(run_dir)]) != os.sep
            name = os.path.relpath(path, run_dir) if shared else path
            if name in found:
                continue
            found[name] = _digest(path)
            if depth < 3 and found[name] != "missing" and os.path.getsize(path) < 1 << 20:
                with contextlib.suppress(Exception):     # a geometry file's own files; else none
                    _digest_named(yamlio.load(yamlio.read_text(path)), os.path.dirname(path),
                                  run_dir, found, depth + 1)


_DIGESTS: dict[tuple, str] = {}


def _digest(path: str) -> str:
    """sha256 of a file's bytes (16 hex digits; 'missing' if unreadable), kept per path, mtime, size."""
    try:
        st = os.stat(path)
        key = (path, st.st_mtime_ns, st.st_size)
        if key not in _DIGESTS:
            with open(path, "rb") as fh:
                _DIGESTS[key] = hashlib.sha256(fh.read()).hexdigest()[:16]
        return _DIGESTS[key]
    except OSError:
        return "missing"


def same_config(sweep: Sweep, run: RunSpec) -> bool:
    """The run directory's config.yaml is the one this sweep would write now, wherever the sweep
    directory was prepared (a sweep moved to another machine keeps its runs), and its
    params.json names the sweep's run.petsc and the data files' contents as they are now (one
    written before it named them: taken as the same)."""
    old = _unplaced(read_text(os.path.join(run.dir, "config.yaml")))
    params = read_json(os.path.join(run.dir, "params.json")) or {}
    petsc = params.get("petsc", sweep.petsc)
    if old is None or old != _unplaced(config_text(sweep, run)) or petsc != sweep.petsc:
        return False
    return "inputs" not in params or not _edited(params["inputs"], input_files(sweep, run))


def is_done(sweep: Sweep, run: RunSpec) -> bool:
    """Completed (or unstable: a rerun gives the same), with the config this sweep would write
    now (``same_config``)."""
    summary = read_json(os.path.join(run.dir, "summary.json"))
    return (summary is not None and summary.get("status") in DONE_STATUSES
            and same_config(sweep, run))


def prepare_run(sweep: Sweep, run: RunSpec) -> bool:
    """Write ``config.yaml`` and ``params.json``; True if a completed result of this config exists.

    A run directory whose config, PETSc options or data files differ from the current ones (the
    sweep, its base config or a file they name was edited) loses its summary.json/run.json, so
    neither this tool nor a SLURM task skips it; one only moved (``same_config``) keeps them and
    gets its new ``output.dir``."""
    os.makedirs(run.dir, exist_ok=True)
    cfg_path = os.path.join(run.dir, "config.yaml")
    text = config_text(sweep, run)
    old = read_text(cfg_path)
    if old is not None and not same_config(sweep, run):
        remove_quietly(os.path.join(run.dir, "summary.json"), os.path.join(run.dir, "run.json"))
    if old != text:
        atomic_write(cfg_path, text)
    params = {"sweep": sweep.name, "sweep_file": sweep.file, "base": sweep.base,
              "run_id": run.run_id, "index": run.index, "parameters": run.params, "petsc": sweep.petsc,
              "inputs": input_files(sweep, run)}
    atomic_write(os.path.join(run.dir, "params.json"),
                  json.dumps(params, indent=1, default=str) + "\n")
    return is_done(sweep, run)
