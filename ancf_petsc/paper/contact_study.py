"""The contact study: Table 1 for both contact laws, the multipliers' unit k_s over two decades,
the former penalty space solved exactly (docs/contact.md), and the bulk-modulus fit."""
from __future__ import annotations

import numpy as np

from ..workflows import sweep as sw
from .inputs import BEAMS, TWISTS, PaperInputs, read_paper
from .runs import elongations, execute, make_sweep, summary_of
from .tables import Table1

#: factors on k_s, the unit of the multipliers: two decades
SCALINGS = (0.1, 1.0, 10.0)
#: the former penalty formulation's gap space (per element, degree 2 along, mean across) and its
#: answers at ψ = 45° (docs/contact.md, "Before": p_n → ∞ limit of the penalty study at daf134a)
PER_ELEMENT_MEAN = {"axial": 2, "curve": 0, "per_element": True}
PENALTY_LIMIT_MM = {10: 0.16188, 400: 6.22170}
PENALTY_DEFAULT_MM = {10: 0.16200, 400: 6.22250}


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
    out_rows = []
    for (mode, sc, proj), st in zip(rows, states):
        s = summary_of(st)
        row = {"mode": mode, "scaling": sc, "space": "per element, mean" if proj else "default",
               "status": st.status, "e10": np.nan, "e400": np.nan, "iterations": None}
        if s and s["steps"]:
            lf, el = elongations(s)
            row.update(e10=float(el[0]) if np.isclose(lf[0], 10) else np.nan,
                       e400=float(el[-1]) if np.isclose(lf[-1], 400) else np.nan,
                       iterations=s.get("newton_iterations"))
        out_rows.append(row)
    return out_rows


def scaling_spread(rows: list[dict], mode: str) -> tuple[float, float]:
    """Largest relative change of the 10 N and 400 N elongations over the scalings of ``mode``."""
    sel = [r for r in rows if r["mode"] == mode and r["space"] == "default"]
    return tuple(float((max(r[k] for r in sel) - min(r[k] for r in sel)) / np.mean([r[k] for r in sel]))
                 for k in ("e10", "e400"))


def scaling_markdown(rows: list[dict]) -> str:
    lines = ["| contact | pressure space | k_s scale | 10 N [mm] | 400 N [mm] | Newton its |",
             "|---|---|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['mode']} | {r['space']} | {r['scaling']:g} | {r['e10']:.6f} | "
                     f"{r['e400']:.6f} | {r['iterations']} |")
    for mode in ("sliding", "unilateral"):
        d10, d400 = scaling_spread(rows, mode)
        lines.append(f"\n{mode}: over two decades of k_s the elongation changes by {100 * d10:.1e} % "
                     f"(10 N) and {100 * d400:.1e} % (400 N).")
    pe = next(r for r in rows if r["space"] != "default")
    lines.append(f"\nThe former penalty formulation's space solved exactly: {pe['e10']:.5f} / {pe['e400']:.5f} mm "
                 f"at 10 / 400 N; its penalty answers at daf134a were {PENALTY_DEFAULT_MM[10]:.5f} / "
                 f"{PENALTY_DEFAULT_MM[400]:.5f} mm at the default p_n and {PENALTY_LIMIT_MM[10]:.5f} / "
                 f"{PENALTY_LIMIT_MM[400]:.5f} mm in the limit p_n → ∞.")
    return "\n".join(lines)


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
            step = next((st for st in steps if np.isclose(st["load_factor"], f)), None)
            shares = "/".join(f"{100 * c['open_share']:.0f}" for c in step["contact"].values()) if step else ""
            cells.append(f"{paper[p][i]:.3f} | {s:.3f} ({100 * (s / paper[p][i] - 1):+.1f} %) | "
                         f"{u:.3f} ({100 * (u / paper[p][i] - 1):+.1f} %) | {shares} %")
        lines.append(f"| {f:g} | " + " | ".join(cells) + " |")
    its = " · ".join(f"ψ={p}°: {sliding.summaries[p]['newton_iterations']} / "
                     f"{unilateral.summaries[p]['newton_iterations']}" for p in TWISTS
                     if p in sliding.summaries and p in unilateral.summaries)
    lines += ["", f"Newton iterations per column (sliding / unilateral): {its}."]
    return "\n".join(lines)


def fit_bulk_modulus(inputs: PaperInputs, out: str, candidates=(0.70e9, 0.80e9, 0.90e9, 1.0e9), jobs: int = 1, log=print):
    """Least-squares K on the relative errors of Table 1's ψ = 0 column (parabola through the
    sums of squares of the candidates)."""
    params = {"geometry.twist_deg": [0] * len(candidates)}
    for b in range(BEAMS):
        params[f"beams[{b}].material.bulk_modulus"] = list(candidates)
    sweep = make_sweep(inputs, out, "fit_bulk_modulus", params, jobs=jobs)
    states = execute(sweep, log)
    paper = read_paper(inputs.table1_csv)
    sse = {}
    for k, st in zip(candidates, states):
        s = summary_of(st)
        lf, el = elongations(s) if s else (np.array([]), np.array([]))
        # a column that stopped short (a limit point) has no sum: NaN, left out of the fit
        sse[k] = float(np.sum((el / paper["psi0_mm"] - 1.0) ** 2)) if len(el) == len(paper["psi0_mm"]) \
            else float("nan")
    ok = [k for k in candidates if np.isfinite(sse[k])]
    if len(ok) < 3:
        raise sw.SweepError("fit_bulk_modulus", f"only {len(ok)} of the K candidates reached 400 N; "
                                                "three are needed for the parabola")
    c = np.polyfit(np.array(ok), np.array([sse[k] for k in ok]), 2)
    return float(-c[1] / (2 * c[0])), sse
