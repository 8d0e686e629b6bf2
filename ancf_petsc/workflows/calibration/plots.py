"""The calibration's figures (matplotlib, Agg canvas): data against the fitted model with the
weighted residuals below, one column per data set (``fit.png``); the profile of the objective
along each parameter with the 95 % threshold (``profiles.png``)."""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ...viz.figures import save_figure
from .identify import CHI2_95


def plot_fit(res, path: str) -> str:
    spec, best = res.spec, res.best
    n = len(spec.data)
    fig = Figure(figsize=(4.6 * n, 5.6))
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, n, squeeze=False, gridspec_kw={"height_ratios": [3, 1.2]}, sharex="col")
    start = 0
    for k, d in enumerate(spec.data):
        top, bottom = axes[0, k], axes[1, k]
        scale = d.value_scale or 1.0
        model = np.asarray(best.model[d.name], dtype=float) / scale
        top.errorbar(d.levels, d.values / scale, yerr=d.sigmas / abs(scale), fmt="o", ms=4, color="k",
                     capsize=2, label=f"data ({d.value_column})")
        top.plot(d.levels, model, "-", color="tab:red", lw=1.6, label="fitted model")
        top.set_title(f"{d.name}: {d.quantity}", fontsize=10)
        top.set_ylabel(f"{d.value_column}")
        top.legend(fontsize=8)
        top.grid(alpha=0.3)
        r = best.r[start:start + len(d.levels)]
        start += len(d.levels)
        bottom.axhline(0.0, color="0.5", lw=0.8)
        bottom.plot(d.levels, r, "o", ms=4, color="tab:red")
        bottom.set_ylabel("(model − data) / σ")
        bottom.set_xlabel(f"load level ({d.load_column})")
        bottom.grid(alpha=0.3)
    fig.suptitle(f"{spec.name}: χ² = {2 * best.cost:.3g} over {len(best.r)} points", fontsize=11)
    return save_figure(fig, path)


def plot_profiles(res, path: str) -> str:
    params = [(p, par) for p, par in zip(res.parameters, res.spec.parameters) if p.profile is not None]
    fig = Figure(figsize=(4.2 * len(params), 3.6))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(params), squeeze=False)[0]
    for ax, (p, par) in zip(axes, params):
        v = np.array(p.profile.values + [p.value])
        d = np.array(p.profile.delta + [0.0])
        order = np.argsort(v)
        ok = np.array([s == "completed" for s in p.profile.status] + [True])[order]
        ax.plot(v[order], d[order], "-", color="tab:blue", lw=1.2)
        ax.plot(v[order][ok], d[order][ok], "o", ms=4, color="tab:blue", label="profile (others re-fitted)")
        if not ok.all():
            ax.plot(v[order][~ok], d[order][~ok], "x", ms=6, color="tab:red", label="failed sample")
        ax.axhline(CHI2_95, color="k", ls="--", lw=0.8, label="95 % (Δχ² = 3.84)")
        lo, hi = np.clip(p.interval, v.min(), v.max())
        if hi > lo:
            ax.axvspan(lo, hi, color="tab:green", alpha=0.12, label="linearised 95 % interval")
        if par.log and v.max() > 10 * v.min():     # a narrow range reads better on a linear axis
            ax.set_xscale("log")
        ax.set_yscale("symlog", linthresh=1.0)
        ax.set_ylim(bottom=-0.1)
        ax.set_xlabel(f"{p.name}" + (f" [{par.unit}]" if par.unit else ""))
        ax.set_ylabel("Δχ²")
        ax.set_title(p.verdict, fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path)
