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
    return {name: turn for name, (turn, _) in turns_and_nodes(c, q, connectivity).items()}


def turns_and_nodes(c, q: np.ndarray, connectivity: np.ndarray) -> dict[str, tuple[float, int]]:
    """``normal_turns`` and the node of the element boundary where each interface's turns most."""
    pj = c.projector

    def x_of(els: np.ndarray) -> np.ndarray:
        return q[connectivity[els]].reshape(len(els), -1, 3)

    out = {}
    for i, itf in enumerate(c.interfaces):
        first, last, T = (float(v[0]) for v in pj.wrap_bounds(np.array([i])))
        bounds = np.arange(int(first), int(last))                     # boundary between e, e + 1
        if len(bounds) == 0:
            out[itf.name] = (0.0, -1)
            continue
        t = np.tile(np.linspace(0.0, T, SAMPLES), len(bounds))
        e = np.repeat(bounds, SAMPLES)
        normals = []
        for elements, xi in ((e, 1.0), (e + 1, -1.0)):
            _, Yz, _, _, _ = pj.surface(x_of, np.full(len(t), i), elements, np.full(len(t), xi), t.copy())
            n = np.cross(Yz[:, :, 1], Yz[:, :, 0])
            normals.append(n / np.linalg.norm(n, axis=1)[:, None])
        turn = np.degrees(np.arccos(np.clip(np.einsum("pi,pi->p", *normals), -1.0, 1.0)))
        k = int(np.argmax(turn))
        out[itf.name] = (float(turn[k]), int(connectivity[e[k]][-1]))
    return out


def turn_notes(c, steps: list[dict]) -> list[str]:
    """One line if a level of ``steps`` (summary.json's) had B's normal turning by more than
    ``TURN_NOTE_DEG`` across an element boundary: the largest, where and when."""
    worst = (0.0, "", 0.0, None)
    for s in steps:
        for name, rep in (s.get("contact") or {}).items():
            turn = rep.get("normal_turn_deg", 0.0) if isinstance(rep, dict) else 0.0
            if turn > worst[0]:
                worst = (turn, name, s["load_factor"], rep.get("normal_turn_x"))
    if worst[0] <= TURN_NOTE_DEG:
        return []
    where = f" at x = {worst[3] * 1e3:.4g} mm" if worst[3] is not None else ""
    return [f"{TURN_NOTE} {worst[1]}: B's surface normal turns by up to {worst[0]:.3g} deg across "
            f"an element boundary{where} (at load factor {worst[2]:g}); a contact point passing there "
            f"turns its force as much, and Newton may cycle: {_advice(c, worst[1], worst[3])}"]


def _advice(c, name: str, x) -> str:
    """More elements, unless the kink is an element from a point force on r of the interface's
    beams: that force deforms its end section locally, and shorter elements sharpen the kink (the
    paper's tendon at 90 deg, 2 axial points: 3.4 deg at 4 elements, 7.1 at 16, next to the soleus'
    pulled node; 1.6 at 16 with traction_force), where the note advised more elements."""
    itf = next((i for i in c.interfaces if i.name == name), None) if c is not None and x is not None else None
    for i, ld in enumerate(c.model.spec.loads if itf is not None else []):
        beam = c.model.beams[ld.beam]
        h = float(np.ptp(beam.x_nodes)) / beam.n_elements
        if ld.kind == "force" and beam.index in (itf.a.index, itf.b.index) and abs(beam.x_nodes[ld.node] - x) <= h * (1 + 1e-9):
            return (f"it is an element from the point force on r of {ld.path or f'loads[{i}]'} ({beam.name}), which "
                    "deforms the end section locally: more elements make it sharper; give that load as "
                    "traction_force (docs/contact.md, \"Limits\")")
    return "more elements along the beams make the surface smoother (docs/contact.md, \"Limits\")"


def add_normal_turns(report: dict, c, q: np.ndarray, connectivity: np.ndarray) -> None:
    """``normal_turn_deg`` of each interface and ``normal_turn_x``, the reference x [m] of the
    element boundary where it turns most, into a level's ``gap_report`` (rank 0)."""
    for name, (turn, node) in turns_and_nodes(c, q, connectivity).items():
        report[name]["normal_turn_deg"] = turn
        report[name]["normal_turn_x"] = float(c.model.q0[node, 0, 0]) if node >= 0 else None
