"""What each subtendon carries and how far it stretches at a converged level.

Per beam: the end force at the load factor λ [N], what acts on its last node from outside: the
loads there (their config values times their multipliers m(λ): a muscle's force in a gait frame)
plus the reactions of supports there (a prescribed displacement's grip; until 2026-12-06 the sum
of the beam's loads wherever applied: 0 under displacement control, and a pressed strip's
pressing loads along it), the elongation — the x-displacement of its last node averaged over the
end section, Σ_k m̄_k Δq_k (m̄_k = ∫ m_k dA / A), the quantity ultrasound speckle tracking
follows, less the same of its first node (0 at a held root; a beam held at its last node and
pulled at its first was reported unstretched) [m] — and the mean axial strain elongation / L."""
from __future__ import annotations

import numpy as np

from ..model.loading import LoadCurve


def subtendon_report(model, q: np.ndarray, lam: float, reactions: np.ndarray | None = None) -> dict:
    """{beam: {"end_force": [Fx, Fy, Fz] N, "elongation": m, "strain": 1}} at the nodal vectors q
    (n_nodes, 6, 3) and load factor λ; ``reactions`` (supports, 3) those of ``model.supports``."""
    spec = model.spec
    out = {}
    for b in model.beams:
        force = np.zeros(3)
        last = b.node_offset + b.n_nodes - 1
        for ld in spec.loads:
            if ld.beam == b.index and b.node_offset + ld.node == last:
                m = lam if ld.curve is None else LoadCurve(ld.curve)(lam)
                force += m * np.asarray(ld.force)
        for sup, r in zip(model.supports, reactions if reactions is not None else []):
            if sup.node == last:
                force += np.asarray(r)
        first = b.node_offset
        du = (model.end_means[b.index] @ (q[last] - model.q0[last])
              - model.root_means[b.index] @ (q[first] - model.q0[first]))
        out[b.name] = {"end_force": force.tolist(), "elongation": float(du[0]),
                       "strain": float(du[0] / spec.length)}
    return out
