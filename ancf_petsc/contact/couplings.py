"""What the contact couples: node blocks of the Jacobian's pattern (the local segments now, with
the terms' couplings) and the element graph a partition weighs (pairs of elements and the work
of their contact points)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class ContactGraph:
    """Element pairs (K, 2) the contact couples with the number of contact points on each pair
    (K,), the contact points per element (n_elements,), and the A element of every multiplier
    node (the element whose rank holds it)."""
    pairs: np.ndarray
    counts: np.ndarray
    points_per_element: np.ndarray
    multiplier_node_element: np.ndarray


def node_couplings(c) -> tuple[np.ndarray, np.ndarray]:
    """Node-block couplings (PETSc numbering) of the ``Contact`` c's local segments now: per
    segment its A nodes, the nodes of every B element its points project onto and its multiplier
    node, all with all, and each term's groups.  Couplings that sliding creates later are added
    when they first occur."""
    if len(c.local) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    seg = c.points.seg[c.local]
    seg_b = np.unique(np.stack([seg, c.projector.eB[c.local]], 1), axis=0)
    e_a = c.points.seg_eA[seg_b[:, 0]]
    groups = [np.concatenate([c.conn[e_a], c.conn[seg_b[:, 1]], c.seg_blocks[seg_b[:, 0]]],
                             axis=1)]                                      # (pairs, 8), −1 unused
    groups += [g for t in c.terms for g in t.couplings(c)]
    rows, cols = [], []
    for group in groups:
        a = np.repeat(group, group.shape[1], axis=1).ravel()
        b = np.tile(group, (1, group.shape[1])).ravel()
        ok = (a >= 0) & (b >= 0)
        rows.append(a[ok])
        cols.append(b[ok])
    # a segment on several B elements also couples those elements with each other
    first = np.searchsorted(seg_b[:, 0], seg_b[:, 0])
    for i in np.flatnonzero(first != np.arange(len(seg_b))):
        others = c.conn[seg_b[first[i]:i, 1]].ravel()
        mine = c.conn[seg_b[i, 1]]
        rows += [np.repeat(mine, len(others)), np.tile(others, len(mine))]
        cols += [np.tile(others, len(mine)), np.repeat(mine, len(others))]
    return np.concatenate(rows), np.concatenate(cols)


def coupling_graph(c) -> ContactGraph:
    """Every contact point's A element with the B element it projects onto now and, for a
    tangential law, with its reference partner's (model numbering, all points)."""
    eA = c.points.eA
    partners = [c.projector.eB] + [t.eB0 for t in c.terms]
    pair, count = np.unique(np.concatenate([np.stack([eA, eB], 1) for eB in partners]), axis=0,
                            return_counts=True)
    return ContactGraph(pairs=pair, counts=count,
                        points_per_element=np.bincount(eA, minlength=c.model.n_elements),
                        multiplier_node_element=c.space.node_element)
