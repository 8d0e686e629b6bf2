"""What every outline importer is: its registry name, its file extensions, the per-outline keys
it reads, how its coordinates are to be taken (pixels or lengths, a scale of its own, a slice),
and ``read`` (file → :class:`RawOutline` in the file's coordinates (u, v))."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from ..physics.spline import SectionError

__all__ = ["Description", "Importer", "OutlineKey", "OutlineReadError", "RawOutline", "file_name"]


class OutlineReadError(SectionError):
    """A source file cannot give the requested outline; the message names the file and the fix."""


@dataclass
class RawOutline:
    """An outline as read: (n, 2) points in the file's coordinates (u, v) and units."""
    points: np.ndarray
    closed: bool                              # the source says the outline is closed
    notes: list = field(default_factory=list)
    scale: tuple[float, float] | None = None  # metres per file unit, when the file gives its own


@dataclass(frozen=True)
class OutlineKey:
    """A key of one outline entry that an importer reads (beside ``file``)."""
    name: str
    type: type                    # int or str
    meaning: str                  # for messages: "the label value of this subtendon, e.g. label: 2"
    required: bool = False
    minimum: int | None = None    # int keys: the smallest value


class Description(Protocol):
    """What a reader may ask of the geometry description it reads for (config.sections)."""
    units: str
    scale: tuple[float, float] | None      # metres per unit as declared; None: pixel_size: header
    slice: tuple[int, int] | None          # (voxel axis, index)


class Importer:
    """One outline file format.  Subclasses set the class attributes and implement ``read``;
    a module of this package that binds ``IMPORTER`` registers it (outline_formats.FORMATS)."""
    name: str = ""                         # registry name (OutlineSource.kind)
    title: str = ""                        # what users call the file, for messages and docs
    extensions: tuple[str, ...] = ()       # lower case, with the dot
    keys: tuple[OutlineKey, ...] = ()      # per-outline keys it reads
    pixels: bool = False                   # coordinates are pixel indices (image defaults)
    header_scale: bool = False             # may give the scale itself (pixel_size: header)
    needs_slice: bool = False              # reads one slice of a volume (the description's slice)

    def read(self, path: str, keys: dict, desc: Description) -> RawOutline:
        """The outline in ``path`` selected by ``keys`` (validated values of ``self.keys``)."""
        raise NotImplementedError

    def matches(self, path: str) -> str | None:
        """The longest of this format's extensions that ``path`` ends with, or None."""
        low = path.lower()
        hits = [e for e in self.extensions if low.endswith(e)]
        return max(hits, key=len) if hits else None


def file_name(path: str) -> str:
    """The name a message shows for a file (its base name)."""
    return os.path.basename(path)
