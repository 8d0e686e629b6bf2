"""How far B's surface is from C¹ in a state: the turn of its outward normal across each element
boundary (the common node of elements e and e + 1), an indicator of the mesh for contact.

B's surface is only C⁰ across its element boundaries (docs/contact.md, "Limits"): a contact point
whose closest place passes a boundary turns its normal, and with it its force, by this angle.
At rest the paper's outlines turn by at most 0.07° (twist 180°, 4 elements); under load the
turn grows where the deformation varies within an element: on the 180° gastrocnemius-biased
unilateral stride (4 elements) 0.2° at frame 1, 2.5° at frame 26 and 8.3° at frame 44, its last
converged one (the medial gastrocnemius under the lateral; 16.4° at the iterate it stopped on:
docs/gait.md, thirty-third session).  Each level reports the largest turn per interface (summary.json's
``contact``: ``normal_turn_deg``), and a run whose turn exceeded ``TURN_NOTE_DEG`` says so once.
"""
from __future__ import annotations

import numpy as np

#: a level whose B surface turns by more than this at an element boundary is noted at the end
TURN_NOTE_DEG = 5.0
#: how the note begins (a restarted run makes it again: reports.made_at_the_end)
TURN_NOTE = "note: the surface's normal turns at element boundaries on interface"
#: places along the interface curve at which each boundary's two normals are compared (odd: the
#: curve's middle is one)
SAMPLES = 17


def normal_turns(c, q: np.ndarray, connectivity: np.ndarray) -> dict[str, float]:
    """Per interface of the ``Contact`` c: the largest angle (degrees) between B's outward
    normals on either side of its element boundaries, at ``SAMPLES`` places along the interface
    curve, for the gathered nodal vectors ``q`` (n_nodes, V, 3; rank 0)."""
    pj = c.projector

    def x_of(els: np.ndarray) -> np.ndarray:
        return q[connectivity[els]].reshape(len(els), -1, 3)

    out = {}
    for i, itf in enumerate(c.interfaces):
        first, last, T = (float(v[0]) for v in pj.wrap_bounds(np.array([i])))
        bounds = np.arange(int(first), int(last))                     # boundary between e, e + 1
        if len(bounds) == 0:
            out[itf.name] = 0.0
            continue
        t = np.tile(np.linspace(0.0, T, SAMPLES), len(bounds))
        e = np.repeat(bounds, SAMPLES)
        normals = []
        for elements, xi in ((e, 1.0), (e + 1, -1.0)):
            _, Yz, _, _, _ = pj.surface(x_of, np.full(len(t), i), elements, np.full(len(t), xi), t.copy())
            n = np.cross(Yz[:, :, 1], Yz[:, :, 0])
            normals.append(n / np.linalg.norm(n, axis=1)[:, None])
        cos = np.clip(np.einsum("pi,pi->p", *normals), -1.0, 1.0)
        out[itf.name] = float(np.degrees(np.arccos(cos)).max())
    return out


def turn_notes(c, steps: list[dict]) -> list[str]:
    """One line if a level of ``steps`` (summary.json's) had B's normal turning by more than
    ``TURN_NOTE_DEG`` across an element boundary: the largest, where and when."""
    worst = (0.0, "", 0.0)
    for s in steps:
        for name, rep in (s.get("contact") or {}).items():
            turn = rep.get("normal_turn_deg", 0.0) if isinstance(rep, dict) else 0.0
            if turn > worst[0]:
                worst = (turn, name, s["load_factor"])
    if worst[0] <= TURN_NOTE_DEG:
        return []
    return [f"{TURN_NOTE} {worst[1]}: B's surface normal turns by up to {worst[0]:.3g} deg across "
            f"an element boundary (at load factor {worst[2]:g}); a contact point passing there turns "
            "its force as much, and Newton may cycle: more elements along the beams make the "
            "surface smoother (docs/contact.md, \"Limits\")"]


def add_normal_turns(report: dict, c, q: np.ndarray, connectivity: np.ndarray) -> None:
    """``normal_turn_deg`` of each interface into a level's ``gap_report`` (rank 0)."""
    for name, turn in normal_turns(c, q, connectivity).items():
        report[name]["normal_turn_deg"] = turn
