"""Derived outputs of a converged level: how far neighbouring subtendons have moved apart.

Ultrasound speckle tracking measures the displacement of the deep (soleus) part of the Achilles
tendon against the superficial (gastrocnemius) parts (e.g. Slane & Thelen 2014: 0.9–2.6 mm).
Here, for every pair of beams joined by a contact interface, keyed "first|second" in config
order whichever beam carries the contact points, the axial displacement u_x of the first beam's
centroid line minus the second's at every node station (the beams of an interface have the same
stations) [m], its largest magnitude (signed) and its value at the far end (x = L)."""
from __future__ import annotations

import numpy as np


def interface_pairs(interfaces) -> list[tuple[int, int]]:
    """(first, second) beam of every interface in config order, each pair once, in order of
    appearance."""
    out = []
    for itf in interfaces:
        pair = (itf.first.index, itf.second.index)
        if pair not in out:
            out.append(pair)
    return out


def displacement_differences(model, q: np.ndarray, pairs: list[tuple[int, int]]) -> dict:
    """Per pair "first|second" (``interface_pairs``): u_x of the first beam's centroid line minus
    the second's at every node station [m] (``profile``), the largest magnitude (``max``, signed)
    and the value at x = L (``end``); ``q`` the nodal vectors (n_nodes, 6, 3)."""
    u = q[:, 0, 0] - model.q0[:, 0, 0]
    out = {}
    for a, b in pairs:
        A, B = model.beams[a], model.beams[b]
        d = u[A.node_offset + np.arange(A.n_nodes)] - u[B.node_offset + np.arange(B.n_nodes)]
        k = int(np.argmax(np.abs(d)))
        out[f"{A.name}|{B.name}"] = {"max": float(d[k]), "end": float(d[-1]), "profile": d.tolist()}
    return out
