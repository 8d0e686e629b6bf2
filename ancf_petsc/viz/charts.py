"""Charts of the studies (matplotlib, Agg canvas only): the speed–accuracy Pareto chart
(study.py) and the stability map (stability.py), plus the helpers that keep charts readable:
log axes with at least two labelled ticks (:func:`readable_log_axis`) and point labels that
overlap neither each other nor the markers (:func:`place_labels`)."""
from __future__ import annotations

import math
import textwrap

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, FuncFormatter, LogLocator, NullFormatter

from ..physics.elements import ELEMENTS
from .figures import save_figure

ERROR_FLOOR = 1e-16       # exact answers (e.g. uniaxial tension) are drawn at this error

# mantissas of the major ticks per decade, sparsest first (readable_log_axis takes the first
# set that puts at least `min_ticks` ticks inside the axis)
_MANTISSAS = ((1.0,), (1.0, 3.0), (1.0, 2.0, 5.0), (1.0, 1.5, 2.0, 3.0, 5.0, 7.0))
_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def log_ticks(lo: float, hi: float, min_ticks: int = 3) -> list[float]:
    """Major tick values inside [lo, hi] (0 < lo < hi) for a log axis: the decades when there
    are at least ``min_ticks`` of them, else 1-3, 1-2-5 or 1-1.5-2-3-5-7 per decade."""
    best: list[float] = []
    for mant in _MANTISSAS:
        ticks = [m * 10.0 ** k for k in range(math.floor(math.log10(lo)) - 1, math.ceil(math.log10(hi)) + 1)
                 for m in mant]
        ticks = [t for t in ticks if lo * (1 - 1e-9) <= t <= hi * (1 + 1e-9)]
        best = ticks
        if len(ticks) >= min_ticks:
            break
    return best


def tick_label(v: float, plain: bool | None = None) -> str:
    """A tick value: plain ('0.05', '2', '300') or as a power of ten ('2×10⁻⁴', '10⁻⁵');
    by default plain between 1e-3 and 1e4."""
    if plain if plain is not None else 1e-3 <= v < 1e4:
        return f"{v:g}"
    k = math.floor(math.log10(v) + 1e-9)
    m = v / 10.0 ** k
    power = "10" + str(k).translate(_SUPERSCRIPT)
    return power if abs(m - 1.0) < 1e-6 else f"{m:g}×{power}"


def readable_log_axis(axis, lo: float | None = None, hi: float | None = None,
                      min_ticks: int = 3) -> list[float]:
    """Give a log-scaled ``ax.xaxis``/``ax.yaxis`` labelled major ticks (:func:`log_ticks`,
    at least two) and unlabelled minor ticks; the view limits are kept (or set to lo, hi)."""
    get, set_ = ((axis.axes.get_xlim, axis.axes.set_xlim) if axis.axis_name == "x"
                 else (axis.axes.get_ylim, axis.axes.set_ylim))
    a, b = get()
    lo = a if lo is None else lo
    hi = b if hi is None else hi
    if hi / lo < 1.5:                       # too narrow to carry two 1-1.5-2-... ticks
        mid = math.sqrt(lo * hi)
        lo, hi = mid / 1.25, mid * 1.25
    set_(lo, hi)
    ticks = log_ticks(lo, hi, min_ticks)
    axis.set_major_locator(FixedLocator(ticks))
    plain = all(1e-3 <= t < 1e4 for t in ticks)       # one style per axis
    axis.set_major_formatter(FuncFormatter(lambda v, _: tick_label(v, plain)))
    axis.set_minor_locator(LogLocator(base=10.0, subs=np.arange(2, 10) * 1.0, numticks=100))
    axis.set_minor_formatter(NullFormatter())
    return ticks


def _overlap(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether box a (x0, y0, x1, y1) overlaps any of the boxes b (k, 4)."""
    if not len(b):
        return np.zeros(0, dtype=bool)
    return (a[0] < b[:, 2]) & (b[:, 0] < a[2]) & (a[1] < b[:, 3]) & (b[:, 1] < a[3])


def place_labels(ax, xy: list[tuple[float, float]], texts: list[str], colours: list,
                 fontsize: float = 6.5, marker_pt: float = 6.0) -> tuple[list, int]:
    """Annotate data points without overlaps: each label goes to the first free spot of a ring
    of candidate positions around its point (growing outwards, with a thin leader line beyond
    the first ring), avoiding every other label, every marker and the axes' edges.  Points are
    labelled in the given order (put the important ones first); a label without a free spot
    is left out.  Call after the layout is final.  Returns (annotations, number left out)."""
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    to_px = fig.dpi / 72.0
    disp = ax.transData.transform(np.asarray(xy, dtype=float).reshape(-1, 2))
    box = ax.bbox.extents
    half = 0.5 * marker_pt * to_px
    taken = [np.column_stack([disp - half, disp + half])] if len(disp) else []
    placed = []
    skipped = 0
    directions = [(1, 1), (1, -1), (-1, 1), (-1, -1), (1, 0), (-1, 0), (0, 1), (0, -1)]
    for (px, py), (x, y), text, colour in zip(disp, xy, texts, colours):
        probe = ax.text(0, 0, text, fontsize=fontsize)
        ext = probe.get_window_extent(renderer)
        probe.remove()
        w, h = ext.width, ext.height
        spot = None
        for radius in (3.0, 8.0, 14.0, 22.0):
            for dx, dy in directions:
                ox = radius * dx * to_px
                oy = radius * dy * to_px
                x0 = px + ox - (w if dx < 0 else (w / 2 if dx == 0 else 0))
                y0 = py + oy - (h if dy < 0 else (h / 2 if dy == 0 else 0))
                cand = np.array([x0, y0, x0 + w, y0 + h])
                inside = (cand[0] >= box[0] and cand[2] <= box[2] and cand[1] >= box[1]
                          and cand[3] <= box[3])
                if inside and not any(_overlap(cand, t).any() for t in taken):
                    spot = (radius, dx, dy, cand)
                    break
            if spot:
                break
        if spot is None:
            skipped += 1
            continue
        radius, dx, dy, cand = spot
        taken.append(cand[None])
        ha = "left" if dx > 0 else ("right" if dx < 0 else "center")
        va = "bottom" if dy > 0 else ("top" if dy < 0 else "center")
        arrow = dict(arrowstyle="-", lw=0.4, color=colour, shrinkA=0, shrinkB=2) if radius > 3 else None
        placed.append(ax.annotate(text, (x, y), xytext=(radius * dx, radius * dy),
                                  textcoords="offset points", ha=ha, va=va, fontsize=fontsize,
                                  color=colour, arrowprops=arrow))
    return placed, skipped


def text_overlaps(fig, artists: list) -> list[tuple[str, str]]:
    """Pairs of the given text artists whose drawn text boxes overlap (leader lines aside)."""
    from matplotlib.text import Text
    renderer = fig.canvas.get_renderer()
    boxes = [(a.get_text(), np.array(Text.get_window_extent(a, renderer).extents)) for a in artists]
    return [(ta, tb) for i, (ta, a) in enumerate(boxes) for tb, b in boxes[i + 1:]
            if _overlap(a, b[None]).any()]


def _family(row) -> str:
    return f"{row.element}, {row.axial_points} axial Gauss points"


def pareto_figure(rows: list, title: str = "", reference: str = "") -> tuple[Figure, object, list]:
    """The Pareto chart as a figure: (figure, axes, element-count annotations).  See
    :func:`pareto_chart`."""
    fams = list(dict.fromkeys(_family(r) for r in rows))
    degrees = sorted({r.cubature_degree for r in rows}, key=lambda d: (d is None, d))
    cycle = colormaps["tab10"].colors
    col = {f: cycle[i % len(cycle)] for i, f in enumerate(fams)}
    marks = dict(zip(degrees, "os^Dvp*h"))
    fig = Figure(figsize=(9.0, 4.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ok = [r for r in rows if r.status == "completed" and math.isfinite(r.rel_error)]
    top = max([max(r.rel_error, ERROR_FLOOR) for r in ok] + [1e-3]) * 3.0
    points: list[tuple] = []                  # (pareto?, x, y, text, colour) of every marker
    for fam in fams:
        for deg in degrees:
            grp = sorted((r for r in ok if _family(r) == fam and r.cubature_degree == deg),
                         key=lambda r: r.elements)
            if not grp:
                continue
            t = [r.wall_time for r in grp]
            e = [max(r.rel_error, ERROR_FLOOR) for r in grp]
            lab = fam + (f", section rule of degree {deg}" if len(degrees) > 1 else "")
            ax.plot(t, e, "-", marker=marks[deg], color=col[fam], ms=5, lw=1.0, alpha=0.9, label=lab)
            points += [(r.pareto, x, y, str(r.elements), col[fam]) for r, x, y in zip(grp, t, e)]
    failed = [r for r in rows if r.status != "completed" and math.isfinite(r.wall_time)]
    if failed:
        ax.plot([r.wall_time for r in failed], [top] * len(failed), "x", color="crimson", ms=6,
                label=f"failed runs ({len(failed)}), drawn at the top")
    front = sorted((r for r in rows if r.pareto), key=lambda r: r.wall_time)
    if front:
        xs, ys = [front[0].wall_time], [max(front[0].rel_error, ERROR_FLOOR)]
        for r in front[1:]:
            xs += [r.wall_time, r.wall_time]
            ys += [ys[-1], max(r.rel_error, ERROR_FLOOR)]
        ax.plot(xs, ys, "-", color="k", lw=1.8, alpha=0.6, zorder=0,
                label="Pareto front (nothing is both faster and more accurate)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    xs_all = [p[1] for p in points] + [r.wall_time for r in failed]
    ys_all = [p[2] for p in points] + ([top] if failed else [])
    if xs_all:
        readable_log_axis(ax.xaxis, min(xs_all) / 1.3, max(xs_all) * 1.3)
        readable_log_axis(ax.yaxis, min(ys_all) / 2.0, max(ys_all) * 2.0)
    ax.set_xlabel("wall time of the run [s] (1 core)")
    ax.set_ylabel("relative error against the reference")
    ax.grid(alpha=0.3, which="major")
    ax.grid(alpha=0.12, which="minor")
    ax.legend(fontsize=7, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              title="numbers at the points:\nelements per beam", title_fontsize=7)
    if title:
        ax.set_title(title + (f"\nreference: {reference}" if reference else ""), fontsize=9)
    fig.tight_layout()
    fig.canvas.draw()
    order = sorted(range(len(points)), key=lambda i: not points[i][0])    # the front first
    labels, _ = place_labels(ax, [points[i][1:3] for i in order], [points[i][3] for i in order],
                             [points[i][4] for i in order])
    return fig, ax, labels


def pareto_chart(rows: list, out_png: str, title: str = "", reference: str = "") -> str:
    """Relative error against wall time (log–log) of a speed–accuracy study.

    One colour per (element type, axial points), one marker per section cubature degree, lines
    along increasing element counts (labelled where there is room, the Pareto front first),
    failed runs as crosses on the top edge, and the Pareto front as a black staircase.
    """
    fig, _, _ = pareto_figure(rows, title, reference)
    return save_figure(fig, out_png)


# the stability map's keys and values in words (the CSV keeps the config's names)
AXIS_WORDS = {"increment": "load increment (fraction of the load)",
              "linesearch": "line search", "bulk_ratio": "K/μ", "contact": "contact",
              "element": "element"}
FAILURE_WORDS = {"max it": "out of Newton iterations", "LS": "line search failed",
                 "J<0": "an element inverted", "NaN": "residual not a number",
                 "budget": "Newton budget spent"}


def axis_words(key: str, value=None) -> str:
    """A stability-map key (and value) as a reader would say it: 'K/μ = 100', 'sliding
    contact', 'element 3333 without ecm'."""
    name = AXIS_WORDS.get(key, key.replace("_", " "))
    if value is None:
        return name
    if key == "contact":
        return f"{value} contact"
    if key == "element":
        text = str(value)
        element, _, locking = text.partition("-")
        remedy = ELEMENTS[element].default_locking if element in ELEMENTS else "none"
        return "element " + (f"{element} without {remedy}" if locking == "none" and remedy != "none"
                             else text + (f" ({remedy})" if not locking and remedy != "none" else ""))
    return f"{name} = {value}"


def stability_chart(cells: list, out_png: str, row_key: str, col_key: str, x_key: str,
                    y_key: str, title: str = "") -> str:
    """Panels (rows: ``row_key``, columns: ``col_key``) of an x × y grid of runs; a cell is
    green (shade = Newton iterations) when it converged, red when it failed, with the
    iteration count or the failure written in it (abbreviations explained under the chart).
    ``cells`` are dicts with the four keys, 'status', 'iterations', 'short' (a short failure
    text) and 'rel_error'."""
    def values(key):
        return list(dict.fromkeys(c.get(key, "") for c in cells))
    rows_v, cols_v, xs, ys = values(row_key), values(col_key), values(x_key), values(y_key)
    its = [c["iterations"] for c in cells if c["status"] == "completed"]
    vmax = max(its + [1])
    greens = colormaps["Greens"]
    fig = Figure(figsize=(2.2 + 2.3 * len(cols_v), 1.1 + 0.42 * len(ys) * len(rows_v) + 0.4 * len(rows_v)))
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(rows_v), len(cols_v), squeeze=False)
    index = {(c.get(row_key, ""), c.get(col_key, ""), c[x_key], c[y_key]): c for c in cells}
    shown: set[str] = set()
    for i, rv in enumerate(rows_v):
        for j, cv in enumerate(cols_v):
            ax = axes[i][j]
            img = np.ones((len(ys), len(xs), 3))
            for a, yv in enumerate(ys):
                for b, xv in enumerate(xs):
                    c = index.get((rv, cv, xv, yv))
                    if c is None:
                        img[a, b] = (0.92, 0.92, 0.92)
                        continue
                    if c["status"] == "completed":
                        img[a, b] = greens(0.25 + 0.6 * math.log1p(c["iterations"]) / math.log1p(vmax))[:3]
                        txt = str(c["iterations"])
                        err = c.get("rel_error", math.nan)
                        if math.isfinite(err) and err > 0.01:
                            txt += f"\n{100 * err:.0f}%"
                    else:
                        img[a, b] = (0.86, 0.30, 0.28)
                        txt = c.get("short", "fail")
                        shown.update(w for w in FAILURE_WORDS if w in txt)
                    ax.text(b, a, txt, ha="center", va="center", fontsize=5.5)
            ax.imshow(img, aspect="auto", interpolation="nearest")
            ax.set_xticks(range(len(xs)), [str(x) for x in xs], fontsize=6.5)
            ax.set_yticks(range(len(ys)), [str(y) for y in ys], fontsize=6.5)
            if i == len(rows_v) - 1:
                ax.set_xlabel(axis_words(x_key), fontsize=7)
            if j == 0:
                ax.set_ylabel((axis_words(row_key, rv) + "\n" if rv != "" else "") + axis_words(y_key),
                              fontsize=7)
            if i == 0 and cv != "":
                ax.set_title(axis_words(col_key, cv), fontsize=8)
    if title:
        fig.suptitle(title, fontsize=9)
    notes = ["green: converged (Newton iterations; % = error against the reference where above 1\u00a0%)"
             + ("; adaptive: the default load stepping with cut-backs" if x_key == "increment" else "")]
    notes.append("red: failed" + (" — " + "; ".join(f"{w}: {FAILURE_WORDS[w]}" for w in FAILURE_WORDS
                                                     if w in shown) if shown else ""))
    width, height = fig.get_size_inches()
    lines = [ln for note in notes for ln in textwrap.wrap(note, int((width - 0.2) / 0.05),
                                                           subsequent_indent="  ")]
    fig.tight_layout(rect=(0, (0.1 + 0.12 * len(lines)) / height, 1, 1))
    fig.text(0.01, 0.01, "\n".join(lines), fontsize=6.5, color="0.25", va="bottom")
    return save_figure(fig, out_png)
