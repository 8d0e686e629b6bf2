"""Neighbouring outlines traced apart → shared interface curves (issue 17, "neighbours traced apart").

Subtendons segmented one at a time never share their borders exactly: the two traces of one border
differ by tens of micrometres, overlap by a few, and end in different places.  Contact needs ONE
curve per border, used by both loops (contact.find_interfaces).  Here, with the merge tolerance
``tol``:

1. every point of every (densified) outline is labelled with the neighbour whose boundary lies
   within ``tol`` of it (the nearest such), or as free surface; a point inside a neighbour by more
   than ``tol`` is an overlap and an error that names both subtendons and the place;
2. runs of equal labels shorter than ``min_run`` are absorbed by their neighbours (flicker where
   two traces drift apart near the tolerance);
3. each border run of A is paired with the run of B it faces; the interface is the midline of the
   pair (each side's points averaged with their closest points on the other, the two midlines
   averaged at equal fractions of their length: neither side, nor the order the outlines are
   listed in, is the reference), so each side moves by about half the local gap;
4. the ends of all interfaces are clustered (within ``2 tol`` plus the sampling step) into
   junctions, so that where three subtendons meet the three interfaces end at one point;
5. every loop becomes a cyclic sequence of segments between junctions: interfaces (shared,
   reversed on one side) and free segments (its own points).

Gaps wider than ``tol`` stay free surfaces.  The segments are open polylines; ``fit.fit_curve``
turns them into splines.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from ..physics.spline import SectionError
from .polyline import PolylineDistance, densify, inside, resample

__all__ = ["Segment", "Merged", "MergeError", "merge_outlines", "Unmerged", "unmerged_borders",
           "gap_closed"]

# a free run of A is a border left partly unmerged with B when it stays within NEAR_TOLS merge
# tolerances of B over at least RUN_TOLS tolerances of arc length: a flank that leaves a junction at
# an angle of more than ~30 degrees gets that close over a shorter length only
NEAR_TOLS = 5.0
RUN_TOLS = 10.0


class MergeError(SectionError):
    """Neighbouring outlines overlap by more than the merge tolerance (or cannot be merged)."""


@dataclass
class Segment:
    """An open polyline between two junctions (or a closed loop: first point == last point).

    ``owners``: (A,) for a free surface of A; (A, B) for an interface that A's loop traverses
    forward and B's loop backwards.  ``sides``: the original points of each owner that the
    segment replaces (for the report of how far each side moved)."""
    name: str
    points: np.ndarray
    owners: tuple[str, ...]
    sides: dict = field(default_factory=dict)
    traced: np.ndarray | None = None      # mask: points from trace vertices (not densified)

    @property
    def is_interface(self) -> bool:
        return len(self.owners) == 2


@dataclass
class Unmerged:
    """A stretch of ``owner``'s free surface running along ``neighbour`` just beyond the merge
    tolerance: most likely one border whose two traces drifted apart (issue 25, item 9)."""
    owner: str
    neighbour: str
    length: float                 # arc length of the stretch [m]
    gap_max: float                # largest distance to the neighbour on it [m]
    gap_min: float
    gap_median: float


@dataclass
class Merged:
    segments: list[Segment]
    loops: dict[str, list[tuple[int, bool]]]        # outline → [(segment index, reversed)]
    junctions: np.ndarray                            # (k, 2) points where segments meet
    junction_loops: list[set]                        # outlines passing through each junction


def _fmt_mm(p) -> str:
    return f"({p[0] * 1e3:.3f}, {p[1] * 1e3:.3f}) mm"


def _runs(lab: np.ndarray) -> list[tuple[int, int, int]]:
    """Cyclic runs of equal labels: (start, length, label); indices wrap modulo len(lab)."""
    n = len(lab)
    starts = np.flatnonzero(lab != np.roll(lab, 1))
    if starts.size == 0:
        return [(0, n, int(lab[0]))]
    ends = np.r_[starts[1:], starts[0] + n]
    return [(int(s), int(e - s), int(lab[s])) for s, e in zip(starts, ends)]


def _clean(lab: np.ndarray, w: np.ndarray, min_run: float) -> np.ndarray:
    """Absorb runs shorter than ``min_run`` (arc length): a short border run becomes free surface,
    a short free run goes to its neighbours (half each when they differ).  Shortest first."""
    lab = lab.copy()
    n = len(lab)
    for _ in range(10 * n):
        runs = _runs(lab)
        if len(runs) == 1:
            break
        lengths = [w[(s + np.arange(m)) % n].sum() for s, m, _ in runs]
        k = int(np.argmin(lengths))
        if lengths[k] >= min_run:
            break
        s, m, label = runs[k]
        idx = (s + np.arange(m)) % n
        prev_label, next_label = runs[k - 1][2], runs[(k + 1) % len(runs)][2]
        if label >= 0 or len(runs) == 2:
            lab[idx] = -1 if label >= 0 else prev_label
        elif prev_label == next_label:
            lab[idx] = prev_label
        else:
            lab[idx[: m // 2]] = prev_label
            lab[idx[m // 2:]] = next_label
    return lab


def merge_outlines(outlines: dict[str, np.ndarray], tol: float, h: float,
                   min_run: float | None = None) -> Merged:
    """Shared interfaces of counter-clockwise closed polylines (metres) traced apart.

    ``tol``: merge tolerance (largest gap or overlap merged into one interface) [m];
    ``h``: sampling step of the densified outlines [m]; ``min_run``: shortest border or free
    run kept (default max(2 tol, 4 h))."""
    names = list(outlines)
    min_run = max(2.0 * tol, 4.0 * h) if min_run is None else min_run
    DV = {a: densify(outlines[a], h, vertices=True) for a in names}
    D = {a: DV[a][0] for a in names}
    V = {a: DV[a][1] for a in names}
    W = {a: 0.5 * (np.linalg.norm(D[a] - np.roll(D[a], 1, axis=0), axis=1)
                   + np.linalg.norm(np.roll(D[a], -1, axis=0) - D[a], axis=1)) for a in names}
    box = {a: (D[a].min(axis=0) - tol, D[a].max(axis=0) + tol) for a in names}
    dist = {a: PolylineDistance(D[a]) for a in names}

    label, seg = {}, {}
    for ia, a in enumerate(names):
        n = len(D[a])
        best = np.full(n, np.inf)
        lab = np.full(n, -1)
        sg = np.zeros(n, dtype=int)
        for ib, b in enumerate(names):
            if b == a or np.any(box[a][1] < box[b][0]) or np.any(box[b][1] < box[a][0]):
                continue
            d, j, _ = dist[b].query(D[a])
            deep = (d > tol) & inside(D[a], D[b])
            if deep.any():
                k = np.flatnonzero(deep)[np.argmax(d[deep])]
                raise MergeError(
                    f"subtendons '{a}' and '{b}' overlap by {d[k] * 1e3:.3f} mm near "
                    f"{_fmt_mm(D[a][k])}, more than the merge tolerance {tol * 1e3:.3g} mm; "
                    "correct the tracing or raise geometry.sections.merge_tolerance")
            _check_interiors(a, b, D[a], D[b], dist[b], tol)
            near = (d <= tol) & (d < best)
            best[near], lab[near], sg[near] = d[near], ib, j[near]
        label[a], seg[a] = lab, sg

    # label runs, pair them across neighbours; unpaired border runs become free surface
    for _ in range(4):
        for a in names:
            label[a] = _clean(label[a], W[a], min_run)
        pairs, unpaired = _pair_runs(names, label, seg)
        if not unpaired:
            break
        for a, (s, m) in unpaired:
            label[a][(s + np.arange(m)) % len(label[a])] = -1
    else:
        for a in names:
            label[a] = _clean(label[a], W[a], min_run)
        pairs, _ = _pair_runs(names, label, seg)

    return _assemble(names, D, V, dist, pairs, tol, h)


def _check_interiors(a: str, b: str, Da: np.ndarray, Db: np.ndarray, dist_b, tol: float) -> None:
    """MergeError where a's inside lies in b's: a's boundary moved 2 tol inwards (still inside a)
    and farther than tol inside b.  Catches what the boundary test cannot: outlines that lie on
    each other (two subtendons traced from one label), whose boundaries are everywhere within
    tol of each other."""
    t = np.roll(Da, -1, axis=0) - np.roll(Da, 1, axis=0)
    n = np.column_stack([-t[:, 1], t[:, 0]]) / np.maximum(np.linalg.norm(t, axis=1), 1e-300)[:, None]
    P = Da + 2.0 * tol * n                     # counter-clockwise: the inside is on the left
    d, _, _ = dist_b.query(P)
    deep = (d > tol) & inside(P, Da) & inside(P, Db)
    if deep.any():
        k = np.flatnonzero(deep)[np.argmax(d[deep])]
        raise MergeError(
            f"subtendons '{a}' and '{b}' overlap: the inside of '{a}' near {_fmt_mm(P[k])} lies "
            f"{d[k] * 1e3:.3f} mm inside '{b}' (the outlines lie on each other), more than the merge "
            f"tolerance {tol * 1e3:.3g} mm; correct the tracing")


def _pair_runs(names, label, seg):
    """Pairs (a, run_a, b, run_b) of facing border runs, and the runs left without a partner."""
    runs = {a: _runs(label[a]) for a in names}
    pairs, taken = [], set()
    for ia, a in enumerate(names):
        for ra in runs[a]:
            s, m, ib = ra
            if ib < 0 or ib < ia:
                continue
            b = names[ib]
            mid = seg[a][(s + m // 2) % len(label[a])]
            nb = len(label[b])
            for rb in runs[b]:
                sb, mb, lb = rb
                if lb == ia and (mid - sb) % nb < mb and (b, sb) not in taken:
                    pairs.append((a, ra, b, rb))
                    taken |= {(a, s), (b, sb)}
                    break
    unpaired = [(a, (s, m)) for a in names for s, m, lb in runs[a] if lb >= 0 and (a, s) not in taken]
    return pairs, unpaired


def _midline(Pa: np.ndarray, dist_b, Pb: np.ndarray, dist_a) -> np.ndarray:
    """The midline of a border traced as Pa (on A) and Pb (on B, in A's direction): each side's
    points averaged with their closest points on the other side, the two midlines resampled at
    equal fractions of their arc length and averaged, so that neither side is the reference."""
    mids = []
    for P, dist in ((Pa, dist_b), (Pb, dist_a)):
        _, _, foot = dist.query(P)
        mids.append(0.5 * (P + foot))
    n = max(len(Pa), len(Pb))
    return 0.5 * sum(resample(M, n, closed=False) if len(M) > 1 else np.repeat(M, n, axis=0) for M in mids)


def _assemble(names, D, V, dist, pairs, tol, h) -> Merged:
    rho = 2.0 * tol + 2.0 * h
    # interfaces: midline of A's run and B's (recomputed: cleaning may have given a run points that
    # were nearer another neighbour, or none); every midline point counts as traced
    mids, ends = [], []
    for a, (s, m, _), b, (sb, mb, _) in pairs:
        ia, ib = (s + np.arange(m)) % len(D[a]), (sb + np.arange(mb)) % len(D[b])
        mid = _midline(D[a][ia], dist[b], D[b][ib][::-1], dist[a])
        mids.append((mid, np.ones(len(mid), dtype=bool)))
        ends += [mid[0], mid[-1]]
    # junctions: cluster the interface ends
    if ends:
        E = np.array(ends)
        parent = np.arange(len(E))

        def root(i):
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i
        for i, j in cKDTree(E).query_pairs(rho):
            parent[root(i)] = root(j)
        roots = np.array([root(i) for i in range(len(E))])
        uniq, cluster = np.unique(roots, return_inverse=True)
        J = np.array([E[cluster == c].mean(axis=0) for c in range(len(uniq))])
    else:
        cluster, J = np.zeros(0, dtype=int), np.zeros((0, 2))

    segments: list[Segment] = []
    # per loop: (start index on the loop, end index, kind, segment id, reversed, j_start, j_end)
    pieces = {a: [] for a in names}
    count = {}
    for k, ((a, (s, m, _), b, (sb, mb, _)), (mid, vert)) in enumerate(zip(pairs, mids)):
        j0, j1 = cluster[2 * k], cluster[2 * k + 1]
        if j0 == j1:                       # a border shorter than the junction radius
            continue
        keep = (np.linalg.norm(mid - J[j0], axis=1) > rho) & (np.linalg.norm(mid - J[j1], axis=1) > rho)
        pts = np.vstack([J[j0], mid[keep], J[j1]])
        key = (a, b)
        count[key] = count.get(key, 0) + 1
        name = f"{a}/{b}" + (f"#{count[key]}" if count[key] > 1 else "")
        na, nb = len(D[a]), len(D[b])
        sides = {a: D[a][(s + np.arange(m)) % na], b: D[b][(sb + np.arange(mb)) % nb]}
        segments.append(Segment(name, pts, (a, b), sides, np.r_[False, vert[keep], False]))
        sid = len(segments) - 1
        pieces[a].append((s, s + m, sid, False, j0, j1))
        pieces[b].append((sb, sb + mb, sid, True, j1, j0))

    loops: dict[str, list[tuple[int, bool]]] = {}
    jloops = [set() for _ in range(len(J))]
    for a in names:
        P, n = D[a], len(D[a])
        ps = sorted(pieces[a])
        if not ps:
            segments.append(Segment(f"{a}", np.vstack([P, P[:1]]), (a,), {a: P}, np.r_[V[a], V[a][:1]]))
            loops[a] = [(len(segments) - 1, False)]
            continue
        loop = []
        for i, (s, e, sid, rev, js, je) in enumerate(ps):
            loop.append((sid, rev))
            jloops[js].add(a)
            jloops[je].add(a)
            s2, e2, _, _, js2, _ = ps[(i + 1) % len(ps)]
            if i + 1 == len(ps):
                s2 += n
            own_idx = np.arange(e, s2) % n
            own = P[own_idx]
            if js2 == je and len(own) == 0:
                continue
            keep = (np.linalg.norm(own - J[je], axis=1) > rho) & (np.linalg.norm(own - J[js2], axis=1) > rho)
            if js2 == je and not keep.any():
                continue                   # a notch smaller than the junction radius
            pts = np.vstack([J[je], own[keep], J[js2]])
            segments.append(Segment(f"{a}:free{sum(1 for g in segments if g.owners == (a,)) + 1}",
                                    pts, (a,), {a: own}, np.r_[False, V[a][own_idx][keep], False]))
            loop.append((len(segments) - 1, False))
        loops[a] = loop
    return Merged(segments, loops, J, jloops)


def gap_closed(seg: Segment, outlines: dict[str, np.ndarray]) -> float:
    """Largest distance between the two traces that an interface ``seg`` replaced [m]."""
    a, b = seg.owners
    d, _, _ = PolylineDistance(outlines[b]).query(seg.sides[a])
    return float(d.max()) if d.size else 0.0


def unmerged_borders(merged: Merged, outlines: dict[str, np.ndarray], tol: float) -> list[Unmerged]:
    """Free-surface stretches that run within NEAR_TOLS * tol of a neighbour over at least
    RUN_TOLS * tol of arc length (longest stretch per owner and neighbour)."""
    dist = {n: PolylineDistance(P) for n, P in outlines.items()}
    found: dict[tuple[str, str], Unmerged] = {}
    for seg in merged.segments:
        if seg.is_interface:
            continue
        a, P = seg.owners[0], seg.points
        step = np.linalg.norm(np.diff(P, axis=0), axis=1)
        for b in outlines:
            if b == a:
                continue
            d, _, _ = dist[b].query(P)
            near = d < NEAR_TOLS * tol
            both = near[1:] & near[:-1]                 # segment pieces with both ends near
            if not both.any():
                continue
            # contiguous runs of near pieces: (start piece, end piece)
            edges = np.diff(np.r_[0, both.astype(int), 0])
            for s0, s1 in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
                length = float(step[s0:s1].sum())
                if length < RUN_TOLS * tol:
                    continue
                dd = d[s0:s1 + 1]
                key = (a, b)
                if key not in found or found[key].length < length:
                    found[key] = Unmerged(a, b, length, float(dd.max()), float(dd.min()), float(np.median(dd)))
    return list(found.values())
