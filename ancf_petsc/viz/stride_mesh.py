"""The figure of the stride's mesh study (workflows/stride_mesh.py): per contact law, each mesh's
worst error against the law's finest mesh over frames per second of solve, for the subtendons'
strains and end differences, and for the interfaces' normal forces."""
from __future__ import annotations

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .figures import save_figure
from .history import COLOURS

#: the panels: (title, the row columns whose largest value is plotted)
PANELS = (("strains and end differences", ("error_strain", "error_difference")),
          ("interfaces' normal forces", ("error_normal_force",)))


def plot_stride_mesh(rows: list[dict], out_png: str) -> str:
    """Two log-log panels of error against frames/s (solve), one line per law, each point a mesh
    labelled with its element count; the finest meshes (the references) are left out."""
    fig = Figure(figsize=(9.0, 3.8))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2)
    laws = list(dict.fromkeys(r["law"] for r in rows))
    for ax, (title, keys) in zip(axes, PANELS):
        for k, law in enumerate(laws):
            pts = []
            for r in rows:
                errs = [float(r[key]) for key in keys if r.get(key)]
                if r["law"] == law and errs and float(r["frames_per_s"]) > 0:
                    pts.append((float(r["frames_per_s"]), max(errs), int(r["elements"])))
            if not pts:
                continue
            c = COLOURS[k % len(COLOURS)]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", color=c, label=law)
            for x, y, n in pts:
                ax.annotate(f"{n}", (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7, color=c)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("frames per second (solve)")
        ax.set_title(title, fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("largest error over the stride\n(against the finest mesh)")
    axes[0].legend(fontsize=8)
    return save_figure(fig, out_png)
