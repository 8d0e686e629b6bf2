"""NIfTI label volumes: one label's region in one slice (the description's ``slice``), read with
nibabel (imported only when a file is read) and traced by ``masks.mask_outline``; u, v = the
indices along the two remaining voxel axes, lower axis first.  With ``pixel_size: header`` the
in-slice voxel size comes from the header (its spatial unit must be set)."""
from __future__ import annotations

import os
from functools import lru_cache

import numpy as np

from .base import Description, Importer, OutlineReadError, RawOutline, file_name
from .masks import LABEL, mask_outline

__all__ = ["IMPORTER", "NIFTI_UNITS", "NiftiSlice", "nifti_slice"]

NIFTI_UNITS = {"meter": 1.0, "mm": 1e-3, "micron": 1e-6}


@lru_cache(maxsize=4)
def _nifti(path: str, mtime: float):
    try:
        import nibabel as nib
    except ImportError:
        raise OutlineReadError("reading NIfTI needs nibabel (Debian python3-nibabel; run make setup)") from None
    try:
        img = nib.load(path)
        data = np.asanyarray(img.dataobj)
    except Exception:
        raise OutlineReadError(f"{file_name(path)} is not a NIfTI file nibabel can read") from None
    zooms = tuple(float(z) for z in img.header.get_zooms()[:3])
    unit = img.header.get_xyzt_units()[0]
    return data, zooms, unit


def nifti_slice(path: str, axis: int, index: int) -> tuple[np.ndarray, tuple[float, float] | None, str]:
    """Slice ``index`` across voxel axis ``axis`` of a NIfTI label volume: the 2D labels (u, v
    = remaining axes in order), the in-slice voxel size in metres (None if the header has no
    spatial unit) and a description."""
    data, zooms, unit = _nifti(path, os.path.getmtime(path))
    while data.ndim > 3 and data.shape[-1] == 1:
        data = data[..., 0]
    if data.ndim != 3:
        raise OutlineReadError(f"{file_name(path)} is a {data.ndim}D volume; expected 3D labels")
    if not 0 <= index < data.shape[axis]:
        raise OutlineReadError(f"{file_name(path)}: slice index {index} is outside 0..{data.shape[axis] - 1} "
                               f"along axis {axis}")
    if data.dtype.kind == "f" and not np.all(np.take(data, index, axis=axis) == np.round(np.take(data, index, axis=axis))):
        raise OutlineReadError(f"{file_name(path)} holds non-integer values; a label volume holds labels")
    sl = np.take(data, index, axis=axis).astype(np.int64)
    keep = [a for a in range(3) if a != axis]
    scale = None
    if unit in NIFTI_UNITS:
        scale = (zooms[keep[0]] * NIFTI_UNITS[unit], zooms[keep[1]] * NIFTI_UNITS[unit])
    return sl, scale, f"{file_name(path)} axis {axis} slice {index}"


class NiftiSlice(Importer):
    name = "nifti"
    title = "NIfTI label volume"
    extensions = (".nii", ".nii.gz")
    keys = (LABEL,)
    pixels = True
    header_scale = True
    needs_slice = True

    def read(self, path: str, keys: dict, desc: Description) -> RawOutline:
        axis, index = desc.slice
        labels, header, what = nifti_slice(path, axis, index)
        r = mask_outline(labels, keys["label"], what)
        if desc.scale is None:
            if header is None:
                raise OutlineReadError(f"{what}: the header has no spatial unit; give pixel_size")
            r.scale = header
        return r


IMPORTER = NiftiSlice()
