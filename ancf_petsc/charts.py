"""Charts of the studies (matplotlib, Agg canvas only): the speed–accuracy Pareto chart
(study.py) and the stability map (stability.py)."""
from __future__ import annotations

import math

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .plotting import _save

ERROR_FLOOR = 1e-16       # exact answers (e.g. uniaxial tension) are drawn at this error


def _family(row) -> str:
    return f"{row.element}, {row.axial_points} axial pts"


def pareto_chart(rows: list, out_png: str, title: str = "", reference: str = "") -> str:
    """Relative error against wall time (log–log) of a speed–accuracy study.

    One colour per (element type, axial points), one marker per section cubature degree, lines
    along increasing element counts (annotated), failed runs as crosses on the top edge, and
    the Pareto front as a black staircase.
    """
    fams = list(dict.fromkeys(_family(r) for r in rows))
    degrees = sorted({r.cubature_degree for r in rows}, key=lambda d: (d is None, d))
    cycle = colormaps["tab10"].colors
    col = {f: cycle[i % len(cycle)] for i, f in enumerate(fams)}
    marks = dict(zip(degrees, "os^Dvp*h"))
    fig = Figure(figsize=(7.6, 4.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ok = [r for r in rows if r.status == "completed" and math.isfinite(r.rel_error)]
    top = max([max(r.rel_error, ERROR_FLOOR) for r in ok] + [1e-3]) * 3.0
    for fam in fams:
        for deg in degrees:
            grp = sorted((r for r in ok if _family(r) == fam and r.cubature_degree == deg),
                         key=lambda r: r.elements)
            if not grp:
                continue
            t = [r.wall_time for r in grp]
            e = [max(r.rel_error, ERROR_FLOOR) for r in grp]
            lab = fam + (f", degree {deg}" if len(degrees) > 1 else "")
            ax.plot(t, e, "-", marker=marks[deg], color=col[fam], ms=5, lw=1.0, alpha=0.9, label=lab)
            for r, x, y in zip(grp, t, e):
                ax.annotate(str(r.elements), (x, y), textcoords="offset points", xytext=(3, 3),
                            fontsize=6, color=col[fam])
    failed = [r for r in rows if r.status != "completed" and math.isfinite(r.wall_time)]
    if failed:
        ax.plot([r.wall_time for r in failed], [top] * len(failed), "x", color="crimson", ms=6,
                label=f"failed ({len(failed)})")
    front = sorted((r for r in rows if r.pareto), key=lambda r: r.wall_time)
    if front:
        xs, ys = [front[0].wall_time], [max(front[0].rel_error, ERROR_FLOOR)]
        for r in front[1:]:
            xs += [r.wall_time, r.wall_time]
            ys += [ys[-1], max(r.rel_error, ERROR_FLOOR)]
        ax.plot(xs, ys, "-", color="k", lw=1.8, alpha=0.6, zorder=0, label="Pareto front")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time of the run [s] (1 core)")
    ax.set_ylabel("relative error vs reference")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    if title:
        ax.set_title(title + (f"\nreference: {reference}" if reference else ""), fontsize=9)
    fig.tight_layout()
    return _save(fig, out_png)


def stability_chart(cells: list, out_png: str, row_key: str, col_key: str, x_key: str,
                    y_key: str, title: str = "") -> str:
    """Panels (rows: ``row_key``, columns: ``col_key``) of an x × y grid of runs; a cell is
    green (shade = Newton iterations) when it converged, red when it failed, with the
    iteration count or the failure written in it.  ``cells`` are dicts with the four keys,
    'status', 'iterations', 'short' (a short failure text) and 'rel_error'."""
    def values(key):
        return list(dict.fromkeys(c.get(key, "") for c in cells))
    rows_v, cols_v, xs, ys = values(row_key), values(col_key), values(x_key), values(y_key)
    its = [c["iterations"] for c in cells if c["status"] == "completed"]
    vmax = max(its + [1])
    greens = colormaps["Greens"]
    fig = Figure(figsize=(2.2 + 2.3 * len(cols_v), 0.8 + 0.42 * len(ys) * len(rows_v) + 0.4 * len(rows_v)))
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(rows_v), len(cols_v), squeeze=False)
    index = {(c.get(row_key, ""), c.get(col_key, ""), c[x_key], c[y_key]): c for c in cells}
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
                    ax.text(b, a, txt, ha="center", va="center", fontsize=5.5)
            ax.imshow(img, aspect="auto", interpolation="nearest")
            ax.set_xticks(range(len(xs)), [str(x) for x in xs], fontsize=6.5)
            ax.set_yticks(range(len(ys)), [str(y) for y in ys], fontsize=6.5)
            if i == len(rows_v) - 1:
                ax.set_xlabel(x_key, fontsize=7)
            if j == 0:
                ax.set_ylabel((f"{row_key} = {rv}\n" if rv != "" else "") + y_key, fontsize=7)
            if i == 0 and cv != "":
                ax.set_title(f"{col_key} = {cv}", fontsize=8)
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return _save(fig, out_png)
