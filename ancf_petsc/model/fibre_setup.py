"""Fibre directions of fibre-reinforced beams at their Gauss points, set up once in the reference
configuration (``physics/fibres.py``): the points' stations x and tendon-frame section points."""
from __future__ import annotations

import numpy as np

from ..physics.cubature import gauss_legendre
from ..physics.fibres import fibre_directions, gauss_point_stations
from .beams import Beam


def directions_at(beam: Beam, x: np.ndarray, yz: np.ndarray, length: float, twist_deg: float,
                  axis) -> np.ndarray:
    """Fibre directions (families, *x.shape, 3) of ``beam``'s law at stations x and beam-frame
    section coordinates yz (*x.shape, 2; origin: the beam's section centroid at x = 0)."""
    f = beam.material.fibres
    c = beam.section.centroid
    a0 = fibre_directions(x.ravel(), c + yz.reshape(-1, 2), length, twist_deg, axis, c,
                          f["follow"], f["extra_twist_deg"], f["angles_deg"])
    return a0.reshape((a0.shape[0],) + x.shape + (3,))


def set_fibre_directions(beam: Beam, length: float, twist_deg: float, axis) -> None:
    """``beam.fibres`` (families, E, P, 3) and ``beam.fibres_axis`` (families, E, na, 3) for a
    law with fibres (one that has ``with_directions``); nothing for an isotropic law."""
    if not hasattr(beam.material, "with_directions"):
        return
    x = gauss_point_stations(beam.x_nodes, beam.xi, beam.layout.block.axial_nodes)                          # (E, P)
    yz = beam.yz if beam.yz.ndim == 3 else np.broadcast_to(beam.yz, x.shape + (2,))
    beam.fibres = directions_at(beam, x, yz, length, twist_deg, axis)
    xa, _ = gauss_legendre(beam.axial_points)
    xx = gauss_point_stations(beam.x_nodes, xa, beam.layout.block.axial_nodes)
    beam.fibres_axis = directions_at(beam, xx, np.zeros(xx.shape + (2,)), length, twist_deg, axis)
