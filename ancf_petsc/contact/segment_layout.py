"""Where each segment's block of the contact Jacobian goes (contact/blocks.py): the points of a
batch of segments, their unknowns inside the block, the multipliers' rows and the block's PETSc
DOF ids.  All of it follows from the points' B elements, the rank's numbering and the held DOFs,
so one layout serves every Jacobian while no point moves to another B element (``layouts``:
kept on the Contact until its numbering changes; ~40 numpy calls per Jacobian, a third of the
Achilles column's contact blocks once their arithmetic was compiled)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: points per batch of segment blocks (bounds the temporaries' memory)
CHUNK_POINTS = 2048


@dataclass
class SegmentLayout:
    """The block layout of the local segments ``sk`` (positions in ``Contact.segments``), each
    spanning ``width`` B elements: D unknowns per block, the first Dq the bodies'."""
    segs: np.ndarray       # (n_s,) segment ids
    P_s: int               # points per block (the largest segment's)
    D: int
    Dq: int
    sel: np.ndarray        # (n,) the points' positions in the local arrays
    s_loc: np.ndarray      # (n,) their block
    p_loc: np.ndarray      # (n,) their place in it
    j: np.ndarray          # (n,) their B element among the block's (0 … width − 1)
    cols: np.ndarray       # (n, 2 EL) their A and B element's unknowns in the block
    whole: bool            # one B element per block
    dense: bool            # ... and every block full with its points in order
    real: np.ndarray       # (n_s, K) the segments' multiplier slots in use
    loc: np.ndarray        # their positions in ``Contact.mults``
    Phi_s: np.ndarray      # (n_s, K, P_s) the multipliers' functions at the points
    share: np.ndarray      # (n_s, K) Φ summed over the segment's points
    ss: np.ndarray         # (m,) block of each multiplier in use
    kk: np.ndarray         # (m,) its slot
    mrow: np.ndarray       # (m,) its row in the block
    rows: np.ndarray       # (n_s, D) PETSc DOF ids, −1 dropped

    @property
    def n_s(self) -> int:
        return len(self.segs)

    def spread(self, X: np.ndarray) -> np.ndarray:
        """Per-point rows X (points, Dq, ...) as (n_s, P_s, Dq, ...) over the block's unknowns."""
        if self.dense:
            return X.reshape((self.n_s, self.P_s) + X.shape[1:])
        out = np.zeros((self.n_s, self.P_s, self.Dq) + X.shape[2:])
        if self.whole:
            out[self.s_loc, self.p_loc] = X
        else:
            out[self.s_loc[:, None], self.p_loc[:, None], self.cols] = X
        return out


def layouts(c, eB: np.ndarray, fixed_mask: np.ndarray) -> list[SegmentLayout]:
    """The layouts of the ``Contact`` c's local segments whose points project onto the B
    elements ``eB`` (over ``c.local``), batched by the number of B elements they span (and in
    chunks of at most ``CHUNK_POINTS`` points); the last ones are kept on c (``block_layouts``,
    reset by ``Contact.set_numbering``) and returned again for the same eB and held DOFs."""
    key = (eB.tobytes(), fixed_mask.tobytes())
    if c.block_layouts is not None and c.block_layouts[0] == key:
        return c.block_layouts[1]
    srow = np.searchsorted(c.segments, c.points.seg[c.local])
    first_b = np.full(len(c.segments), np.iinfo(np.int64).max)
    np.minimum.at(first_b, srow, eB)
    last_b = np.full(len(c.segments), -1)
    np.maximum.at(last_b, srow, eB)
    span = last_b - first_b + 1
    p_max = int(c.points.seg_size.max())
    out = []
    for width in np.unique(span):
        group = np.flatnonzero(span == width)
        for sk in np.array_split(group, -(-len(group) * p_max // CHUNK_POINTS)):
            out.append(_layout(c, eB, srow, first_b, sk, int(width), fixed_mask))
    c.block_layouts = (key, out)
    return out


def _layout(c, eB, srow, first_b, sk, width: int, fixed_mask) -> SegmentLayout:
    """The layout of the segments ``sk``.  The block's unknowns: A's 3 nodes, B's 2 width + 1
    nodes and the (at most two) multiplier nodes of the functions living on the segment:
    D = 18 (2 width + 6) (three-node elements of 18-DOF nodes, 3363; k axial nodes of Dn DOFs:
    Dn ((k − 1) width + k + 3))."""
    pts, sp = c.points, c.space
    DOFS_PER_NODE, EL = c.model.dofs_per_node, c.model.block.dofs_per_element
    k = c.model.block.axial_nodes - 1                   # an element's last node
    segs = c.segments[sk]
    n_s, P_s = len(sk), int(pts.seg_size[segs].max())
    D = DOFS_PER_NODE * (k * width + k + 4)
    Dq = D - 2 * DOFS_PER_NODE                          # the segment's two multiplier nodes
    in_sk = np.zeros(len(c.segments), dtype=bool)
    in_sk[sk] = True
    sel = np.flatnonzero(in_sk[srow])                   # positions in the local arrays
    s_loc = np.searchsorted(sk, srow[sel])
    p_loc = c.local[sel] - pts.seg_start[segs[s_loc]]
    j = eB[sel] - first_b[srow[sel]]
    # each point's 2 x 54 unknowns (A element, its B element) inside the block; B's elements
    # share end nodes, so element j starts 2 nodes after element j - 1
    cols = np.concatenate([np.broadcast_to(np.arange(EL), (len(sel), EL)),
                           EL + k * DOFS_PER_NODE * j[:, None] + np.arange(EL)], axis=1)
    # one B element per segment: each point's unknowns are the block's, in order, and its rows
    # go in whole (every segment full and its points in order: the arrays as they are), never
    # scattered entry by entry (0.1 of the Achilles column's 0.25 s of contact assembly)
    whole = width == 1
    dense = whole and len(sel) == n_s * P_s and np.array_equal(s_loc * P_s + p_loc, np.arange(len(sel)))
    m_ids = sp.seg_mults[segs]                                            # (n_s, K), −1 pad
    real = m_ids >= 0
    Phi_s = sp.dense[segs][:, :, :P_s]                                    # (n_s, K, P_s)
    ss, kk = np.nonzero(real)
    second = sp.node[m_ids[ss, kk]] != c.seg_mnodes[segs[ss], 0]
    mrow = Dq + DOFS_PER_NODE * second + sp.slot[m_ids[ss, kk]]
    # DOF indices: A nodes, B nodes of elements first … first + width − 1, multiplier nodes
    els = c.conn[first_b[sk][:, None] + np.arange(width)]            # (n_s, width, 3)
    bnodes = np.concatenate([els[:, :, :k].reshape(n_s, -1), els[:, -1:, k]], axis=1)
    nodes = np.concatenate([c.conn[pts.seg_eA[segs]], bnodes, c.seg_blocks[segs]], axis=1)
    rows = (DOFS_PER_NODE * nodes[:, :, None] + np.arange(DOFS_PER_NODE)).reshape(n_s, D)
    # the B elements of a segment need not be contiguous (points on e and e + 2): the
    # nodes of an element in between that no point projects onto stay out of the matrix
    used = np.zeros((n_s, D), dtype=bool)
    used[:, :EL] = True
    used[:, Dq:] = np.repeat(c.seg_blocks[segs] >= 0, DOFS_PER_NODE, axis=1)
    used[s_loc[:, None], cols[:, EL:]] = True
    rows = np.where(used, rows, -1)
    rows[rows >= 0] = np.where(fixed_mask[rows[rows >= 0]], -1, rows[rows >= 0])
    return SegmentLayout(segs=segs, P_s=P_s, D=D, Dq=Dq, sel=sel, s_loc=s_loc, p_loc=p_loc, j=j, cols=cols,
                         whole=whole, dense=dense, real=real, loc=np.searchsorted(c.mults, m_ids[real]),
                         Phi_s=Phi_s, share=Phi_s.sum(axis=2), ss=ss, kk=kk, mrow=mrow, rows=rows)
