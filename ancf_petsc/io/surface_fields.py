"""The point fields of the surface VTUs (``surface_NNNN.vtu``): ONE registry of each field's name,
chart label, unit, display factor, the function that computes it from the sampled state, and
where it applies.  ``vtk.SurfaceSampler`` writes them, ``viz.field_values`` labels them, the docs
list them (docs/running.md, "Surface point fields"); a new field is one entry here and its test.

Values are stored in SI (displacement in m, stress in Pa); ``factor`` turns them into the chart's
``unit``.  F = qᵀG is the deformation gradient at the surface point (eq. 5 with the reference
gradients G of the sample point)."""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["SURFACE_FIELDS", "SampledState", "SurfaceField", "fields_for"]

MM = 1.0e3       # metres → millimetres
MPA = 1.0e-6     # pascals → megapascals


@dataclass(frozen=True)
class SampledState:
    """One beam's surface points at one level."""
    r: np.ndarray                 # (n, 3) current positions [m]
    r0: np.ndarray                # (n, 3) reference positions [m]
    F: np.ndarray                 # (n, 3, 3) deformation gradients
    beam: int                     # the beam's index
    fibre_law: object | None      # the beam's fibre-reinforced law bound to the points' directions
    theta: np.ndarray | None = None   # (n,) the projected dilatation of ``locking: mixed``, else None
    P: np.ndarray | None = None       # (n, 3, 3) the stress of ``locking: ecm`` (not the law's at F), else None


def _everywhere(s: SampledState) -> bool:
    return True


def _fibre_reinforced(s: SampledState) -> bool:
    return s.fibre_law is not None


@dataclass(frozen=True)
class SurfaceField:
    """A point field: ``compute`` on the beams where ``applies``; written when it applies to one
    beam at least (NaN on the others); ``where`` says when, in words (docs and messages)."""
    name: str
    label: str                                       # chart label (matplotlib mathtext)
    unit: str                                        # chart unit
    factor: float                                    # stored value → chart unit
    compute: Callable[[SampledState], np.ndarray]
    components: int = 1
    applies: Callable[[SampledState], bool] = _everywhere
    where: str = "every model"
    si_unit: str = "1"                               # the stored value's unit (results.h5 attrs)

    def values(self, s: SampledState) -> np.ndarray:
        """The field on one beam's points, or NaN where it does not apply."""
        if self.applies(s):
            return self.compute(s)
        return np.full((len(s.r),) + ((self.components,) if self.components > 1 else ()), np.nan)


def _green_lagrange_xx(s: SampledState) -> np.ndarray:
    """E_xx = ½(C_xx − 1), C = FᵀF."""
    return 0.5 * (np.einsum("pi,pi->p", s.F[:, :, 0], s.F[:, :, 0]) - 1.0)


def _volume_ratio(s: SampledState) -> np.ndarray:
    """J = det F as the triple product of its columns (no LAPACK)."""
    return np.einsum("pi,pi->p", s.F[:, :, 0], np.cross(s.F[:, :, 1], s.F[:, :, 2]))


#: the surface point fields, in the order they are written
SURFACE_FIELDS = {f.name: f for f in (
    SurfaceField("displacement", "displacement magnitude $|u|$", "mm", MM, lambda s: s.r - s.r0, components=3,
                 si_unit="m"),
    SurfaceField("E_xx", "axial Green-Lagrange strain $E_{xx}$", "%", 100.0, _green_lagrange_xx),
    SurfaceField("J", "volume ratio $J$", "-", 1.0, _volume_ratio),
    SurfaceField("beam", "beam index", "-", 1.0, lambda s: np.full(len(s.r), float(s.beam))),
    SurfaceField("fibre_stretch", r"fibre stretch $\sqrt{I_4}$", "-", 1.0,
                 lambda s: s.fibre_law.fibre_stretch(s.F)[0], applies=_fibre_reinforced,
                 where="fibre-reinforced models (first family; NaN on other beams)"),
    SurfaceField("fibre_stress", r"fibre Cauchy stress $\sigma_{ff}$", "MPa", MPA,
                 lambda s: s.fibre_law.fibre_cauchy_stress(s.F, s.theta, s.P)[0], applies=_fibre_reinforced,
                 where="fibre-reinforced models (first family; NaN on other beams)", si_unit="Pa"),
)}


def fields_for(states: list[SampledState]) -> list[SurfaceField]:
    """The fields written for these beams: those that apply to one of them at least."""
    return [f for f in SURFACE_FIELDS.values() if any(f.applies(s) for s in states)]
