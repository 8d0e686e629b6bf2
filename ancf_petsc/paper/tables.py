"""The paper's Tables 1 and 2 beside ours, with relative errors (``configs/data/paper_table*.csv``)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..config.specs import DEFAULT_CONTACT_MODE
from ..io.levels import gap_note, not_asked, reported_at, step_at
from .inputs import BEAMS, TWISTS, PaperInputs, read_paper
from ..workflows.sweep.collect import run_iterations
from .runs import elongation, execute, make_sweep, summary_of


@dataclass
class Table1:
    loads: np.ndarray
    ours: dict[int, np.ndarray]            # psi -> soleus elongation [mm] (nan where missing)
    paper: dict[int, np.ndarray]
    others: dict[int, dict[str, np.ndarray]]   # psi -> medial/lateral elongation [mm]
    summaries: dict[int, dict]
    #: psi -> the load factor a level passed over in a gap of the load path was reported at
    #: (nan where the level was solved at itself or not reached; io/levels.py)
    reported: dict[int, np.ndarray] = field(default_factory=dict)

    def passed(self, p: int, i: int) -> float | None:
        """The load factor the i-th level of column ψ = p was reported at, past a gap (else None)."""
        at = self.reported.get(p, np.full(len(self.loads), np.nan))[i]
        return float(at) if np.isfinite(at) else None

    def curve(self, p: int) -> tuple[list[float], list[float]]:
        """(load [N], elongation [mm]) of column ψ = p at the levels reached, each at the load it
        was reported at (past a gap of the load path: its reported load factor)."""
        hit = np.isfinite(self.ours[p])
        at = np.where(np.isfinite(self.reported.get(p, np.nan)), self.reported.get(p, np.nan), self.loads)
        return list(at[hit]), list(self.ours[p][hit])

    def mark(self, p: int, i: int) -> str:
        """'†' after a value reported past a gap of the load path (``gap_notes``), else ''."""
        return "†" if self.passed(p, i) is not None else ""

    def gap_notes(self, law: str = "") -> list[str]:
        """One footnote per level reported past a gap of the load path (empty when none)."""
        return [f"† {law}ψ={p}°, {f:g} N: {gap_note(self.passed(p, i))} (solver.step_over_jumps; the error "
                "is against the paper's value at the level asked)"
                for p in self.columns for i, f in enumerate(self.loads) if self.passed(p, i) is not None]

    def missing(self, p: int, i: int) -> str:
        """Why column ψ = p has no value at the i-th level: 'not asked' (not among the run's
        steps) or 'not reached' (the run stopped before it)."""
        return "not asked" if not_asked(self.summaries[p], float(self.loads[i])) else "not reached"

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
            cells = [f"{self.paper[p][i]:.3f} | {self.ours[p][i]:.3f}{self.mark(p, i)} | {100 * e[p][i]:+.2f} %"
                     if np.isfinite(self.ours[p][i]) else f"{self.paper[p][i]:.3f} | {self.missing(p, i)} | "
                     for p in cols]
            lines.append(f"| {f:g} | " + " | ".join(cells) + " |")
        lines += ["", *self.gap_notes()] if self.gap_notes() else []
        reached = [v[np.isfinite(v)] for v in e.values()]
        if not any(len(v) for v in reached):
            return "\n".join(lines + ["", "No level of Table 1 was reached."])
        worst = max(np.max(np.abs(v)) for v in reached if len(v))
        n = sum(len(v) for v in reached)
        within = [sum(int(np.sum(np.abs(v) <= tol)) for v in e.values()) for tol in (0.01, 0.02)]
        total = sum(len(v) for v in e.values())
        complete = n == total
        lines += ["", f"Largest deviation {100 * worst:.2f} % over the {n} of {total} entries reached; "
                      f"{within[0]}/{n} within 1 %, {within[1]}/{n} within 2 %"
                      + (f"; ordering ψ = 0 < 15 < 45 at every load: {'yes' if self.ordered() else 'NO'}."
                         if len(cols) == len(TWISTS) and complete else ".")]
        if complete:
            lines += ["", "Medial and lateral gastrocnemius (x-elongation of their last nodes, mm) at 400 N: "
                      + "; ".join(f"ψ={p}°: medial {self.others[p]['medial_gastrocnemius'][-1]:+.4f}, "
                                  f"lateral {self.others[p]['lateral_gastrocnemius'][-1]:+.4f}" for p in cols)]
        return "\n".join(lines)


def table1(inputs: PaperInputs, out: str, ranks: int = 1, jobs: int = 1, log=print,
           mode: str = "sliding") -> Table1:
    """Table 1: the three pretwist columns at the paper's 13 load levels, with contact ``mode``."""
    params = {"geometry.twist_deg": list(TWISTS)}
    name = "table1"
    if mode != DEFAULT_CONTACT_MODE:
        params["contact.mode"] = [mode] * len(TWISTS)
        name = f"table1_{mode}"
    sweep = make_sweep(inputs, out, name, params, ranks=ranks, jobs=jobs)
    return table1_from(inputs, {p: summary_of(s) for p, s in zip(TWISTS, execute(sweep, log))})


def table1_from(inputs: PaperInputs, summaries: dict[int, dict | None]) -> Table1:
    """Table 1 from the summaries of the three columns (ψ → summary.json, None if missing)."""
    paper = read_paper(inputs.table1_csv)
    loads = paper["load_N"]
    ours, others, reported = {}, {}, {}
    for p in TWISTS:
        s = summaries.get(p)
        col, at = np.full(len(loads), np.nan), np.full(len(loads), np.nan)
        oth = {k: np.full(len(loads), np.nan) for k in ("medial_gastrocnemius", "lateral_gastrocnemius")}
        for i, f in enumerate(loads):
            step = step_at(s["steps"], float(f)) if s is not None else None
            if step is not None:           # a level passed over: reached at its reported load
                col[i] = elongation(step)
                at[i] = reported_at(step) or np.nan
                for k in oth:
                    oth[k][i] = elongation(step, k)
        ours[p], others[p], reported[p] = col, oth, at
    return Table1(loads, ours, {p: paper[f"psi{p}_mm"] for p in TWISTS}, others,
                  {p: s for p, s in summaries.items() if s is not None}, reported)


#: the contact pressure spaces Table 2 is computed with (contact.projection): the default, linear
#: across the interface, which also holds the subtendons' relative section rotations and so keeps
#: one- and two-element models stable, and constant across it (the mean gap)
T2_VARIANTS = {"linear gap": None, "mean gap": {"axial": 2, "curve": 0}}
T2_ELEMENTS = (1, 2, 4, 8, 16)
#: the load of Table 2 [N]
T2_LOAD = 400.0


def table2(inputs: PaperInputs, out: str, elements=T2_ELEMENTS, variants: dict = T2_VARIANTS,
           ranks: int = 1, jobs: int = 1, log=print) -> dict:
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
    sweep = make_sweep(inputs, out, "table2", params, ranks=ranks, jobs=jobs)
    states = execute(sweep, log)
    return {key: table2_row(summary_of(st), st.status, st.reason) for key, st in zip(combos, states)}


def table2_row(s: dict | None, status: str, reason: str, load: float = T2_LOAD) -> dict:
    """One run's entry of Table 2 (``s`` its summary.json, None if missing): the elongation at
    ``load`` (also where a gap of the load path had it reported just past: ``reported_at``)."""
    steps = s["steps"] if s else []
    top = step_at(steps, load)
    unstable = [x["load_factor"] for x in steps if x.get("negative_eigenvalues")]
    return {"elong": elongation(top) if top else np.nan, "reported_at": reported_at(top),
            "status": status, "reason": reason,
            "reached": float(steps[-1]["load_factor"]) if steps else 0.0,
            "unstable_from": min(unstable) if unstable else None,
            "time": (s.get("timings") or {}).get("total", np.nan) if s else np.nan,   # none: killed
            "iterations": run_iterations(s) if s else None,
            "dofs": s.get("dofs") if s else None}


def table2_markdown(inputs: PaperInputs, rows: dict, elements=T2_ELEMENTS) -> str:
    """One table per gap space; ``u`` marks a result reached through unstable equilibria."""
    paper = read_paper(inputs.table2_csv)
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
                    ours = f"{r['elong']:.3f}{'†' if r.get('reported_at') else ''}{mark}"
                    err = f"{100 * (r['elong'] / pv - 1):+.2f} %" if np.isfinite(pv) else ""
                else:
                    ours, err = f"stopped after {r['reached']:g} N{mark}", ""
                cells.append(f"{pv:.3f} | {ours} | {err}" if np.isfinite(pv) else f"– | {ours} | ")
            dofs = next((rows[(v, p, n)]["dofs"] for p in TWISTS if rows[(v, p, n)]["dofs"]), "")
            lines.append(f"| {n} | {dofs} | " + " | ".join(cells) + " |")
    lines += ["", "(u ≥ F N): from that load on the converged states have a negative tangent "
                  "eigenvalue (a saddle of the total potential, not a stable equilibrium)."]
    lines += [f"† {v}, ψ={p}°, {n} element(s), {T2_LOAD:g} N: {gap_note(r['reported_at'])} (solver.step_over_jumps)"
              for (v, p, n), r in rows.items() if r.get("reported_at")]
    for (v, p, n), r in rows.items():
        if r["status"] != "completed":
            lines.append(f"- {v}, ψ={p}°, {n} element(s): {r['status']}: {r['reason']}")
    return "\n".join(lines).strip("\n")


def timing_markdown(t1: Table1) -> str:
    """Run time per Table 1 column, by part (summary.json ``timings``); a column continued with
    --restart (a report stopped and run again) counts the whole run's Newton iterations, and
    its times, the last process's, are marked."""
    keys = ("total", "setup", "element_kernels", "element_assembly", "contact_projection",
            "contact_assembly", "linear_solve", "output")
    lines = ["| ψ | levels | Newton its | " + " | ".join(keys) + " |",
             "|---:|---:|---:|" + "---:|" * len(keys)]
    notes = []
    for p in TWISTS:
        s = t1.summaries.get(p)
        if s:
            t = s.get("timings") or {}
            mark = "‡" if s.get("restarted_from") else ""
            lines.append(f"| {p}° | {len(s['steps'])} | {run_iterations(s)} | "
                         + " | ".join(f"{t.get(k, float('nan')):.2f}{mark}" for k in keys) + " |")
            if mark:
                notes.append(f"‡ ψ={p}°: continued from level {s['restarted_from'].get('step')} "
                             "(--restart): the times are the last process's, the levels before it not included")
    return "\n".join(lines + ([""] + notes if notes else []))
