"""Where a restart's model differs, in the config's words: an entry of a nodal array of the
fingerprint (io/restart.py: the loads, supports, prescribed displacements, reference nodal
vectors, one number per global DOF or a list of DOF ids) as the beam, node, nodal vector and
component, with the config entries placed at that node."""
from __future__ import annotations

import numpy as np

#: fingerprint items with one value per global DOF, and the config section placed on them
PER_DOF = {"reference_nodal_vectors": "", "loads": "loads", "prescribed_displacements": "boundary_conditions"}
#: fingerprint items that are one config key
CONFIG_KEYS = {"length": "geometry.length", "twist_deg": "geometry.twist_deg"}


def difference_text(model, found: tuple[str, str], stored: dict, now: dict) -> str:
    """'item (what changed)' for ``found`` ((key, words) of ``restart.first_difference``
    between the fingerprints ``stored`` and ``now``): a config key by its path, a nodal item's
    change at its place; a changed length or pretwist (which moves every node) before all."""
    for key in CONFIG_KEYS:
        a, b = (np.asarray(x.get(key, np.nan), dtype=float).ravel()[:1] for x in (stored, now))
        if a.size and b.size and not np.allclose(a, b, rtol=1e-12, atol=0.0):
            found = (key, f"{a[0]:.9g} → {b[0]:.9g}")
            break
    return f"{CONFIG_KEYS.get(found[0], found[0])} ({_words(model, found, stored, now)})"


def _words(model, found: tuple[str, str], stored: dict, now: dict) -> str:
    key, words = found
    a = np.asarray(stored.get(key, ()), dtype=float).ravel()
    b = np.asarray(now.get(key, ()), dtype=float).ravel()
    if key in PER_DOF and a.shape == b.shape and a.size == model.n_dofs:
        k = int(np.argmax(np.abs(a - b)))
        return f"{dof_place(model, k, PER_DOF[key])}: {a[k]:.9g} → {b[k]:.9g}"
    if key == "supported_dofs":
        held, was = set(b.astype(int)), set(a.astype(int))
        changed = sorted(held ^ was)
        if changed:
            k = changed[0]
            return f"{dof_place(model, k, 'boundary_conditions')}: {'now held' if k in held else 'now free'}"
    return words


def dof_place(model, dof: int, section: str) -> str:
    """Global DOF ``dof`` as 'beam B node N, r_y z', after the entries of config ``section``
    (loads, boundary_conditions) at that node: 'loads[0] at beam B node N, r x'."""
    node, j = divmod(int(dof), model.dofs_per_node)
    beam = model.beams[int(model.node_beam()[node])]
    local = node - beam.node_offset
    where = f"beam {beam.name} node {local}, {model.block.names[j // 3]} {'xyz'[j % 3]}"
    items = {"loads": model.spec.loads, "boundary_conditions": model.spec.boundary_conditions}.get(section, [])
    paths = [x.path for x in items if x.beam == beam.index and x.node == local and x.path]
    return f"{', '.join(paths)} at {where}" if paths else where
