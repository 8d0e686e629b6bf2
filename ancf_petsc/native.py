"""Compiled kernels: the Cython modules beside their numpy originals, and which path runs.

``scripts/setup.sh`` builds every ``ancf_petsc/**/*.pyx`` in place (scripts/build_native.py).
``load`` returns the compiled module, or None when it is not built, older than its source, or
switched off by ``ANCF_NATIVE=0`` (for side-by-side checks and benchmarks); callers then run
the numpy code, which stays the reference that the compiled code is tested against.
"""
from __future__ import annotations

import importlib
import os
from types import ModuleType

_loaded: dict[str, ModuleType | None] = {}
_why: dict[str, str] = {}


def enabled() -> bool:
    """False when ``ANCF_NATIVE=0`` is set."""
    return os.environ.get("ANCF_NATIVE", "1") != "0"


def load(name: str) -> ModuleType | None:
    """The compiled module ``ancf_petsc.<name>`` or None (see the module docstring)."""
    if not enabled():
        return None
    if name not in _loaded:
        _loaded[name] = _import(name)
    return _loaded[name]


def _import(name: str) -> ModuleType | None:
    pyx = os.path.join(os.path.dirname(__file__), *name.split(".")) + ".pyx"
    try:
        module = importlib.import_module(f"{__package__}.{name}")
    except ImportError as exc:
        _why[name] = f"not built ({exc}): run scripts/setup.sh"
        return None
    if os.path.exists(pyx) and os.path.getmtime(pyx) > os.path.getmtime(module.__file__):
        _why[name] = f"{os.path.basename(module.__file__)} is older than its source: run scripts/setup.sh"
        return None
    return module


def status(name: str) -> str:
    """'compiled', or why the numpy path runs."""
    if not enabled():
        return "numpy (ANCF_NATIVE=0)"
    return "compiled" if load(name) is not None else f"numpy: {_why.get(name, 'unknown')}"
