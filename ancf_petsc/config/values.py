"""Validators for config values: each checks one value and names its key path in the error."""
from __future__ import annotations

import reprlib

import math
import numbers

from ..errors import MISSING_KEY, UNKNOWN_KEY, InputError

#: a config problem: ``path`` is the key path (e.g. ``beams[0].material.mu``); see errors.py
ConfigError = InputError


# --------------------------------------------------------------------------------- primitives
def key_path(path: str, key) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else str(key)


_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxlist, _REPR.maxdict, _REPR.maxtuple, _REPR.maxstring, _REPR.maxother = 3, 6, 6, 6, 60, 60


def shown(v) -> str:
    """A value for a message, at most ~60 characters: a deeply nested or aliased value (a YAML
    alias "bomb") is shown by its first elements only, never built in full."""
    s = "null" if v is None else _REPR.repr(v)       # YAML's word: a key left empty
    return s if len(s) < 60 else s[:57] + "..."


def mapping(value, path: str, required: tuple = (), optional: tuple = ()) -> dict:
    """Check a mapping with exactly the given keys (required ones present, no unknown ones)."""
    if not isinstance(value, dict):
        keys = list(dict.fromkeys(required + optional))        # each key once, required first
        raise ConfigError(path, f"expected a mapping with keys {', '.join(keys)}; "
                                f"got {type(value).__name__} {shown(value)}")
    allowed = set(required) | set(optional)
    for key in value:
        if key not in allowed:
            raise ConfigError(key_path(path, key), "unknown key; allowed here: "
                              + ", ".join(sorted(allowed)), UNKNOWN_KEY)
    for key in required:
        if key not in value or value[key] is None:
            raise ConfigError(key_path(path, key), "missing value (required)", MISSING_KEY)
    return value


def plain_number(field: str) -> float:
    """A written number (a table cell, a quoted config value), NaN if it is none: float() without
    its underscores between digits ('1_0' is 10 to Python, a typing slip in a table of forces)."""
    try:
        return math.nan if "_" in field else float(field)
    except ValueError:
        return math.nan


def number(value, path: str, *, positive=False, nonneg=False, lo=None, hi=None,
           hint: str = "") -> float:
    """A real number (numpy's too: spec.steps = list(np.arange(1, 5)) was 'expected a number;
    got 1'), or its text."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        if isinstance(value, str):
            text, value = value, plain_number(value)
            if math.isnan(value) and text.strip().lower() not in ("nan", "+nan", "-nan"):
                raise ConfigError(path, f"expected a number{hint}; got {shown(text)}")
        else:
            raise ConfigError(path, f"expected a number{hint}; got {shown(value)}")
    value = float(value)
    if not math.isfinite(value):
        bounds = [b for b, on in (("> 0", positive), (">= 0", nonneg)) if on]
        bounds += [f"{op} {b:g}" for op, b in ((">=", lo), ("<=", hi)) if b is not None]
        raise ConfigError(path, f"must be a finite number{' ' if bounds else ''}{' and '.join(bounds)}"
                                f"{hint}; got {value}")
    if positive and value <= 0:
        raise ConfigError(path, f"must be > 0{hint}; got {value:g}")
    if nonneg and value < 0:
        raise ConfigError(path, f"must be >= 0{hint}; got {value:g}")
    if lo is not None and value < lo:
        raise ConfigError(path, f"must be >= {lo:g}{hint}; got {_beside(value, lo)}")
    if hi is not None and value > hi:
        raise ConfigError(path, f"must be <= {hi:g}{hint}; got {_beside(value, hi)}")
    return value


def _beside(value: float, bound: float) -> str:
    """``value`` for a message beside the bound it breaks: %g, unless that rounds it onto the
    bound's text (kappa 0.33333334 against <= 0.333333), then all its digits."""
    return repr(value) if f"{value:g}" == f"{bound:g}" else f"{value:g}"


def integer(value, path: str, *, lo: int | None = None, hi: int | None = None) -> int:
    """An integer (numpy's too, as a Python int)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ConfigError(path, f"expected an integer; got {shown(value)}")
    value = int(value)
    if lo is not None and value < lo:
        raise ConfigError(path, f"must be >= {lo}; got {value}")
    if hi is not None and value > hi:
        raise ConfigError(path, f"must be <= {hi}; got {value}")
    return value


def spline_degree(value, path: str, hi: int) -> int:
    """A spline degree: 1, 2 or odd up to ``hi`` (even degrees above 2 are not built)."""
    p = integer(value, path, lo=1, hi=hi)
    if p > 2 and p % 2 == 0:
        ok = ", ".join(str(k) for k in range(1, hi + 1) if k <= 2 or k % 2)
        raise ConfigError(path, f"must be one of {ok}: interpolating splines of even degree above 2 are not "
                                f"built (not-a-knot ends need an odd degree); got {p}")
    return p


def string(value, path: str, choices: tuple | None = None) -> str:
    if not isinstance(value, str) or not value:
        what = f"one of {', '.join(choices)}" if choices else "a non-empty string"
        raise ConfigError(path, f"expected {what}; got {shown(value)}")
    if choices is not None and value not in choices:
        raise ConfigError(path, f"must be one of {', '.join(choices)}; got {shown(value)}")
    return value


def boolean(value, path: str) -> bool:
    if not isinstance(value, bool):
        raise ConfigError(path, f"expected true or false; got {shown(value)}")
    return value


def vector(value, path: str, n: int, **kw) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise ConfigError(path, f"expected a list of {n} numbers; got {shown(value)}")
    return tuple(number(v, key_path(path, i), **kw) for i, v in enumerate(value))


def sequence(value, path: str, *, nonempty=True) -> list:
    if not isinstance(value, list):
        raise ConfigError(path, f"expected a list; got {shown(value)}")
    if nonempty and not value:
        raise ConfigError(path, "expected a non-empty list")
    return value
