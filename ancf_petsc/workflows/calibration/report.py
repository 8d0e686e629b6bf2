"""The calibration's files: ``fit.json`` (everything, machine-readable), ``report.md`` (the table of
parameters with errors, correlations and verdicts), the figures (``plots.py``)."""
from __future__ import annotations

import json
import os

import numpy as np

from ...io.files import atomic_write, remove_quietly
from .calibrate import CalibrationResult
from .identify import CHI2_95, RCOND
from .log import SampleLog
from .plots import plot_fit, plot_profiles
from .sample import n_data, optimum_notes


def _finite(x):
    """JSON-safe numbers (inf/NaN as strings)."""
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return float(x) if np.isfinite(x) else str(x)
    return x


def _span(interval, closed=(True, True)) -> str:
    """[lo, hi] for a table; an open side (the profile never crossed 3.84) as its edge with ≤/≥,
    an unbounded one as ∞."""
    lo, hi = interval
    a = f"{lo:.4g}" if np.isfinite(lo) and lo > -1e300 else "−∞"
    b = f"{hi:.4g}" if np.isfinite(hi) else "∞"
    return f"[{'≤' if not closed[0] else ''}{a}, {'≥' if not closed[1] else ''}{b}]"


def s2_text(unc) -> str:
    """How the errors were scaled (identify.py), in words."""
    if unc.absolute:
        return "s² = 1 (absolute σ)"
    if unc.floored:
        return (f"s² = 1: χ²/(m − n) = {unc.chi2_dof:.3g} ({unc.dof} dof) is below 1, the data fit "
                "better than their σ, and the σ are kept as the errors (not shrunk by it)")
    return f"s² = χ²/(m − n) = {unc.s2:.4g} ({unc.dof} dof)"


def summary(res: CalibrationResult, log: SampleLog) -> dict:
    spec, best, unc = res.spec, res.best, res.uncertainty
    params = [{"name": p.name, "keys": spec.parameters[i].key_text(), "value": p.value, "start": p.start,
               "se": _finite(p.se), "ci95": _finite(list(p.interval)), "rel_halfwidth95": _finite(p.width),
               "verdict": p.verdict, "reason": p.reason, "at_bound": p.at_bound,
               "profile": None if p.profile is None else {
                   "values": p.profile.values, "delta_chi2": _finite(p.profile.delta),
                   "status": p.profile.status, "closed": list(p.profile.closed),
                   "interval95": list(p.profile.interval)}}
              for i, p in enumerate(res.parameters)]
    return {
        "fit": spec.name, "fit_file": spec.file, "model": spec.model_path, "status": res.fit.status,
        "message": res.fit.message, "cost": best.cost, "chi2": 2 * best.cost, "data_points": n_data(spec),
        "parameters": params, "s2": None if unc is None else unc.s2, "dof": None if unc is None else unc.dof,
        "chi2_per_dof": None if unc is None else unc.chi2_dof,
        "correlation": None if unc is None else _finite(unc.corr.tolist()),
        "singular_values": None if unc is None else unc.singular_values.tolist(),
        "best_sample": best.record(), "samples": log.counts(), "throughput": res.throughput,
        "wall_time": res.wall_time, "starts": res.starts,
        "rules": {"chi2_95": CHI2_95, "rcond": RCOND,
                  "determined": "w <= 0.25 and the profile closed on both sides",
                  "not determined": "the profile open on both sides, or w > 1 (or infinite)",
                  "w": "relative half-width of the profile's 95 % interval where computed, else of "
                       "the linearised one (t SE / |p|; t: Student's 97.5 % quantile, m - n dof); "
                       "log-scaled: the larger factor - 1", "t95": None if unc is None else unc.t95}}


def markdown(res: CalibrationResult, log: SampleLog) -> str:
    spec, unc = res.spec, res.uncertainty
    tp = res.throughput
    lines = [f"# Calibration {spec.name}", "",
             f"Model `{os.path.relpath(spec.model_path, os.path.dirname(spec.file))}`, "
             f"{n_data(spec)} data points in {len(spec.data)} set(s), {len(spec.parameters)} parameter(s); "
             f"{spec.optimizer.method}: {res.fit.status} ({res.fit.message}).", "",
             f"χ² = {2 * res.best.cost:.4g}" + ("" if unc is None else f", {s2_text(unc)}")
             + f"; {tp.get('samples', 0)} samples ({tp.get('resumed', 0)} read from the log): "
             + ", ".join(f"{n} {status}" for status, n in sorted(log.counts().items())) + ".", "",
             "| parameter | start | fitted | SE | 95 % interval, linearised | 95 % interval, profile | w | verdict |",
             "|---|---:|---:|---:|---|---|---:|---|"]
    for p in res.parameters:
        bound = " (at a bound)" if p.at_bound else ""
        prof = "—" if p.profile is None else _span(p.profile.interval, p.profile.closed)
        lines.append(f"| {p.name} | {p.start:.4g} | {p.value:.5g}{bound} | {p.se:.3g} | "
                     f"{_span(p.interval)} | {prof} | {p.width:.3g} | {p.verdict}: {p.reason} |")
    gaps = optimum_notes(spec, res.best)
    if gaps:
        lines += [""] + [f"- {g.removeprefix('warning: ')}" for g in gaps]
    if unc is not None and len(res.parameters) > 1:
        names = [p.name for p in res.parameters]
        lines += ["", "Correlations:", "", "| | " + " | ".join(names) + " |",
                  "|---|" + "---:|" * len(names)]
        for n, row in zip(names, unc.corr):
            lines.append(f"| {n} | " + " | ".join(f"{c:+.3f}" for c in row) + " |")
    lines += ["", "Verdict: w is the relative half-width of the 95 % interval (the profile's where "
              "computed, else the linearised one; log-scaled: the larger factor − 1); determined: "
              "w ≤ 0.25 and the profile crosses Δχ² = 3.84 on both sides; not determined: the profile "
              "flat on both sides within the bounds, or w > 1; else weakly determined.",
              "", "![fit](fit.png)"] + (["", "![profiles](profiles.png)"]
                                       if any(p.profile for p in res.parameters) else [])
    return "\n".join(lines) + "\n"


def write_report(res: CalibrationResult, log: SampleLog) -> list[str]:
    """fit.json, report.md, fit.png and profiles.png in the output directory; their paths.  Those
    of them this fit does not write (profiles.png without profiles) are removed: an earlier fit's
    there would read as this one's."""
    os.makedirs(res.output, exist_ok=True)
    names = ("fit.json", "report.md", "fit.png", "profiles.png")
    out = [os.path.join(res.output, "fit.json")]
    atomic_write(out[0], json.dumps(summary(res, log), indent=1) + "\n")
    if res.parameters:
        out.append(os.path.join(res.output, "report.md"))
        atomic_write(out[1], markdown(res, log))
        out.append(plot_fit(res, os.path.join(res.output, "fit.png")))
        if any(p.profile for p in res.parameters):
            out.append(plot_profiles(res, os.path.join(res.output, "profiles.png")))
    remove_quietly(*[os.path.join(res.output, n) for n in names if os.path.join(res.output, n) not in out])
    return out
