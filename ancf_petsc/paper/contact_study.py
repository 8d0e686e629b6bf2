"""The contact study: Table 1 for both contact laws, the multipliers' unit k_s over two decades,
the former penalty space solved exactly (docs/contact.md), and the bulk-modulus fit."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..io.levels import gap_note, reported_at, step_at
from ..workflows import sweep as sw
from ..workflows.sweep.collect import run_iterations
from .inputs import BEAMS, TWISTS, PaperInputs, read_paper
from .runs import elongation, elongations, execute, make_sweep, summary_of
from .tables import Table1

#: factors on k_s, the unit of the multipliers: two decades
SCALINGS = (0.1, 1.0, 10.0)
#: the former penalty formulation's gap space (per element, degree 2 along, mean across) and its
#: answers at ψ = 45° (docs/contact.md, "Before": p_n → ∞ limit of the penalty study at daf134a)
PER_ELEMENT_MEAN = {"axial": 2, "curve": 0, "per_element": True}
PENALTY_LIMIT_MM = {10: 0.16188, 400: 6.22170}
PENALTY_DEFAULT_MM = {10: 0.16200, 400: 6.22250}
#: the scaling study's columns and their loads [N]
SCALING_LOADS = {"e10": 10.0, "e400": 400.0}


def scaling_study(inputs: PaperInputs, out: str, twist: int = 45, scalings=SCALINGS, ranks: int = 1, jobs: int = 1,
                  log=print) -> list[dict]:
    """Soleus elongation at 10 and 400 N for both contact laws with the multipliers' unit k_s
    scaled over two decades, and the former penalty space solved exactly (no penalty)."""
    rows = [("sliding", sc, None) for sc in scalings] + [("unilateral", sc, None) for sc in scalings]
    rows.append(("sliding", 1.0, PER_ELEMENT_MEAN))
    params = {"geometry.twist_deg": [twist] * len(rows), "contact.mode": [m for m, _, _ in rows],
              "contact.scaling": [sc for _, sc, _ in rows],
              "contact.projection": [pr for _, _, pr in rows]}
    states = execute(make_sweep(inputs, out, f"scaling_psi{twist}", params, ranks=ranks, jobs=jobs), log)
    return [scaling_row(summary_of(st), mode, sc, proj, st.status) for (mode, sc, proj), st in zip(rows, states)]


def scaling_row(s: dict | None, mode: str, scaling: float, projection: dict | None, status: str,
                loads: dict = SCALING_LOADS) -> dict:
    """One run of the scaling study: the elongations at 10 and 400 N (``s`` its summary.json, None
    if missing); ``reported``: column → (level, load factor it was reported at past a gap)."""
    row = {"mode": mode, "scaling": scaling, "space": "per element, mean" if projection else "default",
           "status": status, "e10": np.nan, "e400": np.nan, "iterations": None, "reported": {}}
    if s and s["steps"]:
        for key, load in loads.items():
            step = step_at(s["steps"], load)
            if step is not None:
                row[key] = elongation(step)
                if reported_at(step) is not None:
                    row["reported"][key] = (load, reported_at(step))
        row["iterations"] = run_iterations(s)
    return row


def scaling_spread(rows: list[dict], mode: str) -> tuple[float, float]:
    """Largest relative change of the 10 N and 400 N elongations over the scalings of ``mode``."""
    sel = [r for r in rows if r["mode"] == mode and r["space"] == "default"]
    return tuple(float((max(r[k] for r in sel) - min(r[k] for r in sel)) / np.mean([r[k] for r in sel]))
                 for k in ("e10", "e400"))


def _unreached(row: dict) -> str:
    """The loads a scaling-study run did not reach, in words ('' when it reached both)."""
    return " and ".join(f"{SCALING_LOADS[k]:g} N" for k in SCALING_LOADS if not np.isfinite(row[k]))


def scaling_markdown(rows: list[dict]) -> str:
    lines = ["| contact | pressure space | k_s scale | 10 N [mm] | 400 N [mm] | Newton its |",
             "|---|---|---:|---:|---:|---:|"]
    for r in rows:
        cell = {k: f"{r[k]:.6f}{'†' if k in r.get('reported', {}) else ''}" if np.isfinite(r[k]) else "not reached"
                for k in ("e10", "e400")}
        lines.append(f"| {r['mode']} | {r['space']} | {r['scaling']:g} | {cell['e10']} | {cell['e400']} | "
                     f"{r['iterations']} |")
    lines += [f"\n† {r['mode']}, {r['space']}, k_s scale {r['scaling']:g}, {level:g} N: {gap_note(at)} "
              "(solver.step_over_jumps)" for r in rows for level, at in r.get("reported", {}).values()]
    for mode in dict.fromkeys(r["mode"] for r in rows):
        short = [f"k_s scale {r['scaling']:g} did not reach {_unreached(r)}" for r in rows
                 if r["mode"] == mode and r["space"] == "default" and _unreached(r)]
        if short:
            lines.append(f"\n{mode}: no spread over k_s: the run with {'; with '.join(short)}.")
            continue
        d10, d400 = scaling_spread(rows, mode)
        lines.append(f"\n{mode}: over two decades of k_s the elongation changes by {100 * d10:.1e} % "
                     f"(10 N) and {100 * d400:.1e} % (400 N).")
    pe = next(r for r in rows if r["space"] != "default")
    if _unreached(pe):
        lines.append(f"\nThe former penalty formulation's space solved exactly: its run did not reach {_unreached(pe)}.")
        return "\n".join(lines)
    lines.append(f"\nThe former penalty formulation's space solved exactly: {pe['e10']:.5f} / {pe['e400']:.5f} mm "
                 f"at 10 / 400 N; its penalty answers at daf134a were {PENALTY_DEFAULT_MM[10]:.5f} / "
                 f"{PENALTY_DEFAULT_MM[400]:.5f} mm at the default p_n and {PENALTY_LIMIT_MM[10]:.5f} / "
                 f"{PENALTY_LIMIT_MM[400]:.5f} mm in the limit p_n → ∞.")
    return "\n".join(lines)


def _law_cell(t: Table1, p: int, i: int) -> str:
    """A column's elongation at the i-th level and its error against the paper, or 'not reached'."""
    v = t.ours[p][i]
    return f"{v:.3f}{t.mark(p, i)} ({100 * (v / t.paper[p][i] - 1):+.1f} %)" if np.isfinite(v) else "not reached"


def laws_markdown(sliding: Table1, unilateral: Table1) -> str:
    """Table 1 for both contact laws beside the paper, with the open share of each interface."""
    paper = sliding.paper
    lines = ["| load [N] | " + " | ".join(f"ψ={p}° paper | sliding | unilateral | open mg/lg/lg-mg"
                                          for p in TWISTS) + " |",
             "|---:|" + "---:|---:|---:|:---:|" * len(TWISTS)]
    for i, f in enumerate(sliding.loads):
        cells = []
        for p in TWISTS:
            s, u = sliding.ours[p][i], unilateral.ours[p][i]
            steps = unilateral.summaries[p]["steps"] if p in unilateral.summaries else []
            step = step_at(steps, float(f))          # a level passed over in a gap: where reported
            shares = "/".join(f"{100 * c['open_share']:.0f}" for c in step["contact"].values()) if step else ""
            cells.append(f"{paper[p][i]:.3f} | {_law_cell(sliding, p, i)} | {_law_cell(unilateral, p, i)} | "
                         + (f"{shares} %" if step else ""))
        lines.append(f"| {f:g} | " + " | ".join(cells) + " |")
    notes = sliding.gap_notes("sliding, ") + unilateral.gap_notes("unilateral, ")
    lines += ["", *notes] if notes else []
    its = " · ".join(f"ψ={p}°: {run_iterations(sliding.summaries[p])} / "
                     f"{run_iterations(unilateral.summaries[p])}" for p in TWISTS
                     if p in sliding.summaries and p in unilateral.summaries)
    lines += ["", f"Newton iterations per column (sliding / unilateral): {its}."]
    return "\n".join(lines)


@dataclass
class BulkFit:
    """The least-squares bulk modulus and every column it solved (issue 25, item 10)."""
    k: float                                    # minimiser [Pa]
    sse: float                                  # sum of squared relative errors at k
    evaluations: list[tuple[float, float]]     # (K, sum of squares) in the order solved
    errors: np.ndarray                          # relative errors of the column at k
    bounds: tuple[float, float]


def _column_errors(inputs: PaperInputs, out: str, ks: list[float], jobs: int, log) -> list[np.ndarray]:
    """Relative errors of Table 1's ψ = 0 column at each K (one sweep); a column
    that does not reach 400 N is an error naming K and where it stopped, never a missing point."""
    tag = "_".join(f"{k / 1e9:.6g}".replace(".", "p") for k in ks)
    params = {"geometry.twist_deg": [0] * len(ks)}
    for b in range(BEAMS):
        params[f"beams[{b}].material.bulk_modulus"] = list(ks)
    states = execute(make_sweep(inputs, out, f"fit_bulk_modulus_{tag}", params, jobs=jobs), log)
    paper = read_paper(inputs.table1_csv)["psi0_mm"]
    found = []
    for k, st in zip(ks, states):
        s = summary_of(st)
        lf, el = elongations(s) if s else (np.array([]), np.array([]))
        if len(el) != len(paper):
            last = f"last converged level {lf[-1]:g} N" if len(lf) else "no level converged"
            raise sw.SweepError("fit_bulk_modulus", f"the psi = 0 column with K = {k / 1e9:.4g} GPa did not "
                                f"reach 400 N ({st.status}, {last}; run directory {st.run.dir}); "
                                "the fit needs every column it asks for")
        found.append(el / paper - 1.0)
    return found


def fit_bulk_modulus(inputs: PaperInputs, out: str, grid=(0.6e9, 0.8e9, 1.0e9, 1.2e9, 1.4e9),
                     xtol: float = 2e6, jobs: int = 1, log=print) -> BulkFit:
    """Least-squares K on the relative errors of Table 1's ψ = 0 column: the columns of a coarse
    grid (solved together) bracket the minimum, bounded Brent (scipy) finds it to ``xtol``."""
    from scipy.optimize import minimize_scalar
    ks = sorted(grid)
    errors = dict(zip(ks, _column_errors(inputs, out, ks, jobs, log)))   # K → errors, in solve order

    def sse(k: float) -> float:
        return float(np.sum(errors[k] ** 2))

    best = int(np.argmin([sse(k) for k in ks]))
    if best in (0, len(ks) - 1):
        raise sw.SweepError("fit_bulk_modulus", f"the least squares are smallest at the end of the grid "
                            f"(K = {ks[best] / 1e9:.3g} GPa): the minimum lies outside "
                            f"{ks[0] / 1e9:.3g}-{ks[-1] / 1e9:.3g} GPa; widen the grid")
    bounds = (ks[best - 1], ks[best + 1])

    def f(k: float) -> float:
        k = float(round(k / 1e5) * 1e5)          # 0.1 MPa: reuse a run asked for twice
        if k not in errors:
            errors[k] = _column_errors(inputs, out, [k], 1, log)[0]
        return sse(k)

    res = minimize_scalar(f, bounds=bounds, method="bounded", options={"xatol": xtol})
    k = float(round(res.x / 1e5) * 1e5)
    return BulkFit(k, f(k), [(kk, sse(kk)) for kk in errors], errors[k], bounds)


def fit_markdown(fit: BulkFit) -> str:
    """The fit, every column it solved, and the errors of the column at the minimiser."""
    lines = [f"K = {fit.k / 1e9:.4f} GPa minimises the sum of squared relative errors of Table 1's "
             f"psi = 0 column ({fit.sse:.3e}; largest error {100 * np.abs(fit.errors).max():.2f} %), "
             f"bounded Brent between {fit.bounds[0] / 1e9:.2g} and {fit.bounds[1] / 1e9:.2g} GPa "
             f"after a coarse grid; {len(fit.evaluations)} columns solved, all to 400 N.", "",
             "| K [GPa] | sum of squared relative errors |", "|---|---|"]
    lines += [f"| {k / 1e9:.4f} | {v:.4e} |" for k, v in sorted(fit.evaluations)]
    return "\n".join(lines)
