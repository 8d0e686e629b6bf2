"""One measured cross-section (a :class:`~.spec.GeometrySource`) → spline loops per subtendon.

Steps (docs/geometry.md): read each outline in its file's coordinates (``outline_formats``);
apply the declared units and axes; check it (closed, simple, a plausible size); make it counter-clockwise;
smooth it (Gaussian along the arc, ``smoothing``); merge the borders of neighbours traced apart
(``merge``); fit interpolating splines with few control points (``fit``, ``fit_tolerance``).  Loops
of named curves (Type III style) are taken exactly as given, interfaces shared by name.
Every change of area is reported.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..config.sections import UNITS, GeometrySource, SectionsSpec
from ..config.values import ConfigError, key_path
from ..physics.spline import SectionError, SplineCurve
from . import polyline as pl
from .fit import corners, fit_curve
from ..outline_formats import FORMATS, OutlineReadError
from .merge import MergeError, gap_closed, merge_outlines, unmerged_borders

__all__ = ["Station", "build_station", "AREA_LIMITS"]

#: plausible total tendon section area [m^2]: 100 um^2 .. 100 cm^2
AREA_LIMITS = (1e-10, 1e-2)
DEFAULT_MERGE_TOL = 50e-6          # [m]
DEFAULT_MERGE_PX = 1.5             # pixels, for image sources (if larger)
MERGE_WIDTH_SHARE = 0.1            # of the narrowest outline's width, at most (if smaller)
DEFAULT_SMOOTHING_PX = 2.0         # pixels, for image sources (0 for point lists and SVG)
#: largest control-point spacing of a fitted curve, as a fraction of its outline's perimeter
MAX_SPACING = 1.0 / 12.0
#: the largest change of a region's area by smoothing, merging and fitting (the traced area is
#: the image's): a region of a few pixels shrank by 42-100 % under the default 2-pixel smoothing
#: and was solved with no word (the shipped outlines change by 0.4 % at most)
MAX_AREA_CHANGE = 0.05
#: the largest smoothing or merge tolerance given, as a fraction of the narrowest outline's width
MAX_SCALE = 0.25


@dataclass
class Station:
    """The spline loops of one cross-section and how they were made."""
    loops: dict[str, list[tuple[SplineCurve, bool]]]
    junctions: np.ndarray                           # (k, 2) points where curves of >= 2 loops meet
    junction_loops: list[set]
    raw_area: dict[str, float]
    area: dict[str, float]                          # of the final spline loops (fine polygon)
    report: list[str] = field(default_factory=list)
    merge_tolerance: float | None = None
    pixel: float | None = None                      # metres per pixel of image sources
    fit_tolerance: float = np.inf                   # [m] the splines' largest distance from the trace

    def polyline(self, name: str, n_per_piece: int = 16) -> np.ndarray:
        """Fine closed polyline of a loop (tendon frame, metres)."""
        parts = [(cv.reversed() if f else cv).sample(n_per_piece)[:-1] for cv, f in self.loops[name]]
        return np.vstack(parts)


def _fmt_mm(p) -> str:
    return f"({p[0] * 1e3:.3f}, {p[1] * 1e3:.3f}) mm"


def _read(src: GeometrySource, name: str):
    """(points in file units, closed flag, scale (u, v) [m/unit], pixel flag, notes): inline
    points as given, a file by its format (outline_formats)."""
    o = src.outlines[name]
    if o.points is not None:
        return np.array(o.points, dtype=float), False, src.scale, False, []
    fmt = FORMATS[o.kind]
    try:
        r = fmt.read(o.file, o.keys, src)
    except OutlineReadError as exc:
        raise src.err(f"outlines.{name}", str(exc)) from None
    return r.points, r.closed, (r.scale if r.scale is not None else src.scale), fmt.pixels, r.notes


def _to_tendon(P: np.ndarray, scale, axes: np.ndarray) -> np.ndarray:
    return (P * np.asarray(scale)[None, :]) @ axes.T


def _close(P: np.ndarray, closed: bool, name: str, src: GeometrySource) -> np.ndarray:
    """Closed polyline without a repeated end point; an open point list is an error."""
    size = float(np.ptp(P, axis=0).max()) if len(P) else 0.0
    if size == 0.0:
        raise src.err(f"outlines.{name}", "all points coincide; an outline needs a region")
    # points a millionth of the outline apart are one (each point of a list written twice with
    # 1e-6 mm added: the median spacing was 0 and the closed outline called open)
    P = pl.drop_duplicates(P, 1e-6 * size, closed=False)
    gap = float(np.linalg.norm(P[-1] - P[0]))
    if gap <= 1e-9 * size:
        P = P[:-1]
    elif not closed:
        steps = np.linalg.norm(np.diff(P, axis=0), axis=1)
        if gap > 3.0 * float(np.median(steps)):
            past = pl.self_intersection(P, 1e-9 * size)   # traced past its start: not 'trace it all the way round'
            if past is not None:
                raise src.err(f"outlines.{name}", f"the outline runs past its start: it crosses itself near "
                              f"{_fmt_mm(past)} and ends at {_fmt_mm(P[-1])}, {gap * 1e3:.3f} mm from its start "
                              f"{_fmt_mm(P[0])}; remove the points traced beyond the start")
            raise src.err(f"outlines.{name}", f"the outline is open: it starts at {_fmt_mm(P[0])} and ends "
                          f"at {_fmt_mm(P[-1])}, {gap * 1e3:.3f} mm apart (points are {np.median(steps) * 1e3:.3f} mm "
                          "apart); trace it all the way round (repeat the first point at the end)")
    if len(P) < 3:
        raise src.err(f"outlines.{name}", "an outline needs at least 3 distinct points")
    hit = pl.self_intersection(P, 1e-9 * size)
    if hit is not None:
        raise src.err(f"outlines.{name}", f"the outline crosses itself near {_fmt_mm(hit)}; "
                      "fix the tracing so that it is a simple loop")
    if abs(pl.signed_area(P)) <= 1e-9 * size * size:
        raise src.err(f"outlines.{name}", f"the outline encloses no area: its {len(P)} points lie on one line; "
                      "trace the region's border all the way round")
    return P


def _plausible(areas: dict[str, float], src: GeometrySource) -> None:
    total = sum(areas.values())
    lo, hi = AREA_LIMITS
    if lo <= total <= hi:
        return
    target = 50e-6                                 # a tendon of 50 mm^2
    cur = UNITS.get(src.units, None)
    hint = ""
    if cur is not None:
        best = min(("m", "mm", "um"), key=lambda u: abs(np.log(total * (UNITS[u] / cur) ** 2 / target)))
        if best != src.units:
            hint = f" (in {best} the outlines would enclose {total * (UNITS[best] / cur) ** 2 * 1e6:.3g} mm^2)"
    big = max(areas, key=areas.get)
    what = "small" if total < lo else "large"
    raise src.err("units", f"the outlines enclose {total:.3g} m^2 in total ({big} {areas[big]:.3g} m^2), too "
                  f"{what} for a tendon (expected {lo:g} to {hi:g} m^2): check units: {src.units}"
                  f"{' and pixel_size' if src.units == 'px' else ''}{hint}")


def default_merge_tolerance(raw: dict[str, np.ndarray], pixel: float | None) -> float:
    """50 µm, at most a tenth of the narrowest outline's width (fascicle-sized sections: the
    demo mask at 2.5 µm pixels, 0.05 mm² in all, was merged across 50 µm, its soleus lost 19 %
    of its area and the geometry was refused), and at least 1.5 pixels of an image source."""
    width = min(pl.smallest_width(P) for P in raw.values())
    return max(min(DEFAULT_MERGE_TOL, MERGE_WIDTH_SHARE * width), DEFAULT_MERGE_PX * (pixel or 0.0))


def _check_scales(raw: dict[str, np.ndarray], opts: SectionsSpec) -> None:
    """A smoothing or merge tolerance given wider than a quarter of the narrowest outline erases it
    (millimetres written as metres: smoothing 0.05 collapsed the outline and raised a NaN traceback,
    merge_tolerance 0.05 said 'no neighbour within the merge tolerance' of two touching halves)."""
    given = [k for k in ("smoothing", "merge_tolerance") if getattr(opts, k) is not None]
    width = {n: pl.smallest_width(P) for n, P in raw.items()} if given else {}
    for key in given:
        narrow = min(width, key=width.get)
        v, w = getattr(opts, key), width[narrow]
        if v > MAX_SCALE * w:
            raise ConfigError(key_path(opts.key, key), f"{v:g} m is {v / w:.3g} x the width of the narrowest "
                              f"outline, {narrow} ({w * 1e3:.4g} mm), which it would erase: it is in metres "
                              f"(50 um = 5e-05); give at most {MAX_SCALE * w:.2g} m; got {v:g}")


def fit_segment(Q: np.ndarray, closed: bool, degree: int, tol: float, name: str,
                 max_spacing: float, traced: np.ndarray | None = None) -> list[SplineCurve]:
    """Curves through an open polyline Q (or closed: Q[0] == Q[-1]), broken at sharp corners;
    ``traced`` marks the traced points (see fit.fit_curve)."""
    traced = np.ones(len(Q), dtype=bool) if traced is None else traced
    body = Q[:-1] if closed else Q
    cidx = corners(body, closed=closed)
    if closed and cidx.size:
        body = np.roll(body, -int(cidx[0]), axis=0)
        traced = np.r_[np.roll(traced[:-1], -int(cidx[0])), False]
        traced[-1] = traced[0]
        cidx = (cidx - cidx[0]) % len(body)
        Q = np.vstack([body, body[:1]])
        cuts = np.r_[np.sort(cidx), len(body)]
    elif closed:
        cuts = np.array([0, len(body)])
    else:
        cuts = np.r_[0, cidx, len(Q) - 1]
    cuts = np.unique(cuts)
    out = []
    for k, (i, j) in enumerate(zip(cuts[:-1], cuts[1:])):
        part = Q[i:j + 1]
        nm = name if len(cuts) == 2 else f"{name}.{k + 1}"
        whole = closed and len(cuts) == 2
        out.append(fit_curve(part, degree, tol, nm, max_spacing, min_points=5 if whole else 2,
                             traced=traced[i:j + 1], periodic=whole and not cidx.size).curve)
    return out


def build_station(src: GeometrySource, opts: SectionsSpec, label: str = "") -> Station:
    """Spline loops of every outline of one geometry description (see the module docstring)."""
    names = list(src.outlines)
    if src.curves:
        return _curve_loops(src, opts, label)
    raw, notes, pixel = {}, [], None
    for name in names:
        P, closed, scale, is_px, nts = _read(src, name)
        P = _close(_to_tendon(P, scale, src.axes), closed, name, src)
        raw[name] = pl.canonical_start(P[::-1] if pl.signed_area(P) < 0 else P)
        notes += [f"{name}: {n}" for n in nts]
        if is_px:
            pixel = float(np.sqrt(scale[0] * scale[1]))
    raw_area = {n: pl.signed_area(P) for n, P in raw.items()}
    _plausible(raw_area, src)
    _check_scales(raw, opts)

    sigma = opts.smoothing if opts.smoothing is not None else DEFAULT_SMOOTHING_PX * (pixel or 0.0)
    tol = opts.merge_tolerance if opts.merge_tolerance is not None else default_merge_tolerance(raw, pixel)
    fit_tol = opts.fit_tolerance if opts.fit_tolerance is not None else \
        (0.5 * pixel if pixel else 0.25 * tol)
    smooth = {n: (pl.smooth(P, sigma) if sigma > 0 else P) for n, P in raw.items()}
    perim = {n: pl.perimeter(P) for n, P in smooth.items()}
    h = min(0.5 * tol, min(perim.values()) / 200.0)
    try:
        merged = merge_outlines(smooth, tol, h)
    except MergeError as exc:
        raise src.err("outlines", str(exc)) from None

    curves_of = []
    for seg in merged.segments:
        owner = seg.owners[0]
        closed = len(seg.owners) == 1 and np.allclose(seg.points[0], seg.points[-1]) and \
            len(merged.loops[owner]) == 1
        try:
            curves_of.append(fit_segment(seg.points, closed, opts.spline_degree, fit_tol, seg.name,
                                          MAX_SPACING * min(perim[o] for o in seg.owners), seg.traced))
        except SectionError as exc:
            raise src.err(f"outlines.{owner}", str(exc)) from None
    loops = {}
    for name in names:
        loop = []
        for sid, rev in merged.loops[name]:
            cs = curves_of[sid]
            loop += [(c, True) for c in reversed(cs)] if rev else [(c, False) for c in cs]
        loops[name] = loop
    st = Station(loops, merged.junctions, merged.junction_loops, raw_area, {}, [], tol, pixel, fit_tol)
    st.area = {n: pl.signed_area(st.polyline(n)) for n in names}
    _check_area_change(st, smooth, sigma, tol, src)
    st.report = _report(st, raw, smooth, merged, curves_of, sigma, tol, fit_tol, label) + \
        [f"  note: {n}" for n in notes]
    return st


def _check_area_change(st: Station, smooth: dict, sigma: float, tol: float, src: GeometrySource) -> None:
    """Smoothing, merging and fitting may change no region's area by more than MAX_AREA_CHANGE; the
    advice names the stage that did most (a merge tolerance of 0.74 mm was told to lower smoothing 0)."""
    for n, a0 in st.raw_area.items():
        change = st.area[n] / a0 - 1.0
        if abs(change) > MAX_AREA_CHANGE:
            by_smoothing = abs(pl.signed_area(smooth[n]) / a0 - 1.0) >= 0.5 * abs(change)
            fix = ("geometry.sections.smoothing a smaller value (0: none) or a finer image" if by_smoothing else
                   f"geometry.sections.merge_tolerance ({tol * 1e3:.3g} mm) a smaller value, or check the tracing")
            raise src.err(f"outlines.{n}", f"smoothing ({sigma * 1e3:.3g} mm), merging and fitting change "
                          f"its area by {change * 100:+.1f} % ({a0 * 1e6:.4g} -> {st.area[n] * 1e6:.4g} mm^2): "
                          f"it is small against them; give {fix}")


def _report(st, raw, smooth, merged, curves_of, sigma, tol, fit_tol, label) -> list[str]:
    head = f"geometry{' ' + label if label else ''}: smoothing {sigma * 1e3:.3g} mm, merge tolerance " \
           f"{tol * 1e3:.3g} mm, fit tolerance {fit_tol * 1e3:.3g} mm"
    lines = [head]
    for n in st.loops:
        a0, a1 = st.raw_area[n], st.area[n]
        a_s = pl.signed_area(smooth[n])
        ctrl = sum(len(c.points) - 1 for c, _ in st.loops[n])
        d, _, _ = pl.PolylineDistance(st.polyline(n)).query(raw[n])
        lines.append(f"  {n}: area {a0 * 1e6:.4g} -> {a1 * 1e6:.4g} mm^2 ({(a1 / a0 - 1) * 100:+.2f} %: "
                     f"smoothing {(a_s / a0 - 1) * 100:+.2f} %, merge and fit {(a1 / a_s - 1) * 100:+.2f} %), "
                     f"{len(st.loops[n])} curves, {ctrl} control points, trace moved <= {d.max() * 1e3:.3f} mm")
    for seg, cs in zip(merged.segments, curves_of):
        if not seg.is_interface:
            continue
        S = np.vstack([c.sample(16) for c in cs])
        dist = pl.PolylineDistance(S, closed=False)
        moves = []
        for side in seg.owners:
            d, _, _ = dist.query(seg.sides[side])
            moves.append(f"{side} moved <= {d.max() * 1e3:.3f} mm (rms {np.sqrt(np.mean(d ** 2)) * 1e3:.3f})")
        length = float(np.linalg.norm(np.diff(S, axis=0), axis=1).sum())
        lines.append(f"  interface {seg.name}: {length * 1e3:.3f} mm long, traces up to "
                     f"{gap_closed(seg, smooth) * 1e3:.3f} mm apart merged, " + ", ".join(moves))
    lines += _unmerged_warnings(merged, smooth, tol)
    free = [n for n in st.loops if all(len(merged.segments[s].owners) == 1 for s, _ in merged.loops[n])]
    if free:
        lines.append(f"  no neighbour within the merge tolerance: {', '.join(free)}")
    return lines


def _unmerged_warnings(merged, smooth, tol: float) -> list[str]:
    """Warnings for a border split into pieces or left partly unmerged by the merge tolerance."""
    out = []
    pieces: dict[tuple[str, ...], int] = {}
    for seg in merged.segments:
        if seg.is_interface:
            key = tuple(sorted(seg.owners))
            pieces[key] = pieces.get(key, 0) + 1
    for (a, b), n in pieces.items():
        if n > 1:
            out.append(f"  warning: the border {a}/{b} was merged in {n} separate pieces (free surface "
                       "between them): if it is one border, its traces drift apart by more than the "
                       f"merge tolerance {tol * 1e3:.3g} mm; raise geometry.sections.merge_tolerance or "
                       "check the tracing")
    done = set()
    for u in sorted(unmerged_borders(merged, smooth, tol), key=lambda u: -u.length):
        pair = tuple(sorted((u.owner, u.neighbour)))
        if pair in done:
            continue
        done.add(pair)
        out.append(f"  warning: {u.length * 1e3:.3f} mm of {u.owner}'s free surface runs "
                   f"{u.gap_min * 1e3:.3f}-{u.gap_max * 1e3:.3f} mm (median {u.gap_median * 1e3:.3f} mm) from "
                   f"{u.neighbour}, just beyond the merge tolerance {tol * 1e3:.3g} mm: the border is partly "
                   f"unmerged (no contact there); if it is one border, raise geometry.sections.merge_tolerance "
                   f"to about {2e3 * u.gap_median:.2g} mm, or check the tracing")
    return out


def _curve_loops(src: GeometrySource, opts: SectionsSpec, label: str) -> Station:
    """Loops of named curves, exactly as given (one SplineCurve per name, shared by its loops)."""
    curves = {}
    for cname, pts in src.curves.items():
        P = _to_tendon(np.array(pts, dtype=float), src.scale, src.axes)
        try:
            curves[cname] = SplineCurve(P, opts.spline_degree, cname, periodic=True)
        except SectionError as exc:
            raise src.err(f"curves.{cname}", str(exc)) from None
    loops = {}
    for name, o in src.outlines.items():
        loop = []
        for ref in o.curves:
            flip = ref.startswith("-")
            loop.append((curves[ref.lstrip("-").strip()], flip))
        _check_chain(loop, o.curves, name, src)
        loops[name] = loop
    # junctions: curve end points used by two or more loops
    pts, owners = [], []
    for name, loop in loops.items():
        for cv, _ in loop:
            for p in (cv.start, cv.end):
                pts.append(p)
                owners.append(name)
    P = np.array(pts)
    size = float(np.ptp(P, axis=0).max())
    J, jl = [], []
    for i, p in enumerate(P):
        if any(np.linalg.norm(p - q) <= 1e-9 * size for q in J):
            continue
        same = np.linalg.norm(P - p, axis=1) <= 1e-9 * size
        who = {owners[k] for k in np.flatnonzero(same)}
        if len(who) >= 2:
            J.append(p)
            jl.append(who)
    st = Station(loops, np.array(J).reshape(-1, 2), jl, {}, {}, [], None, None)
    for n in loops:                                  # counter-clockwise, as make_outline stores them
        if pl.signed_area(st.polyline(n)) < 0:
            loops[n] = [(cv, not f) for cv, f in reversed(loops[n])]
    st.area = {n: pl.signed_area(st.polyline(n)) for n in loops}
    st.raw_area = dict(st.area)
    st.fit_tolerance = opts.fit_tolerance or 1e-4 * size
    _plausible(st.area, src)
    st.report = [f"geometry{' ' + label if label else ''}: {len(curves)} named curves, loops as given"] + \
        [f"  {n}: area {a * 1e6:.4g} mm^2, {len(loops[n])} curves" for n, a in st.area.items()]
    return st


def _check_chain(loop, refs, name: str, src: GeometrySource) -> None:
    """Consecutive curves must meet; a curve listed the wrong way round is named."""
    eff = [cv.reversed() if f else cv for cv, f in loop]
    size = float(np.ptp(np.vstack([c.points for c in eff]), axis=0).max())
    tol = 1e-9 * size
    if len(eff) == 1 and np.linalg.norm(eff[0].end - eff[0].start) > tol:
        raise src.err(f"outlines.{name}.curves", f"curve '{refs[0].strip().lstrip('-')}' alone does not close the "
                      f"loop: it starts at {_fmt_mm(eff[0].start)} and ends at {_fmt_mm(eff[0].end)}; list all "
                      "the curves around the outline")
    for k, cv in enumerate(eff):
        nxt = eff[(k + 1) % len(eff)]
        if np.linalg.norm(cv.end - nxt.start) <= tol:
            continue
        # which single reversal would close the chain here?
        for j, c in ((k, cv), ((k + 1) % len(eff), nxt)):
            r = c.reversed()
            before, after = eff[j - 1], eff[(j + 1) % len(eff)]
            if np.linalg.norm(before.end - r.start) <= tol and np.linalg.norm(r.end - after.start) <= tol:
                ref = refs[j].strip()
                fix = ref[1:] if ref.startswith("-") else "-" + ref
                raise src.err(f"outlines.{name}.curves", f"curve '{ref.lstrip('-')}' runs the wrong way round "
                              f"in this loop (wrong orientation); write '{fix}'")
        raise src.err(f"outlines.{name}.curves", f"curve '{cv.name.lstrip('-')}' ends at {_fmt_mm(cv.end)} but the "
                      f"next curve '{nxt.name.lstrip('-')}' starts at {_fmt_mm(nxt.start)}; list the curves in "
                      "order around the outline")
