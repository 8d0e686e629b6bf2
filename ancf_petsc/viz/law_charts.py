"""The interface study's chart (scripts/interface_study.py): one subtendon pair's end
difference u_first − u_second against the load, one curve per interface law and one panel per
loading, every law with a line style of its own (a colour of its family's map, darker for a
stiffer matrix or more friction; a marker per family; dashed on the unilateral normal law)."""
from __future__ import annotations

from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .figures import save_figure
from .surface_mesh import MM

#: colour map (None: black and grey) and marker of each family of laws
FAMILIES = {"sliding": (None, "o"), "elastic": ("Blues", "s"), "coulomb": ("Reds", "^")}


def family(name: str) -> str:
    """The family of a law's label on the sliding law ("sliding", "elastic" with bonded, "coulomb")."""
    return "coulomb" if name.startswith("coulomb") else "elastic" if name.startswith(("elastic", "bonded")) else "sliding"


def law_style(label: str, labels: list[str]) -> dict:
    """Line style of the law ``label`` among the study's ``labels``: no two share one."""
    unilateral = label.startswith("unilateral")
    name = label.removeprefix("unilateral").removeprefix(", ") or "sliding"
    cmap, marker = FAMILIES[family(name)]
    if cmap is None:
        colour = "0.45" if unilateral else "k"
    else:
        members = [x for x in labels if not x.startswith("unilateral") and family(x) == family(name)]
        colour = colormaps[cmap](0.35 + 0.6 * members.index(name) / max(len(members) - 1, 1))
    return {"color": colour, "marker": marker, "ls": "--" if unilateral else "-", "ms": 4}


def plot_law_differences(runs: list[dict], labels: list[str], loadings: list[str], pair: str,
                         elements: int, out_png: str) -> str:
    """``runs``: dicts with loading, law, elements, status and steps (summary.json's); the
    pair's end difference [mm] against the load factor (the tendon force in N), per law."""
    fig = Figure(figsize=(13, 5.2))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(loadings), squeeze=False)[0]
    for ax, loading in zip(axes, loadings):
        for r in runs:
            if r["loading"] != loading or r["elements"] != elements or not r["steps"]:
                continue
            load = [st["load_factor"] for st in r["steps"]]
            du = [MM * st["displacement_differences"][pair]["end"] for st in r["steps"]]
            ax.plot(load, du, lw=1.2, **law_style(r["law"], labels),
                    label=r["law"] + ("" if r["status"] == "completed" else f" ({r['status']})"))
        ax.set_title(f"{loading} loading, psi = 45 deg, {elements} elements")
        ax.set_xlabel("tendon force [N]")
        ax.set_ylabel(pair.replace("|", " - ").replace("_", " ") + " at x = L [mm]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6.5, loc="upper left", ncol=2)
    fig.tight_layout()
    return save_figure(fig, out_png)
