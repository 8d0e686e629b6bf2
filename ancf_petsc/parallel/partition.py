"""Distribution of elements over MPI ranks: contiguous blocks, a METIS graph partition, or whole
beams (METIS on the beam graph, for the fascicle-parallel solver, linalg/fieldsplit.py).

The element graph has one vertex per element (weight: its Gauss points, the cost of eq. 9, plus
``CONTACT_COST`` per contact point it carries) and
an edge between elements that share a node (weight: 18 × shared nodes, the DOFs they couple) or
that are coupled by contact (weight: the contact quadrature points of A's element projecting onto
B's element in the reference configuration, ×18).  METIS (pymetis) cuts it into equal-work parts
with few cut couplings; ``layout_from_owner`` then renumbers the nodes rank by rank.
"""
from __future__ import annotations

import importlib
import os
import sys
from types import ModuleType

import numpy as np
import scipy.sparse as sp

from ..model.beams import Model
from .layout import Layout, block_layout, layout_from_owner

CONTACT_COST = 4


def element_graph(model: Model, contact=None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """CSR element graph (xadj, adjncy, edge weights) and vertex weights."""
    n_el = model.n_elements
    conn = model.connectivity()
    rows, cols, wts = [], [], []
    # elements sharing a node (along a beam: the end node)
    node_el = np.repeat(np.arange(n_el), conn.shape[1])
    nodes = conn.ravel()
    order = np.argsort(nodes, kind="stable")
    nodes, node_el = nodes[order], node_el[order]
    starts = np.flatnonzero(np.r_[True, nodes[1:] != nodes[:-1]])
    ends = np.r_[starts[1:], len(nodes)]
    for s, e in zip(starts, ends):
        els = np.unique(node_el[s:e])
        if len(els) > 1:
            a, b = np.meshgrid(els, els)
            off = a != b
            rows.append(a[off]); cols.append(b[off]); wts.append(np.full(off.sum(), model.dofs_per_node))
    graph = None if contact is None else contact.coupling_graph()
    if graph is not None:
        (pa, pb), cnt = graph.pairs.T, graph.counts
        keep = pa != pb
        rows += [pa[keep], pb[keep]]; cols += [pb[keep], pa[keep]]
        wts += [model.dofs_per_node * cnt[keep], model.dofs_per_node * cnt[keep]]
    if rows:
        r, c, w = np.concatenate(rows), np.concatenate(cols), np.concatenate(wts)
    else:
        r = c = w = np.zeros(0, dtype=np.int64)
    G = sp.coo_matrix((w.astype(np.int64), (r, c)), shape=(n_el, n_el)).tocsr()   # sums duplicates
    G.sort_indices()
    vw = np.concatenate([np.full(b.n_elements, len(b.section.weights) * b.axial_points)
                         for b in model.beams])
    if graph is not None:
        # a contact point (projection + Hessian) costs about as much as CONTACT_COST Gauss points
        vw = vw + CONTACT_COST * graph.points_per_element
    return G.indptr.astype(np.int64), G.indices.astype(np.int64), G.data.astype(np.int64), vw


def load_pymetis() -> ModuleType:
    """pymetis, its METIS calls bound to its own METIS (64-bit indices).  Its ``METIS_*`` and
    ``gk_*`` functions are exported, so a library already loaded with RTLD_GLOBAL took them over:
    dolfinx (the solid references, ancf_verify) loads Debian's METIS 5.1 (32-bit) that way, and
    pymetis imported after it segfaulted on the 64-bit arrays.  RTLD_DEEPBIND keeps its own."""
    if "pymetis" in sys.modules:
        return sys.modules["pymetis"]
    flags = sys.getdlopenflags()
    sys.setdlopenflags(os.RTLD_NOW | os.RTLD_LOCAL | os.RTLD_DEEPBIND)
    try:
        return importlib.import_module("pymetis")
    finally:
        sys.setdlopenflags(flags)


def metis_owner(model: Model, size: int, contact=None) -> np.ndarray:
    """Element → rank from METIS (k-way); identical on every rank (METIS is deterministic)."""
    if size == 1:
        return np.zeros(model.n_elements, dtype=np.int64)
    metis = load_pymetis()
    xadj, adjncy, ew, vw = element_graph(model, contact)
    opts = metis.Options(seed=1)
    adjacency = metis.CSRAdjacency(xadj.tolist(), adjncy.tolist())
    _, parts = metis.part_graph(size, adjacency, vweights=vw.tolist(), eweights=ew.tolist(),
                                  options=opts)
    owner = np.asarray(parts, dtype=np.int64)
    if len(np.unique(owner)) < size:           # tiny graphs: METIS may leave a part empty
        owner = np.argsort(np.argsort(owner, kind="stable"), kind="stable") * size // len(owner)
    return owner


def beam_owner(model: Model, size: int, contact=None) -> np.ndarray:
    """Element → rank with every beam whole on one rank: METIS (k-way, 1 % imbalance allowed)
    on the beam graph contracted from ``element_graph`` (vertex weight: the beam's elements'
    work; edge weight: the couplings between two beams).  Falls back to a greedy assignment of
    the heaviest beams to the lightest rank when METIS leaves a rank empty or unbalanced."""
    n_beams = len(model.beams)
    elem_beam = model.element_beam()
    if size == 1:
        return np.zeros(model.n_elements, dtype=np.int64)
    xadj, adjncy, ew, vw = element_graph(model, contact)
    bw = np.bincount(elem_beam, weights=vw, minlength=n_beams).astype(np.int64)
    rows, cols = np.repeat(elem_beam, np.diff(xadj)), elem_beam[adjncy]
    between = rows != cols                      # couplings within a beam are no edge
    G = sp.coo_matrix((ew[between], (rows[between], cols[between])), shape=(n_beams, n_beams)).tocsr()
    G.sort_indices()
    owner = None
    if n_beams > size:
        metis = load_pymetis()
        adjacency = metis.CSRAdjacency(G.indptr.tolist(), G.indices.tolist())
        _, parts = metis.part_graph(size, adjacency, vweights=bw.tolist(),
                                    eweights=G.data.astype(np.int64).tolist(),
                                    options=metis.Options(seed=1, ufactor=10))
        owner = np.asarray(parts, dtype=np.int64)
    # the heaviest rank may carry at most one beam more than a perfect balance
    limit = bw.sum() / size + bw.max()
    if owner is None or len(np.unique(owner)) < min(size, n_beams) or \
            np.bincount(owner, weights=bw, minlength=size).max() > limit:
        owner = np.zeros(n_beams, dtype=np.int64)
        load = np.zeros(size)
        for b in np.argsort(-bw, kind="stable"):
            owner[b] = int(np.argmin(load))
            load[owner[b]] += bw[b]
    return owner[elem_beam]


OWNERS = {"metis": metis_owner, "beams": beam_owner}


def make_layout(model: Model, method: str, size: int, rank: int, contact=None, comm=None) -> Layout:
    """Layout by ``method`` ('blocks' | 'metis' | 'beams'); METIS runs on rank 0 and is
    broadcast."""
    extra = None if contact is None else contact.coupling_graph().multiplier_node_element
    if method == "blocks" or size == 1:
        lay = block_layout(model.connectivity(), model.n_nodes, size, rank, extra)
    else:
        owner = OWNERS[method](model, size, contact) if rank == 0 else None
        if comm is not None:
            owner = comm.bcast(owner, root=0)
        lay = layout_from_owner(owner, model.connectivity(), model.n_nodes, size, rank, method, extra)
    lay.dofs_per_node = model.dofs_per_node
    return lay


def partition_stats(layout: Layout, model: Model, contact=None) -> dict:
    """Elements, beam nodes and contact multiplier blocks per rank, cut beam couplings and cut
    contact pairs (reference pairs)."""
    conn = model.connectivity()
    own = layout.elem_owner
    # a node shared by elements of different ranks is a cut coupling
    el_of = np.repeat(np.arange(model.n_elements), conn.shape[1])
    nodes = conn.ravel()
    rk = own[el_of]
    lo = np.full(model.n_nodes, layout.size); hi = np.full(model.n_nodes, -1)
    np.minimum.at(lo, nodes, rk); np.maximum.at(hi, nodes, rk)
    cut_nodes = int(np.sum(lo != hi))
    beam_nodes, extra = layout.blocks_per_rank()
    out = {"method": layout.method, "elements_per_rank": np.bincount(own, minlength=layout.size).tolist(),
           "nodes_per_rank": beam_nodes, "cut_beam_nodes": cut_nodes}
    if contact is not None:
        out["multiplier_blocks_per_rank"] = extra
        graph = contact.coupling_graph()
        pairs = graph.pairs
        out["contact_pairs"] = int(len(pairs))
        cut = own[pairs[:, 0]] != own[pairs[:, 1]]
        out["cut_contact_pairs"] = int(np.sum(cut))
        out["cut_contact_points"] = int(np.sum(graph.counts[cut]))
    return out
