"""The partition's counts (summary.json ``partition``, the run header) count what they name."""
import os

import numpy as np

from helpers import CONFIGS, load_raw


def test_nodes_per_rank_counts_beam_nodes_and_the_multiplier_blocks_apart():
    """The paper's tendon at 1 element a subtendon has 9 beam nodes (summary ``exchange``
    ``total_nodes`` 9, 162 DOFs); ``nodes_per_rank`` said [11] on 1 rank and [3, 4, 4] on 3: the
    contact multipliers' blocks (contact/multipliers.py) counted as nodes."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.contact import build_contact
    from ancf_petsc.model.build import build_model
    from ancf_petsc.parallel.partition import make_layout, partition_stats
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["elements"] = 1
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    spec = parse_config(raw)
    model = build_model(spec)
    contact = build_contact(model, spec.contact, lambda *a: None)
    for size in (1, 3):
        lay = make_layout(model, "blocks", size, 0, contact)
        st = partition_stats(lay, model, contact)
        extra = lay.n_blocks - model.n_nodes
        assert extra > 0                          # the case: multiplier blocks exist
        assert sum(st["nodes_per_rank"]) == model.n_nodes == 9, st
        assert sum(st["multiplier_blocks_per_rank"]) == extra, st
        assert st["nodes_per_rank"] == np.bincount(lay.node_owner[:model.n_nodes], minlength=size).tolist()
        assert f"nodes per rank {st['nodes_per_rank']}" in lay.summary()
