"""Charts of one run with contact interfaces: the force against the elongation (a prescribed
end's reaction under displacement control) and how far the subtendons moved against each other,
first − second in config order, against the force (``io/derived.py``)."""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .figures import save_figure
from .surface_mesh import MM


def plot_force_and_differences(force: np.ndarray, force_label: str, elongations: dict[str, np.ndarray],
                               differences: dict[str, np.ndarray], out_png: str, title: str = "") -> str:
    """Left: ``force`` [N] (per level) against each probe's elongation u_x [m]; right: each pair's
    end difference u_first − u_second [m] against the force.  ``force_label`` names the force
    (a load or a support's reaction, or the load factor when neither is a force)."""
    fig = Figure(figsize=(11.0, 4.4))
    FigureCanvasAgg(fig)
    left, right = fig.subplots(1, 2)
    for name, u in elongations.items():
        left.plot(MM * np.asarray(u), force, "o-", ms=3, lw=1.2, label=name)
    left.set_xlabel("elongation u_x of the probe [mm]")
    left.set_ylabel(force_label)
    for pair, d in differences.items():
        right.plot(force, MM * np.asarray(d), "o-", ms=3, lw=1.2, label=pair.replace("|", " − "))
    right.set_xlabel(force_label)
    right.set_ylabel("u_x first − second at x = L [mm]")
    right.axhline(0.0, color="0.5", lw=0.8)
    for ax in (left, right):
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8, frameon=False)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return save_figure(fig, out_png)
