"""Registries that find their entries themselves: every module of a package that binds a named
object (an outline format's ``IMPORTER``, an element's ``ELEMENT``) is one entry, so that adding
one is one new module (outline_formats, physics/elements)."""
from __future__ import annotations

import importlib
import pkgutil


def discover(path: list[str], package: str, attribute: str, kind: str) -> dict[str, tuple[str, object]]:
    """name → (module, object) of every module of ``package`` (its ``__path__``: ``path``) that
    binds ``attribute`` (an object with a ``name``), in the modules' order; two of one name are an
    ImportError naming both ("{kind} a and b are both named 'x'")."""
    found: dict[str, tuple[str, object]] = {}
    for info in pkgutil.iter_modules(path):
        obj = getattr(importlib.import_module(f"{package}.{info.name}"), attribute, None)
        if obj is None:
            continue
        if obj.name in found:
            raise ImportError(f"{kind} {found[obj.name][0]} and {info.name} are both named {obj.name!r}")
        found[obj.name] = (info.name, obj)
    return found
