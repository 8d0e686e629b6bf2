"""The reproduction's figures: load-elongation against Table 1, convergence against Table 2, the
soleus slip along the tendon and Figure 5's renders."""
from __future__ import annotations

import os

import numpy as np

from .. import viz
from ..io.files import atomic_write, remove_quietly
from ..io.levels import ended_words, step_at
from ..io.reader import read_contact
from .inputs import TWISTS, PaperInputs, read_paper
from .tables import Table1

#: Figure 5's camera: from the soleus' side (+y), rolled by 180° so that x runs 0 -> L from
#: left to right (z then points down; a rotation, not a mirror image)
FIGURE5_VIEW = (-8.0, 70.0, 180.0)


#: the figures the last report drew into its --out, one file name a line (``keep_only``)
FIGURE_LIST = ".ancf-report-figures"


def keep_only(out: str, made: list[str], others: bool = False) -> None:
    """Remove from ``out`` the figures an earlier report listed there and this one did not draw
    again (left beside this report's report.md they read as its own: the paper's Table 1 figure
    beside another model's report), then list this report's.  ``others``: keep and list them too
    (a report of the paper's sweeps, whose runs, reused, drew them: ``ancf-report --contact``
    after ``ancf-report``)."""
    path = os.path.join(out, FIGURE_LIST)
    names = {os.path.basename(f) for f in made}
    try:
        with open(path) as fh:
            earlier = {line.strip() for line in fh if line.strip() and os.sep not in line.strip()}
    except OSError:                       # the first report here (or one before this list)
        earlier = set()
    if others:
        names |= {n for n in earlier if os.path.exists(os.path.join(out, n))}
    else:
        remove_quietly(*[os.path.join(out, n) for n in sorted(earlier - names)])
    atomic_write(path, "".join(f"{n}\n" for n in sorted(names)))


#: load levels the slip figure shows [N]
SLIP_LEVELS = (10, 100, 200, 400)


def slip_figures(t1: Table1, out: str, twist: int = 45) -> list[str]:
    """Soleus–gastrocnemius slip and contact pressure along the tendon (viz.plot_slip)."""
    s = t1.summaries.get(twist)
    if not s or not s.get("contact_interfaces"):
        return []
    h5 = os.path.join(s.get("output_dir") or "", "results.h5")
    if not os.path.exists(h5):
        return []
    at = [step_at(s["steps"], f) for f in SLIP_LEVELS]            # a level passed over: where reported
    levels = [read_contact(h5, s["steps"].index(st) + 1) for st in at if st is not None]
    if not levels:                       # none of SLIP_LEVELS reached: an empty chart says nothing
        return []
    names = viz.interface_labels(s["contact_interfaces"])
    soleus = tuple(k for k, n in enumerate(s["contact_interfaces"]) if "soleus" in n)
    return [viz.plot_slip(levels, names, os.path.join(out, f"slip_psi{twist}.png"), soleus,
                               s.get("length", 0.07),
                               title=f"ψ = {twist}°: the soleus slides past the gastrocnemius subtendons")]


def figures(inputs: PaperInputs, t1: Table1, out: str, t2rows: dict | None = None, log=print) -> list[str]:
    """Load-elongation vs the paper, Table 2 convergence, Figure 5 (ψ = 15°, 45°) renders."""
    made = []
    curves = {f"ψ = {p}°": t1.curve(p) for p in TWISTS if p in t1.summaries}
    if curves:
        made.append(viz.plot_load_elongation(curves, inputs.table1_csv, os.path.join(out, "load_elongation.png"),
                                                  {f"ψ = {p}°": f"psi{p}_mm" for p in TWISTS},
                                                  title="Type III tendon: soleus elongation vs Table 1"))
    made += slip_figures(t1, out)
    if t2rows:
        paper = read_paper(inputs.table2_csv)
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
    vtus, drawn = {}, {}
    for p in (15, 45):
        s = t1.summaries.get(p)
        if s and s.get("steps"):
            run_dir = s.get("output_dir") or ""
            last = os.path.join(run_dir, f"surface_{len(s['steps']):04d}.vtu")
            if os.path.exists(last):
                vtus[p] = (last, os.path.join(run_dir, "surface_0000.vtu"))
                f = s["steps"][-1]["load_factor"]   # the level drawn: the last one the run reached
                drawn[p] = f"{f:g} N" + ("" if s.get("status") == "completed" else
                                         f" (the last level reached; {ended_words(s)})")
    if len(vtus) == 2:
        made.append(viz.render_pair(vtus[15][0], vtus[45][0], os.path.join(out, "figure5.png"),
                                         titles=(f"(a) ψ = 15°, {drawn[15]}", f"(b) ψ = 45°, {drawn[45]}"),
                                         view=FIGURE5_VIEW, reference_vtu=(vtus[15][1], vtus[45][1])))
    for p, (last, ref) in vtus.items():
        made.append(viz.render_surfaces(last, os.path.join(out, f"figure5_psi{p}.png"),
                                             title=f"ψ = {p}°, soleus at {drawn[p]}", view=FIGURE5_VIEW,
                                             reference_vtu=ref))
    for m in made:
        log(f"[report] wrote {m}")
    return made
