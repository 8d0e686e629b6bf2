"""A pressure that changes sign within elements along the beam under Coulomb friction: an
inf-sup instability that raises the friction the interface carries (docs/interface.md, Limits).

Coulomb's bound is μ ∫ p⁺ dA (friction.py), so the pull of the points with p < 0 adds to what a
sliding interface carries beyond μ × its net pressing force N = ∫ p dA.  On the pressed strips
(configs/friction_pressed_strips.yaml, N = 0.01 N, a uniform 100 Pa) the pressure along the
beam is too rich for the mesh near the gripped end at 8 and 16 elements: it swings from
−1 078 to 2 128 Pa within the last elements, and the grip force while sliding is 1.011 / 1.087 μN
(μ = 0.5; 1.348 at μ = 1, 16 elements); with ``contact.projection: {axial: 1}`` 1.000 (1.003
at μ = 1), with ``contact.axial_points: 2`` 1.000.  Each level reports ``pull_within_elements`` [N] per
interface (friction.py): the pull that cancels, along the beam within each element (per A
element and place across the curve), against pressed points.  An interface whose net pressing
force is positive, whose pull lies there (at least ``WITHIN_SHARE`` of ``tension_force``: an
oscillation, not a pulled region) and whose pull raises the bound by more than
``EXCESS`` of μN draws one warning per run.  Measured (2026-12-08): the strips at 8 / 16
elements all of the pull within elements, the bound 1.08 / 8.7 % above μN (μ = 0.5; 34.8 % at
μ = 1); 1, 2 and 4 elements no pull (μ = 0.05 … 1); the 100-frame stride
(configs/gait_stride_walking.yaml) with μ = 0.3 at most 0.959 of its pull within elements
(frame 62; lg_sol), the rest pulled regions across the curve, where the sliding law holds the
subtendons together.
"""
from __future__ import annotations

import numpy as np

#: the share of an interface's pull that must lie within elements between pressed points
WITHIN_SHARE = 0.99
#: the least excess of Coulomb's bound over μ × the net pressing force that is reported
EXCESS = 0.005
#: what marks the warning (a restarted run makes it again: reports.made_at_the_end)
OSCILLATION_NOTE = "the pressure oscillates in sign under Coulomb friction"


def pull_within_elements(c, st, on: np.ndarray) -> float:
    """The pull [N] of the local points ``on`` (bool, one interface) of the ``Contact`` c at its
    evaluation st that cancels against pressure along the beam within an element: per line of
    points (A element, place across the curve) Σ τ⁻ less the line's own net pull.  A segment's
    points live on one rank, so the ranks' parts add up."""
    v = on & st.pr.valid
    if not v.any():
        return 0.0
    tau = st.tau[v]
    lines = np.column_stack([c.points.seg[c.local][v], c.points.t[c.local][v]])
    _, line = np.unique(lines, axis=0, return_inverse=True)
    net = np.bincount(line.ravel(), tau)
    return float(np.minimum(net, 0.0).sum() - np.minimum(tau, 0.0).sum())


def oscillation_notes(c, steps: list[dict]) -> list[str]:
    """One warning if, at a level of ``steps`` (summary.json's), an interface of the ``Contact``
    c with Coulomb friction pressed overall with its pull all within elements (module
    docstring): the worst level, the bound's and the friction force's ratio to μN, the cause
    and the remedies."""
    mu = next((t.mu for t in c.terms if t.bounded), None)     # Coulomb friction's μ
    if mu is None:
        return []
    worst, levels = None, 0
    for s in steps:
        for name, rep in (s.get("contact") or {}).items():
            within = rep.get("pull_within_elements") if isinstance(rep, dict) else None
            if within is None:
                continue
            pull = -rep["tension_force"]
            net = rep["pressing_force"] - pull
            if net <= 0.0 or pull <= 0.0 or within < WITHIN_SHARE * pull or within <= EXCESS * net:
                continue
            levels += 1
            friction = float(np.linalg.norm(rep["shear_force"])) / (mu * net)
            if worst is None or within / net > worst[0]:
                worst = (within / net, name, s["load_factor"], friction, net)
    if worst is None:
        return []
    excess, name, level, friction, net = worst
    return [f"warning: contact interface {name}: {OSCILLATION_NOTE} within elements along the beam "
            f"at {levels} level(s) (worst at load factor {level:g}): the pull there lets Coulomb's "
            f"bound mu * (pressing force) reach {1.0 + excess:.4g} x mu N (N = {net:.4g} N the net "
            f"pressing force; the friction force is {friction:.4g} x mu N). Likely an inf-sup "
            "instability: the pressure space is too rich for the mesh near a supported end. "
            + remedies(c.spec)]


def remedies(spec) -> str:
    """The settings that remove the oscillation, given the pressure space ``spec`` (a ContactSpec)
    has: a lower degree along the beam than its own (the linear one, friction's default, can
    oscillate too) or fewer contact points, with what they did on the pressed strips."""
    if spec.projection[0] >= 2:
        return ("contact.projection: {axial: 1} (friction's default) or contact.axial_points: 2 "
                "remove it (the pressed strips at 16 elements, mu = 0.5: 1.087 x mu N, with either "
                "1.000; docs/interface.md, \"Limits\")")
    fixes = {"contact.projection: {axial: 0}": "1.000"} if spec.projection[0] == 1 else {}
    if spec.axial_points > 2:
        fixes["contact.axial_points: 2"] = "1.001"
    if not fixes:
        return "docs/interface.md, \"Limits\""
    return (f"The pressure is of degree {spec.projection[0]} along the beam here (friction's default "
            f"is 1): {' or '.join(fixes)} remove it (the pressed strips at 16 elements, mu = 1, "
            f"linear pressure: 1.006 x mu N, with them {' and '.join(fixes.values())}; docs/interface.md, "
            "\"Limits\")")
