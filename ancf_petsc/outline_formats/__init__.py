"""Outline file formats: one module per format, each binding ``IMPORTER`` (an :class:`Importer`:
registry name, extensions, per-outline keys, pixels or lengths, own scale, slice, ``read``).
The package finds them itself, so adding a format is one new module here (and its test); config
validation (``config.sections``), ``geometry_input.build`` and the docs read ``FORMATS``.

The third-party readers (Pillow, scikit-image, nibabel, svgelements) are imported only when a file
of theirs is read.  User guide: docs/geometry.md."""
from __future__ import annotations

from ..registry import discover
from .base import Description, Importer, OutlineKey, OutlineReadError, RawOutline

__all__ = ["Description", "FORMATS", "Importer", "OutlineKey", "OutlineReadError", "RawOutline",
           "format_of", "known_types", "outline_keys"]


def _discover() -> dict[str, Importer]:
    """name → importer of every module of this package that binds ``IMPORTER``; no extension
    claimed twice."""
    found: dict[str, Importer] = {}
    for name, (_, imp) in discover(__path__, __name__, "IMPORTER", "outline formats").items():
        for e in imp.extensions:
            other = [n for n, f in found.items() if e in f.extensions]
            if other:
                raise ImportError(f"outline formats {other[0]!r} and {imp.name!r} both claim {e}")
        found[name] = imp
    return found


#: every outline file format, by registry name (OutlineSource.kind)
FORMATS = _discover()


def format_of(path: str) -> Importer | None:
    """The format whose extension ``path`` ends with (the longest match: .nii.gz before .gz)."""
    hits = [(len(m), f) for f in FORMATS.values() if (m := f.matches(path))]
    return max(hits, key=lambda h: h[0])[1] if hits else None


def known_types() -> str:
    """The extensions and what they are, for messages: '.csv/.txt (point list), .svg (SVG drawing) ...'."""
    parts = [f"{'/'.join(f.extensions)} ({f.title})" for f in FORMATS.values()]
    return ", ".join(parts[:-1]) + " or " + parts[-1] if len(parts) > 1 else parts[0]


def outline_keys() -> dict[str, list[Importer]]:
    """Every per-outline key any format reads → the formats that read it."""
    out: dict[str, list[Importer]] = {}
    for f in FORMATS.values():
        for k in f.keys:
            out.setdefault(k.name, []).append(f)
    return out
