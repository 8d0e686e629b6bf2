"""The force each beam carries through its cross-sections along its length (issue 39): the
load transfer between subtendons that shear-lag, friction and muscle-load studies are about.

At an axial Gauss point x_g of an element the material cross-section x = x_g (normal e_x in the
reference configuration; the pretwist turns it in its plane and keeps its area) carries

    f(x_g) = ∫_A P e_x dA = Σ_p w_p P_p e_x / (w_g dx/dξ),

P the first Piola–Kirchhoff stress of the beam's own energy parts (``Model.element_data``: the
law, its fibres, the projected dilatation of ``locking: mixed``, the axis terms of ``ecm``) at
the points p of that station, w_p their weights (det J0 × axial × section weight), w_g the axial
Gauss weight (every part's rule is axial-major: na stations of equally many points,
``model/build.py``).  Summed over the beams, f_x equals the axial load applied beyond x, up to the contact forces
between material points on either side of the cut (the beams slide past each other); between
the beams the contact and the interface laws move it from one to another.
"""
from __future__ import annotations

import numpy as np

from ..physics.cubature import gauss_legendre

__all__ = ["AxialForces", "axial_forces", "element_means"]


class AxialForces:
    """``axial_forces`` of one model, its reference-state data (gradients, weights, laws: half
    the work of a call) computed once: ``AxialForces(model)(q)``, as the results writer does at
    every level."""

    def __init__(self, model):
        self.beams = []
        for beam in model.beams:
            E = beam.n_elements
            xa, wa = gauss_legendre(beam.axial_points)
            k = beam.layout.block.axial_nodes - 1                                  # element ends k apart
            dx_dxi = 0.5 * (beam.x_nodes[k::k] - beam.x_nodes[0:-1:k])             # (E,)
            x = beam.x_nodes[0:-1:k, None] + dx_dxi[:, None] * (xa[None, :] + 1.0)
            self.beams.append((beam, wa, dx_dxi, x.ravel(), model.element_data(beam, np.arange(E))))

    def __call__(self, q: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """``axial_forces(model, q)``."""
        out = {}
        for beam, wa, dx_dxi, x, parts in self.beams:
            E, na = beam.n_elements, len(wa)
            qe = q[beam.connectivity][:, :, list(beam.vectors)].reshape(E, -1, 3)
            force = np.zeros((E, na, 3))
            for G, w, law in parts:
                F = np.matmul(np.swapaxes(qe, 1, 2)[:, None], G)                  # (E, P, 3, 3)
                P = law.stress(F)[0]
                per = G.shape[1] // na                                            # points per station
                f = (w[..., None] * P[..., :, 0]).reshape(E, na, per, 3).sum(axis=2)
                force += f / (wa[None, :, None] * dx_dxi[:, None, None])
            out[beam.name] = (x, force.reshape(-1, 3))
        return out


def axial_forces(model, q: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per beam: the reference x of every axial Gauss point (E na,) [m] and the force f there
    (E na, 3) [N] the section carries (module docstring), for nodal vectors q (n_nodes, V, 3).
    Within an element it oscillates where the element locks (the paper's 3 axial points: the
    Achilles soleus at 400 N carries 460 / 325 / 463 N at the first element's points, whose
    mean is 400 N); ``element_means`` gives each element's mean.  (``AxialForces`` for many q.)"""
    return AxialForces(model)(q)


def element_means(model, forces: dict[str, tuple[np.ndarray, np.ndarray]]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per beam: each element's mid x (E,) [m] and the mean of ``axial_forces`` over its length
    (E, 3) [N] (the axial Gauss rule's weighted mean)."""
    out = {}
    for beam in model.beams:
        _, wa = gauss_legendre(beam.axial_points)
        x, f = forces[beam.name]
        f = f.reshape(beam.n_elements, len(wa), 3)
        k = beam.layout.block.axial_nodes - 1
        out[beam.name] = (0.5 * (beam.x_nodes[0:-1:k] + beam.x_nodes[k::k]),
                          np.einsum("g,egi->ei", wa / wa.sum(), f))
    return out
