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
    valid = st.pr.valid
    contact.restore()
    if contact.law.decides_activity:          # unilateral: touching or apart
        g = np.where(valid, st.pr.g, np.inf)
        if not st.pr.in_window or np.min(g, initial=0.0) < -1e-9 * size:
            raise ContactSetupError("the bodies interpenetrate in the reference configuration "
                                    f"({_where(contact, np.argmin(g))}gap {np.min(g, initial=0.0):.3e} m); "
                                    "separate them", *_key(contact, np.argmin(g)))
        return
    gap = np.linalg.norm(st.pr.d, axis=1)
    if not st.pr.in_window or gap.max() > 1e-9 * size:
        raise ContactSetupError(f"the interfaces do not match in the reference configuration "
                                f"({_where(contact, np.argmax(gap))}largest gap {gap.max():.3e} m); "
                                "neighbours must share their interface curve and element boundaries",
                                *_key(contact, np.argmax(gap)))


def _interface(contact, point: int) -> int:
    """The interface (its index in ``contact.interfaces``) of local point ``point``."""
    return int(contact.points.itf[contact.local[point]])


def _where(contact, point: int) -> str:
    """"interface NAME: " of local point ``point`` (empty without points)."""
    if len(contact.local) == 0:
        return ""
    return f"interface {contact.interfaces[_interface(contact, point)].name}: "


def _key(contact, point: int) -> tuple:
    """(interface index,) for ``ContactSetupError`` where the config lists the interfaces, one
    each in its order (the key is then contact.interfaces[k]), else ()."""
    if len(contact.local) == 0 or len(contact.spec.interfaces or ()) != len(contact.interfaces):
        return ()
    return (_interface(contact, point),)
