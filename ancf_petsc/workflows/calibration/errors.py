"""The fit file's error type and the small value checks its parser uses (each names its key)."""
from __future__ import annotations

import math
from typing import Any

from ...errors import InputError


class CalibrationError(InputError):
    """A problem with a fit file or its data; ``path`` is the key in the fit file
    (e.g. ``parameters[0].bounds``), ``message`` what is wrong and the fix."""


def expect(cond: bool, path: str, message: str) -> None:
    if not cond:
        raise CalibrationError(path, message)


def number(value: Any, path: str, positive: bool = False) -> float:
    """A finite number (YAML may give 1e6 as a string); ``positive``: > 0."""
    try:
        ok = not isinstance(value, bool) and math.isfinite(float(value))
    except (TypeError, ValueError):
        ok = False
    expect(ok, path, f"expected a number; got {value!r}")
    value = float(value)
    expect(not positive or value > 0, path, f"must be > 0; got {value:g}")
    return value


def integer(value: Any, path: str, lo: int = 1) -> int:
    expect(isinstance(value, int) and not isinstance(value, bool) and value >= lo, path,
           f"expected an integer >= {lo}; got {value!r}")
    return value


class CalibrationInterrupted(Exception):
    """A signal stopped the calibration (on every rank) after the samples logged so far."""

    def __init__(self, signum: int):
        super().__init__(f"stopped by signal {signum}")
        self.signum = signum
