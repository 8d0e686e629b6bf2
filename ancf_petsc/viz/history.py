"""The figure of a load-history run (config history:): over the frames, the force each muscle
applies to its subtendon, each subtendon's elongation as a strain, and the differential
displacement of every pair of neighbours at the free end (first − second, config order)."""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .figures import save_figure

COLOURS = ("#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02")


def history_series(summary: dict) -> dict:
    """Per frame: time [s], and per subtendon its end force x [N] and strain; per interface pair
    the end difference [m] (summary.json's ``subtendons`` and ``displacement_differences``)."""
    steps = [s for s in summary["steps"] if "subtendons" in s]
    t = np.array([s.get("time", s["load_factor"]) for s in steps])
    names = list(steps[0]["subtendons"]) if steps else []
    force = {n: np.array([s["subtendons"][n]["end_force"][0] for s in steps]) for n in names}
    strain = {n: np.array([s["subtendons"][n]["strain"] for s in steps]) for n in names}
    pairs = list(steps[0].get("displacement_differences", {})) if steps else []
    diff = {p: np.array([s["displacement_differences"][p]["end"] for s in steps]) for p in pairs}
    return {"time": t, "force": force, "strain": strain, "difference": diff,
            "timed": bool(steps) and "time" in steps[0]}


def plot_history(summary: dict, out_png: str, title: str = "") -> str:
    """Three panels over the frames: muscle forces [N], strains [%], end differences [mm]; the
    last only where the run has neighbours to differ (a history without contact drew it empty)."""
    d = history_series(summary)
    panels = 3 if d["difference"] else 2
    fig = Figure(figsize=(7.0, 2.5 * panels))
    FigureCanvasAgg(fig)
    axes = list(fig.subplots(panels, 1, sharex=True))
    for k, (name, f) in enumerate(d["force"].items()):
        c = COLOURS[k % len(COLOURS)]
        axes[0].plot(d["time"], f, color=c, label=name.replace("_", " "))
        axes[1].plot(d["time"], 100.0 * d["strain"][name], color=c)
    for k, (pair, v) in enumerate(d["difference"].items()):
        axes[2].plot(d["time"], 1e3 * v, color=COLOURS[(k + 3) % len(COLOURS)], label=pair.replace("_", " "))
    axes[0].set_ylabel("muscle force [N]")
    axes[1].set_ylabel("subtendon strain [%]\n(end-section mean)")
    if d["difference"]:
        axes[2].set_ylabel("end displacement\ndifference [mm]")
        axes[2].legend(fontsize=7, frameon=False)
    axes[-1].set_xlabel("time [s]" if d["timed"] else "load factor")
    axes[0].legend(fontsize=8, frameon=False)
    for ax in axes:
        ax.grid(alpha=0.3)
    if title:
        axes[0].set_title(title, fontsize=10)
    return save_figure(fig, out_png)
