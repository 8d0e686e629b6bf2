"""The paper's Tables 1 and 2, the contact study and the figures for the Type III Achilles tendon.

Every study is a sweep (``sweep.py``) over the Achilles config, so runs resume, fail cleanly and
can be run with several ranks.  The tables put our numbers beside the paper's
(``configs/data/paper_table{1,2}_*.csv``) with relative errors.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass

import numpy as np
import yaml

from ..io.reader import read_contact
from ..workflows import sweep as sw

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CONFIGS = os.path.join(ROOT, "configs")
BASE = os.path.join(CONFIGS, "achilles_type3_psi45.yaml")
PAPER_T1 = os.path.join(CONFIGS, "data", "paper_table1_elongation.csv")
PAPER_T2 = os.path.join(CONFIGS, "data", "paper_table2_convergence.csv")
TWISTS = (0, 15, 45)
PROBE = "soleus"
BEAMS = 3


def read_paper(path: str) -> dict[str, np.ndarray]:
    """A paper table CSV (``#`` comment lines) as columns."""
    with open(path) as fh:
        rows = [ln.strip().split(",") for ln in fh if ln.strip() and not ln.startswith("#")]
    head, body = rows[0], np.array(rows[1:], dtype=float)
    return {h: body[:, i] for i, h in enumerate(head)}


# ------------------------------------------------------------------------------ running
def make_sweep(out: str, name: str, parameters: dict, mode: str = "list", ranks: int = 1,
               jobs: int = 1, petsc: list[str] | None = None, base: str = BASE) -> sw.Sweep:
    """Write ``<out>/<name>.sweep.yaml`` and load it."""
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, f"{name}.sweep.yaml")
    # the report marks unstable levels itself (Table 2's "u"): they are results, not failures
    n = len(next(iter(parameters.values()))) if mode == "list" else 1
    parameters = {**parameters, "solver.allow_unstable": [True] * n}
    doc = {"base": base, "name": name, "mode": mode, "parameters": parameters,
           "run": {"ranks": ranks, "jobs": jobs, "petsc": list(petsc or [])},
           "output": os.path.join(out, name)}
    with open(path, "w") as fh:
        yaml.safe_dump(doc, fh, sort_keys=False)
    return sw.load_sweep(path)


def execute(sweep: sw.Sweep, log=print) -> list[sw.RunState]:
    """Run what is not done yet; the state of every run afterwards."""
    sw.run_sweep(sweep, log=log)
    sw.collect(sweep)
    return [sw.run_state(r) for r in sw.expand(sweep)]


def summary_of(state: sw.RunState) -> dict | None:
    path = os.path.join(state.run.dir, "summary.json")
    if not os.path.exists(path):
        return None
    with open(path) as fh:
        return json.load(fh)


def elongations(summary: dict, probe: str = PROBE) -> tuple[np.ndarray, np.ndarray]:
    """(load levels, x-elongation [mm]) of a probe over the converged steps."""
    steps = summary["steps"]
    return (np.array([s["load_factor"] for s in steps]),
            np.array([1e3 * s["probes"][probe]["displacement"][0] for s in steps]))


# ------------------------------------------------------------------------------ Table 1
@dataclass
class Table1:
    loads: np.ndarray
    ours: dict[int, np.ndarray]            # psi -> soleus elongation [mm] (nan where missing)
    paper: dict[int, np.ndarray]
    others: dict[int, dict[str, np.ndarray]]   # psi -> medial/lateral elongation [mm]
    summaries: dict[int, dict]

    @property
    def columns(self) -> list[int]:
        """The pretwists that have results."""
        return [p for p in TWISTS if p in self.summaries]

    def errors(self) -> dict[int, np.ndarray]:
        return {p: self.ours[p] / self.paper[p] - 1.0 for p in self.columns}

    def ordered(self) -> bool:
        """ψ = 0 < 15 < 45 at every load (as in the paper)."""
        return bool(np.all(self.ours[0] < self.ours[15]) and np.all(self.ours[15] < self.ours[45]))

    def markdown(self) -> str:
        e, cols = self.errors(), self.columns
        lines = ["| load [N] | " + " | ".join(f"ψ={p}° paper | ψ={p}° ours | err" for p in cols) + " |",
                 "|---:|" + "---:|---:|---:|" * len(cols)]
        for i, f in enumerate(self.loads):
            cells = [f"{self.paper[p][i]:.3f} | {self.ours[p][i]:.3f} | {100 * e[p][i]:+.2f} %" for p in cols]
            lines.append(f"| {f:g} | " + " | ".join(cells) + " |")
        worst = max(np.nanmax(np.abs(v)) for v in e.values())
        n = sum(len(v) for v in e.values())
        within = [sum(int(np.sum(np.abs(v) <= tol)) for v in e.values()) for tol in (0.01, 0.02)]
        lines += ["", f"Largest deviation {100 * worst:.2f} %; {within[0]}/{n} entries within 1 %, "
                      f"{within[1]}/{n} within 2 %"
                      + (f"; ordering ψ = 0 < 15 < 45 at every load: {'yes' if self.ordered() else 'NO'}."
                         if len(cols) == len(TWISTS) else ".")]
        lines += ["", "Medial and lateral gastrocnemius (x-elongation of their last nodes, mm) at 400 N: "
                  + "; ".join(f"ψ={p}°: medial {self.others[p]['medial_gastrocnemius'][-1]:+.4f}, "
                              f"lateral {self.others[p]['lateral_gastrocnemius'][-1]:+.4f}" for p in cols)]
        return "\n".join(lines)


def table1(out: str, ranks: int = 1, jobs: int = 1, log=print, mode: str = "sliding") -> Table1:
    """Table 1: the three pretwist columns at the paper's 13 load levels, with contact ``mode``."""
    params = {"geometry.twist_deg": list(TWISTS)}
    name = "table1"
    if mode != "sliding":
        params["contact.mode"] = [mode] * len(TWISTS)
        name = f"table1_{mode}"
    sweep = make_sweep(out, name, params, ranks=ranks, jobs=jobs)
    return table1_from({p: summary_of(s) for p, s in zip(TWISTS, execute(sweep, log))})


def table1_from(summaries: dict[int, dict | None]) -> Table1:
    paper = read_paper(PAPER_T1)
    loads = paper["load_N"]
    ours, others = {}, {}
    for p in TWISTS:
        s = summaries.get(p)
        col = np.full(len(loads), np.nan)
        oth = {k: np.full(len(loads), np.nan) for k in ("medial_gastrocnemius", "lateral_gastrocnemius")}
        if s is not None:
            lf, el = elongations(s)
            for i, f in enumerate(loads):
                hit = np.flatnonzero(np.isclose(lf, f))
                if len(hit):
                    col[i] = el[hit[0]]
                    for k in oth:
                        oth[k][i] = elongations(s, k)[1][hit[0]]
        ours[p] = col
        others[p] = oth
    return Table1(loads, ours, {p: paper[f"psi{p}_mm"] for p in TWISTS}, others,
                  {p: s for p, s in summaries.items() if s is not None})


# ------------------------------------------------------------------------------ Table 2
#: the contact pressure spaces Table 2 is computed with (contact.projection): the default, linear
#: across the interface, which also holds the subtendons' relative section rotations and so keeps
#: one- and two-element models stable, and constant across it (the mean gap)
T2_VARIANTS = {"linear gap": None, "mean gap": {"axial": 2, "curve": 0}}
T2_ELEMENTS = (1, 2, 4, 8, 16)


def table2(out: str, elements=T2_ELEMENTS, variants: dict = T2_VARIANTS, ranks: int = 1,
           jobs: int = 1, log=print) -> dict:
    """Soleus elongation at 400 N for n x n x n elements, per gap space and pretwist.

    Rows are keyed (variant, ψ, n); each records whether the path stayed stable (the number
    of negative tangent eigenvalues at every converged level, ``inertia.py``)."""
    combos = [(v, p, n) for v in variants for p in TWISTS for n in elements]
    # the load path of Table 1 (a coarse model stepped straight to 50 N can land on another,
    # unstable branch: docs/contact.md)
    params = {"geometry.twist_deg": [p for _, p, _ in combos],
              "contact.projection": [variants[v] for v, _, _ in combos]}
    for b in range(BEAMS):
        params[f"beams[{b}].elements"] = [n for _, _, n in combos]
    sweep = make_sweep(out, "table2", params, ranks=ranks, jobs=jobs)
    states = execute(sweep, log)
    rows = {}
    for key, st in zip(combos, states):
        s = summary_of(st)
        lf, el = elongations(s) if s else (np.array([]), np.array([]))
        done = len(lf) and np.isclose(lf[-1], 400.0)
        neg = [(x["load_factor"], x.get("negative_eigenvalues")) for x in (s["steps"] if s else [])]
        unstable = [f for f, k in neg if k]
        rows[key] = {"elong": float(el[-1]) if done else np.nan,
                     "status": st.status, "reason": st.reason,
                     "reached": float(lf[-1]) if len(lf) else 0.0,
                     "unstable_from": min(unstable) if unstable else None,
                     "time": s["timings"]["total"] if s else np.nan,
                     "iterations": s.get("newton_iterations") if s else None,
                     "dofs": s.get("dofs") if s else None}
    return rows


def table2_markdown(rows: dict, elements=T2_ELEMENTS) -> str:
    """One table per gap space; ``u`` marks a result reached through unstable equilibria."""
    paper = read_paper(PAPER_T2)
    pn = {int(n): i for i, n in enumerate(paper["elements_per_subtendon"])}
    variants = list(dict.fromkeys(v for v, _, _ in rows))
    lines = []
    for v in variants:
        lines += ["", f"**{v}**" + (" (default)" if T2_VARIANTS.get(v, 0) is None else
                                    f" (contact.projection: {T2_VARIANTS.get(v)})"), "",
                  "| elements n×n×n | DOFs | " + " | ".join(f"ψ={p}° paper | ψ={p}° ours | err"
                                                          for p in TWISTS) + " |",
                  "|---:|---:|" + "---:|---:|---:|" * len(TWISTS)]
        for n in elements:
            cells = []
            for p in TWISTS:
                r = rows[(v, p, n)]
                pv = paper[f"psi{p}_mm"][pn[n]] if n in pn else np.nan
                mark = f" (u ≥ {r['unstable_from']:g} N)" if r["unstable_from"] is not None else ""
                if np.isfinite(r["elong"]):
                    ours = f"{r['elong']:.3f}{mark}"
                    err = f"{100 * (r['elong'] / pv - 1):+.2f} %" if np.isfinite(pv) else ""
                else:
                    ours, err = f"stopped after {r['reached']:g} N{mark}", ""
                cells.append(f"{pv:.3f} | {ours} | {err}" if np.isfinite(pv) else f"– | {ours} | ")
            dofs = next((rows[(v, p, n)]["dofs"] for p in TWISTS if rows[(v, p, n)]["dofs"]), "")
            lines.append(f"| {n} | {dofs} | " + " | ".join(cells) + " |")
    lines += ["", "(u ≥ F N): from that load on the converged states have a negative tangent "
                  "eigenvalue (a saddle of the total potential, not a stable equilibrium)."]
    for (v, p, n), r in rows.items():
        if r["status"] != "completed":
            lines.append(f"- {v}, ψ={p}°, {n} element(s): {r['status']}: {r['reason']}")
    return "\n".join(lines).strip("\n")


# ------------------------------------------------------------------------------ contact study
#: factors on k_s, the unit of the multipliers: two decades
SCALINGS = (0.1, 1.0, 10.0)
#: the former penalty formulation's gap space (per element, degree 2 along, mean across) and its
#: answers at ψ = 45° (docs/contact.md, "Before": p_n → ∞ limit of the penalty study at daf134a)
PER_ELEMENT_MEAN = {"axial": 2, "curve": 0, "per_element": True}
PENALTY_LIMIT_MM = {10: 0.16188, 400: 6.22170}
PENALTY_DEFAULT_MM = {10: 0.16200, 400: 6.22250}


def scaling_study(out: str, twist: int = 45, scalings=SCALINGS, ranks: int = 1, jobs: int = 1,
                  log=print) -> list[dict]:
    """Soleus elongation at 10 and 400 N for both contact laws with the multipliers' unit k_s
    scaled over two decades, and the former penalty space solved exactly (no penalty)."""
    rows = [("sliding", sc, None) for sc in scalings] + [("unilateral", sc, None) for sc in scalings]
    rows.append(("sliding", 1.0, PER_ELEMENT_MEAN))
    params = {"geometry.twist_deg": [twist] * len(rows), "contact.mode": [m for m, _, _ in rows],
              "contact.scaling": [sc for _, sc, _ in rows],
              "contact.projection": [pr for _, _, pr in rows]}
    states = execute(make_sweep(out, f"scaling_psi{twist}", params, ranks=ranks, jobs=jobs), log)
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


# ------------------------------------------------------------------------------ bulk modulus fit
def fit_bulk_modulus(out: str, candidates=(0.70e9, 0.80e9, 0.90e9, 1.0e9), jobs: int = 1, log=print):
    """Least-squares K on the relative errors of Table 1's ψ = 0 column (parabola through the
    sums of squares of the candidates)."""
    params = {"geometry.twist_deg": [0] * len(candidates)}
    for b in range(BEAMS):
        params[f"beams[{b}].material.bulk_modulus"] = list(candidates)
    sweep = make_sweep(out, "fit_bulk_modulus", params, jobs=jobs)
    states = execute(sweep, log)
    paper = read_paper(PAPER_T1)
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


# ------------------------------------------------------------------------------ timing
def timing_markdown(t1: Table1) -> str:
    keys = ("total", "setup", "element_kernels", "element_assembly", "contact_projection",
            "contact_assembly", "linear_solve", "output")
    lines = ["| ψ | Newton its | " + " | ".join(keys) + " |", "|---:|---:|" + "---:|" * len(keys)]
    for p in TWISTS:
        s = t1.summaries.get(p)
        if s:
            t = s["timings"]
            lines.append(f"| {p}° | {s['newton_iterations']} | "
                         + " | ".join(f"{t.get(k, float('nan')):.2f}" for k in keys) + " |")
    return "\n".join(lines)


# ------------------------------------------------------------------------------ figures
#: Figure 5's camera: from the soleus' side (+y), rolled by 180° so that x runs 0 -> L from
#: left to right (z then points down; a rotation, not a mirror image)
FIGURE5_VIEW = (-8.0, 70.0, 180.0)


#: load levels the slip figure shows [N]
SLIP_LEVELS = (10, 100, 200, 400)


def slip_figures(t1: Table1, out: str, twist: int = 45) -> list[str]:
    """Soleus–gastrocnemius slip and contact pressure along the tendon (viz.plot_slip)."""
    from .. import viz
    s = t1.summaries.get(twist)
    if not s or not s.get("contact_interfaces"):
        return []
    h5 = os.path.join(s.get("output_dir") or "", "results.h5")
    if not os.path.exists(h5):
        return []
    loads = [st["load_factor"] for st in s["steps"]]
    levels = [read_contact(h5, loads.index(f) + 1) for f in SLIP_LEVELS if f in loads]
    names = [n.split(" ")[0].replace("_", "–") for n in s["contact_interfaces"]]
    soleus = tuple(k for k, n in enumerate(s["contact_interfaces"]) if "soleus" in n)
    return [viz.plot_slip(levels, names, os.path.join(out, f"slip_psi{twist}.png"), soleus,
                               s.get("length", 0.07),
                               title=f"ψ = {twist}°: the soleus slides past the gastrocnemius subtendons")]


def figures(t1: Table1, out: str, t2rows: dict | None = None, log=print) -> list[str]:
    """Load-elongation vs the paper, Table 2 convergence, Figure 5 (ψ = 15°, 45°) renders."""
    from .. import viz
    made = []
    curves = {f"ψ = {p}°": (list(t1.loads[np.isfinite(t1.ours[p])]), list(t1.ours[p][np.isfinite(t1.ours[p])]))
              for p in TWISTS if p in t1.summaries}
    if curves:
        made.append(viz.plot_load_elongation(curves, PAPER_T1, os.path.join(out, "load_elongation.png"),
                                                  {f"ψ = {p}°": f"psi{p}_mm" for p in TWISTS},
                                                  title="Type III tendon: soleus elongation vs Table 1"))
    made += slip_figures(t1, out)
    if t2rows:
        paper = read_paper(PAPER_T2)
        ours = {}
        for v in dict.fromkeys(k[0] for k in t2rows):
            for p in TWISTS:
                ours[f"ψ = {p}°, {v}"] = [(n, r["elong"]) for (vv, pp, n), r in sorted(t2rows.items())
                                           if vv == v and pp == p and np.isfinite(r["elong"])]
        theirs = {f"ψ = {p}°": list(zip(paper["elements_per_subtendon"].astype(int), paper[f"psi{p}_mm"]))
                  for p in TWISTS}
        unstable = [(n, r["elong"]) for (_, _, n), r in t2rows.items()
                    if r["unstable_from"] is not None and np.isfinite(r["elong"])]
        made.append(viz.plot_convergence(ours, theirs, os.path.join(out, "convergence.png"),
                                              title="Soleus elongation at 400 N vs elements per subtendon",
                                              flagged=unstable))
    vtus = {}
    for p in (15, 45):
        s = t1.summaries.get(p)
        if s:
            run_dir = s.get("output_dir") or ""
            last = os.path.join(run_dir, f"surface_{len(s['steps']):04d}.vtu")
            if os.path.exists(last):
                vtus[p] = (last, os.path.join(run_dir, "surface_0000.vtu"))
    if len(vtus) == 2:
        made.append(viz.render_pair(vtus[15][0], vtus[45][0], os.path.join(out, "figure5.png"),
                                         titles=("(a) ψ = 15°, 400 N", "(b) ψ = 45°, 400 N"),
                                         view=FIGURE5_VIEW, reference_vtu=(vtus[15][1], vtus[45][1])))
    for p, (last, ref) in vtus.items():
        made.append(viz.render_surfaces(last, os.path.join(out, f"figure5_psi{p}.png"),
                                             title=f"ψ = {p}°, soleus at 400 N", view=FIGURE5_VIEW,
                                             reference_vtu=ref))
    for m in made:
        log(f"[report] wrote {m}")
    return made
