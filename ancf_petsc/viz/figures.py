"""Line charts of run results: load-elongation against the paper, convergence under refinement, slip
and pressure along the tendon; and the small readers they use."""
from __future__ import annotations

import csv
import json

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, ScalarFormatter

from .surface_mesh import MM


def save_figure(fig: Figure, out_png: str) -> str:
    fig.savefig(out_png, dpi=150, bbox_inches="tight", pad_inches=0.08)
    return out_png


def read_csv_table(path: str) -> dict[str, np.ndarray]:
    """Numeric CSV with a header row; lines starting with '#' are comments.  Column -> array."""
    with open(path, newline="") as fh:
        rows = [r for r in csv.reader(line for line in fh
                                      if line.strip() and not line.lstrip().startswith("#"))]
    if not rows:
        raise ValueError(f"{path}: no header row")
    header, body = [h.strip() for h in rows[0]], rows[1:]
    try:
        arr = np.array([[float(x) for x in r] for r in body], dtype=float).reshape(-1, len(header))
    except ValueError as exc:
        raise ValueError(f"{path}: non-numeric or ragged data ({exc})") from None
    return {h: arr[:, i] for i, h in enumerate(header)}


def curve_from_summary(summary_json: str, probe: str, component: int = 0,
                       scale: float = MM) -> tuple[list[float], list[float]]:
    """(load factors, probe displacement component x scale) per converged step of a run."""
    with open(summary_json) as fh:
        steps = json.load(fh)["steps"]
    return ([s["load_factor"] for s in steps],
            [scale * s["probes"][probe]["displacement"][component] for s in steps])


def _colours(labels: list[str]) -> dict[str, tuple]:
    cycle = colormaps["tab10"].colors
    return {lab: cycle[i % len(cycle)] for i, lab in enumerate(dict.fromkeys(labels))}


def plot_load_elongation(curves: dict[str, tuple[list[float], list[float]]], paper_csv: str,
                         out_png: str, columns: dict[str, str], *, load_column: str = "load_N",
                         title: str = "") -> str:
    """Our load-elongation curves (lines) against the paper's points (markers), plus the relative
    error [%] at the paper's loads within our range (ours interpolated) in a lower panel.

    ``curves``: label -> (loads [N], elongations [mm]); ``columns``: label -> CSV column.
    """
    table = read_csv_table(paper_csv)
    missing = [c for c in [load_column, *columns.values()] if c not in table]
    if missing:
        raise ValueError(f"{paper_csv}: no column(s) {missing}; available: {sorted(table)}")
    col = _colours(list(curves))
    fig = Figure(figsize=(6.0, 5.2))
    FigureCanvasAgg(fig)
    ax, axe = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [2.6, 1.0]})
    loads_p = table[load_column]
    for lab, (loads, elong) in curves.items():
        loads, elong = np.asarray(loads, float), np.asarray(elong, float)
        ax.plot(loads, elong, "-", color=col[lab], lw=1.6, label=f"{lab} (this code)")
        if lab not in columns:
            continue
        ref = table[columns[lab]]
        ax.plot(loads_p, ref, "o", mfc="none", color=col[lab], ms=5,
                label=f"{lab} (paper)")
        if not len(loads):
            continue
        inside = (loads_p >= loads.min() - 1e-9) & (loads_p <= loads.max() + 1e-9)
        if inside.any():
            order = np.argsort(loads)
            ours = np.interp(loads_p[inside], loads[order], elong[order])
            err = 100.0 * (ours - ref[inside]) / ref[inside]
            axe.plot(loads_p[inside], err, "o-", color=col[lab], ms=3.5, lw=1.0)
    axe.axhline(0.0, color="0.5", lw=0.6)
    ax.set_ylabel("elongation [mm]")
    axe.set_ylabel("ours vs paper [%]")
    axe.set_xlabel("load [N]")
    ax.legend(fontsize=8, frameon=False)
    for a in (ax, axe):
        a.grid(alpha=0.3)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return save_figure(fig, out_png)


def plot_convergence(table: dict[str, list[tuple[int, float]]],
                     paper: dict[str, list[tuple[int, float]]], out_png: str, *,
                     title: str = "", ylabel: str = "elongation at 400 N [mm]",
                     flagged: list[tuple[int, float]] | None = None) -> str:
    """Elongation vs elements per subtendon (log2 x axis): ours lines + markers, the paper's open
    markers.  A label of ``table`` shares the colour of the ``paper`` label it starts with
    (``"ψ = 0°, linear gap"`` goes with ``"ψ = 0°"``); variants after the comma get their own
    line style; ``flagged`` points get a black cross."""
    col = _colours(list(paper) + [lab.split(",")[0] for lab in table])
    variants = list(dict.fromkeys(lab.split(",", 1)[1].strip() for lab in table if "," in lab))
    styles = ["-s", "--^", ":o", "-.d"]
    fig = Figure(figsize=(7.4, 3.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ticks: set[int] = set()
    for lab, pts in table.items():
        if not pts:
            continue
        n, v = np.array(sorted(pts), dtype=float).T
        var = lab.split(",", 1)[1].strip() if "," in lab else ""
        style = styles[variants.index(var) % len(styles)] if var else styles[0]
        ax.plot(n, v, style, color=col[lab.split(",")[0]], ms=5, lw=1.5, label=f"{lab} (this code)")
        ticks.update(int(x) for x in n)
    for lab, pts in paper.items():
        n, v = np.array(sorted(pts), dtype=float).T
        ax.plot(n, v, "o", mfc="none", color=col[lab], ms=8, mew=1.3, label=f"{lab} (paper)")
        ticks.update(int(x) for x in n)
    if flagged:
        n, v = np.array(flagged, dtype=float).T
        ax.plot(n, v, "x", color="k", ms=9, mew=1.6, label="reached through unstable states")
    ax.set_xscale("log", base=2)
    ax.xaxis.set_major_locator(FixedLocator(sorted(ticks)))
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_locator(FixedLocator([]))
    ax.set_xlabel("elements per subtendon")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return save_figure(fig, out_png)


def interface_labels(names: list[str]) -> list[str]:
    """Legend labels "first − second (curve)" of interface names "curve (first|second)"."""
    out = []
    for name in names:
        curve, _, pair = name.partition(" (")
        out.append(f"{pair.rstrip(')').replace('|', ' − ')} ({curve})" if pair else name)
    return out


def counted_points(level: dict) -> np.ndarray:
    """Which contact points count (weight > 0) at a level from ``io.reader.read_contact``.  A point
    whose partner place lies past the end of its interface curve or past B's beam end (beyond the
    fade bands of ``contact.projection.end_weight``) has weight 0: it is out of contact, and its
    gap, pressure and slip are written as exactly 0.  Files without ``weight`` (before issue 25):
    the points with all three exactly 0."""
    if "weight" in level:
        return np.asarray(level["weight"]) > 0.0
    return ~((level["gap"] == 0.0) & (level["pressure"] == 0.0) & np.all(level["slip"] == 0.0, axis=1))


def plot_slip(levels: list[dict], names: list[str], out_png: str, interfaces: tuple[int, ...],
              length: float, title: str = "", level_label: str = "{:g} N") -> str:
    """Axial slip u_first − u_second (top; first and second in config order) and contact
    pressure (bottom) of the contact points along the tendon, one colour per load level (its
    load factor formatted by ``level_label``), one marker per interface (``names`` per interface
    id): ``levels`` from ``io.reader.read_contact``.
    Points out of contact (``counted_points``) have no slip: they are marked by a cross along the
    top edge of both panels at their x (not as zero slip), explained below the figure."""
    fig = Figure(figsize=(8.0, 6.0))
    FigureCanvasAgg(fig)
    ax_s = fig.add_subplot(2, 1, 1)
    ax_p = fig.add_subplot(2, 1, 2, sharex=ax_s)
    cmap = colormaps["viridis"]
    markers = ("o", "s", "^", "D")
    out = []                                      # (load, x) of the points out of contact
    for i, lev in enumerate(levels):
        c = cmap(i / max(len(levels) - 1, 1))
        counts = counted_points(lev)
        for j, k in enumerate(interfaces):
            sel = (lev["interface"] == k) & counts
            x = MM * lev["x0"][sel, 0]
            order = np.argsort(x)
            label = level_label.format(lev["load_factor"]) if j == 0 else None
            ax_s.plot(x[order], MM * lev["slip"][sel, 0][order], markers[j % 4], color=c, ms=3,
                      label=label)
            ax_p.plot(x[order], 1e-6 * lev["pressure"][sel][order], markers[j % 4], color=c, ms=3)
            gone = (lev["interface"] == k) & ~counts
            for ax in (ax_s, ax_p):
                ax.plot(MM * lev["x0"][gone, 0], np.ones(gone.sum()), "X", color=c, mec="k", ms=8,
                        transform=ax.get_xaxis_transform(), clip_on=False, zorder=5)[0].set_in_layout(False)
            out += [(lev["load_factor"], x0) for x0 in MM * lev["x0"][gone, 0]]
    for j, k in enumerate(interfaces):
        ax_s.plot([], [], markers[j % 4], color="0.4", ms=4, label=names[k].replace(" (", "\n("))
    if out:
        ax_s.plot([], [], "X", color="0.6", mec="k", ms=7, label="out of contact\n(weight 0, no slip)")
    ax_s.set_ylabel("slip along x [mm]\n(u_first − u_second)")
    ax_p.set_ylabel("contact pressure [MPa]\n(> 0 presses, < 0 holds)")
    ax_p.set_xlabel("x along the tendon [mm] (0: supports, L: loaded end)")
    ax_p.set_xlim(0.0, MM * length)
    for ax in (ax_s, ax_p):
        ax.grid(alpha=0.3)
        ax.axhline(0.0, color="0.5", lw=0.8)
    ax_s.legend(fontsize=7, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    if title:
        ax_s.set_title(title, fontsize=10)
    fig.tight_layout()
    if out:                                      # the caption, below the figure
        at = ", ".join(f"{x:.1f} mm at {level_label.format(f)}" for f, x in out)
        fig.text(0.01, 0.0, f"X on the top edge: {len(out)} point(s) out of contact ({at}): the partner "
                 "place lies past the end of the interface curve or of the beam,\nso the point has "
                 "weight 0 and no slip, gap or pressure (results.h5 writes them as 0, with weight 0).",
                 fontsize=7, va="top")
    return save_figure(fig, out_png)
