"""The reference configuration of a contact model: gap-free interfaces (sliding) or touching
without penetration (unilateral), checked once when the contact is built."""
from __future__ import annotations

import numpy as np

from .interfaces import ContactSetupError


def check_reference_gaps(contact) -> None:
    """The reference configuration must be gap-free (sliding) or not penetrating
    (unilateral): evaluated with every point local, then the projection state is reset."""
    n_blocks = contact.model.n_nodes + contact.space.n_nodes
    xl = np.zeros((n_blocks, contact.model.block.vectors_per_node, 3))
    xl[:contact.model.n_nodes] = contact.model.q0
    st = contact.evaluate(xl, np.arange(n_blocks))
    size = max(np.sqrt(b.section.area) for b in contact.model.beams)
    g = st.pr.g[st.pr.valid]
    contact.restore()
    if contact.law.decides_activity:          # unilateral: touching or apart
        if not st.pr.in_window or np.min(g, initial=0.0) < -1e-9 * size:
            raise ContactSetupError("the bodies interpenetrate in the reference configuration "
                                f"(gap {np.min(g):.3e} m); separate them")
        return
    gap = np.linalg.norm(st.pr.d, axis=1)
    if not st.pr.in_window or gap.max() > 1e-9 * size:
        raise ContactSetupError(f"the interfaces do not match in the reference configuration "
                                f"(largest gap {gap.max():.3e} m); neighbours must share "
                                "their interface curve and element boundaries")
