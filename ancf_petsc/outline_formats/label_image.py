"""Label masks: the region of one label in a 2D label image (PNG/TIFF; one channel: grayscale,
palette or 16-bit), read with Pillow (imported only when a file is read) and traced by
``masks.mask_outline``.  u = column index, v = row index (pixel centres at integers)."""
from __future__ import annotations

import os
from functools import lru_cache

import numpy as np

from .base import Description, Importer, OutlineReadError, RawOutline, file_name
from .masks import LABEL, mask_outline

__all__ = ["IMPORTER", "LabelImage", "label_image"]


@lru_cache(maxsize=8)
def _image(path: str, mtime: float) -> np.ndarray:
    try:
        from PIL import Image
    except ImportError:
        raise OutlineReadError("reading label images needs Pillow (Debian python3-pil)") from None
    try:
        im = Image.open(path)
    except Exception:
        raise OutlineReadError(f"{file_name(path)} is not an image Pillow can read") from None
    if getattr(im, "n_frames", 1) > 1:
        raise OutlineReadError(f"{file_name(path)} has {im.n_frames} pages; save the slice as a single image "
                               "(or use a NIfTI volume with slice:)")
    if im.mode not in ("1", "L", "P", "I", "I;16", "I;16B", "I;16L", "F"):
        raise OutlineReadError(f"{file_name(path)} is a {im.mode} image; a label mask has one channel "
                               "(grayscale or palette) holding the label values")
    a = np.array(im)
    if a.dtype.kind == "f":
        if not np.all(a == np.round(a)):
            raise OutlineReadError(f"{file_name(path)} holds non-integer values; a label mask holds labels")
    return a.astype(np.int64)


def label_image(path: str) -> np.ndarray:
    """A 2D label image (PNG/TIFF), rows × columns."""
    return _image(path, os.path.getmtime(path))


class LabelImage(Importer):
    name = "label_image"
    title = "label mask image"
    extensions = (".png", ".tif", ".tiff")
    keys = (LABEL,)
    pixels = True

    def read(self, path: str, keys: dict, desc: Description) -> RawOutline:
        r = mask_outline(label_image(path), keys["label"], file_name(path))
        r.points = r.points[:, ::-1].copy()          # (row, col) → (u, v) = (col, row)
        return r


IMPORTER = LabelImage()
