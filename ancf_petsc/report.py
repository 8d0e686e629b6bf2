"""The paper's Tables 1 and 2, the penalty study and the figures for the Type III Achilles tendon.

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

from . import sweep as sw

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
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


def table1(out: str, ranks: int = 1, jobs: int = 1, log=print) -> Table1:
    """Table 1: the three pretwist columns at the paper's 13 load levels."""
    sweep = make_sweep(out, "table1", {"geometry.twist_deg": list(TWISTS)}, ranks=ranks, jobs=jobs)
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


# ------------------------------------------------------------------------------ penalty study
PENALTY_SCALES = (1e-3, 1e-2, 1e-1, 10 ** -0.5, 1.0, 10 ** 0.5, 10.0, 100.0, 1e3, 1e4)


def penalty_study(out: str, twist: int = 45, scales=PENALTY_SCALES, ranks: int = 1, jobs: int = 1,
                  log=print) -> dict:
    """Soleus elongation at 10 and 400 N vs penalty (× the default p_n) for the projected gap,
    and the pointwise gap for comparison."""
    steps = [10, 50, 100, 200, 300, 400]
    n = len(scales)
    params = {"geometry.twist_deg": [twist] * (2 * n), "steps": [steps] * (2 * n),
              "contact.penalty_scale": list(scales) * 2,
              "contact.projection": [None] * n + ["pointwise"] * n}
    sweep = make_sweep(out, f"penalty_psi{twist}", params, ranks=ranks, jobs=jobs)
    states = execute(sweep, log)
    res = {"scales": list(scales), "projected": [], "pointwise": []}
    for i, st in enumerate(states):
        s = summary_of(st)
        row = {"status": st.status, "reason": st.reason, "iterations": None, "e10": np.nan,
               "e400": np.nan, "max_gap": np.nan, "mean_gap": np.nan,
               "penalty": _penalty_from_log(st.run.dir)}
        if s and s["steps"]:
            lf, el = elongations(s)
            row["iterations"] = s.get("newton_iterations")
            row["e10"] = float(el[0]) if np.isclose(lf[0], 10) else np.nan
            row["e400"] = float(el[-1]) if np.isclose(lf[-1], 400) else np.nan
            gaps = s["steps"][-1].get("contact", {})
            row["max_gap"] = max((g["max_gap"] for g in gaps.values()), default=np.nan)
            row["mean_gap"] = max((g.get("max_projected_gap", np.nan) for g in gaps.values()), default=np.nan)
        (res["projected"] if i < n else res["pointwise"]).append(row)
    return res


def _penalty_from_log(run_dir: str) -> float:
    try:
        with open(os.path.join(run_dir, "log.txt")) as fh:
            for ln in fh:
                if "penalty p_n =" in ln:
                    return float(ln.split("penalty p_n =")[1].split()[0])
    except OSError:
        pass
    return np.nan


def penalty_markdown(res: dict, twist: int) -> str:
    ref_i = res["scales"].index(100.0)
    ref = res["projected"][ref_i]["e400"]
    lines = [f"ψ = {twist}°; scale = p_n / default (p_n = 1000 E/h); reference: scale 100.", "",
             "| scale | p_n [Pa/m] | 10 N [mm] | 400 N [mm] | vs ref. | max mean gap [µm] | max local gap [µm] "
             "| Newton its | pointwise gap: 400 N [mm] | Newton its |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for sc, a, b in zip(res["scales"], res["projected"], res["pointwise"]):
        if a["status"] == "completed":
            fa = (f"{a['e10']:.5f} | {a['e400']:.5f} | {100 * (a['e400'] / ref - 1):+.3f} % | "
                  f"{1e6 * a['mean_gap']:.3f} | {1e6 * a['max_gap']:.1f} | {a['iterations']}")
        else:
            fa = f"{a['status']}: {a['reason'][:60]} | | | | | {a['iterations'] or ''}"
        fb = (f"{b['e400']:.5f} | {b['iterations']}" if b["status"] == "completed"
              else f"{b['status']} | {b['iterations'] or ''}")
        lines.append(f"| {sc:.3g} | {a['penalty']:.3g} | {fa} | {fb} |")
    return "\n".join(lines)


def penalty_plateau(res: dict) -> tuple[float, float]:
    """Largest relative change of the 10 N and 400 N elongations over the decade around the
    default (scales 10^-1/2 .. 10^1/2)."""
    sc = np.array(res["scales"])
    sel = (sc >= 10 ** -0.5 * 0.999) & (sc <= 10 ** 0.5 * 1.001)
    out = []
    for key in ("e10", "e400"):
        v = np.array([r[key] for r in res["projected"]])[sel]
        out.append(float((v.max() - v.min()) / v.mean()))
    return out[0], out[1]


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
    sse = []
    for st in states:
        lf, el = elongations(summary_of(st))
        sse.append(float(np.sum((el / paper["psi0_mm"] - 1.0) ** 2)))
    c = np.polyfit(np.array(candidates), np.array(sse), 2)
    return float(-c[1] / (2 * c[0])), dict(zip(candidates, sse))


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


def figures(t1: Table1, out: str, t2rows: dict | None = None, log=print) -> list[str]:
    """Load-elongation vs the paper, Table 2 convergence, Figure 5 (ψ = 15°, 45°) renders."""
    from . import plotting
    made = []
    curves = {f"ψ = {p}°": (list(t1.loads[np.isfinite(t1.ours[p])]), list(t1.ours[p][np.isfinite(t1.ours[p])]))
              for p in TWISTS if p in t1.summaries}
    if curves:
        made.append(plotting.plot_load_elongation(curves, PAPER_T1, os.path.join(out, "load_elongation.png"),
                                                  {f"ψ = {p}°": f"psi{p}_mm" for p in TWISTS},
                                                  title="Type III tendon: soleus elongation vs Table 1"))
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
        made.append(plotting.plot_convergence(ours, theirs, os.path.join(out, "convergence.png"),
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
        made.append(plotting.render_pair(vtus[15][0], vtus[45][0], os.path.join(out, "figure5.png"),
                                         titles=("(a) ψ = 15°, 400 N", "(b) ψ = 45°, 400 N"),
                                         view=FIGURE5_VIEW, reference_vtu=(vtus[15][1], vtus[45][1])))
    for p, (last, ref) in vtus.items():
        made.append(plotting.render_surfaces(last, os.path.join(out, f"figure5_psi{p}.png"),
                                             title=f"ψ = {p}°, soleus at 400 N", view=FIGURE5_VIEW,
                                             reference_vtu=ref))
    for m in made:
        log(f"[report] wrote {m}")
    return made
