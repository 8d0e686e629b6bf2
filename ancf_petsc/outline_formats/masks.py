"""The outline of one label's region in a 2D label array (shared by the mask importers): the
marching-squares contour at level 0.5 of its mask (skimage.measure.find_contours)."""
from __future__ import annotations

import numpy as np

from .base import OutlineKey, OutlineReadError, RawOutline

__all__ = ["LABEL", "SPECKLE", "mask_outline", "ring_area"]

#: components (and holes) of a label smaller than this fraction of its largest region are dropped
SPECKLE = 0.01
#: the per-outline key of every mask importer: which label is this subtendon
LABEL = OutlineKey("label", int, "the label value of this subtendon, e.g. label: 2", required=True, minimum=1)


def ring_area(C: np.ndarray) -> float:
    """Signed area of a closed ring of points (shoelace)."""
    y, z = C[:, 0], C[:, 1]
    return 0.5 * float(np.sum(y * np.roll(z, -1) - np.roll(y, -1) * z))


def mask_outline(labels: np.ndarray, label: int, what: str) -> RawOutline:
    """Outline of the region ``labels == label``: the marching-squares contour at level 0.5
    (skimage.measure.find_contours) of its mask, in array index coordinates (first, second index).

    The largest region is kept; other regions and holes smaller than ``SPECKLE`` of it are
    dropped (noted); larger ones are an error (a subtendon is one region without holes)."""
    mask = labels == label
    if not mask.any():
        present = np.unique(labels)
        shown = ", ".join(str(v) for v in present[:12]) + (" ..." if present.size > 12 else "")
        raise OutlineReadError(f"{what}: no pixel has label {label} (labels present: {shown}); "
                               "check the label value of this subtendon")
    try:
        from skimage import measure
    except ImportError:
        raise OutlineReadError("tracing masks needs scikit-image (Debian python3-skimage; run make setup)") from None
    padded = np.pad(mask.astype(float), 1)
    contours = [c - 1.0 for c in measure.find_contours(padded, 0.5)]
    rings = [c[:-1] if np.allclose(c[0], c[-1]) else c for c in contours]
    areas = np.array([ring_area(r) for r in rings])
    big = int(np.argmax(np.abs(areas)))
    sign = np.sign(areas[big])
    notes = []
    outer = [i for i in range(len(rings)) if np.sign(areas[i]) == sign and i != big]
    holes = [i for i in range(len(rings)) if np.sign(areas[i]) != sign]
    ref = abs(areas[big])
    for kind, idx in (("separate region", outer), ("hole", holes)):
        large = [i for i in idx if abs(areas[i]) > SPECKLE * ref]
        if large:
            raise OutlineReadError(f"{what}: label {label} has a {kind} of {abs(areas[large[0]]):.0f} px^2 "
                                   f"beside its main region of {ref:.0f} px^2; a subtendon is one region "
                                   "without holes: fix the mask")
        if idx:
            notes.append(f"dropped {len(idx)} {kind}(s) below {SPECKLE:.0%} of the region")
    return RawOutline(rings[big], closed=True, notes=notes)
