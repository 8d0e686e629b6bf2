"""Sweep vocabulary and small helpers: statuses, the sweep-file error, YAML loading, key paths into a
config (``beams[0].material.mu``)."""
from __future__ import annotations

import copy
import json
import os
import re
from typing import Any

import yaml

from ... import yamlio

from ...errors import InputError

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


class SweepError(InputError):
    """A problem with a sweep file; ``path`` is the key in the sweep file (e.g. ``run.jobs``)."""


class SweepLoader(yamlio.StrictLoader):
    """SafeLoader that also reads ``1e6`` and ``0.86e9`` as floats (YAML 1.2 style)."""


SweepLoader.add_implicit_resolver(
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


def path_exists(raw: Any, tokens: tuple[Token, ...]) -> bool:
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
    """Set ``raw[tokens] = value`` in place, creating missing mappings on the way; each container
    on the way becomes the key path's own (a YAML anchor's node is one object under every alias:
    ``beams[0].material.mu`` set the mu of every beam written ``material: *m``)."""
    node = raw
    for tok in tokens[:-1]:
        if isinstance(tok, str) and tok not in node:
            node[tok] = {}
        else:
            node[tok] = copy.copy(node[tok])
        node = node[tok]
    node[tokens[-1]] = copy.deepcopy(value)


def load_yaml(path: str, key: str, loader: type = yamlio.StrictLoader) -> Any:
    """Load a YAML file; errors name ``key`` (and the path, unless it is the sweep file itself)."""
    where = f"{path}: " if key else ""
    if os.path.isdir(path):
        raise SweepError(key, f"{path}: is a directory, not a YAML file" if key else "is a directory, not a YAML file")
    if not os.path.isfile(path):
        raise SweepError(key, f"no such file: {path}" if key else "no such file")
    try:
        return yamlio.load(yamlio.read_text(path), loader)
    except UnicodeDecodeError:
        raise SweepError(key, f"{where}not a text (UTF-8) YAML file") from None
    except yaml.YAMLError as exc:
        raise SweepError(key, f"{where}{yamlio.syntax_error(exc)}") from None
    except OSError as exc:
        raise SweepError(key, f"{where}cannot read: {exc.strerror}") from None


def as_int(value: Any, path: str, lo: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < lo:
        raise SweepError(path, f"expected an integer >= {lo}; got {value!r}")
    return value


def as_str(value: Any, path: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise SweepError(path, f"expected a non-empty string; got {value!r}")
    return value


def read_text(path: str) -> str | None:
    try:
        with open(path) as fh:
            return fh.read()
    except OSError:
        return None


def read_json(path: str) -> dict | None:
    try:
        with open(path) as fh:
            data = json.load(fh)
        return data if isinstance(data, dict) else None
    except (OSError, ValueError):
        return None
