"""Between sliding and bonded (issue 27): the paper's tendon (psi = 45 deg, Table 1's levels) with
every interface law — frictionless sliding, the elastic interfascicular matrix over several
stiffnesses k_t, Coulomb friction over several coefficients mu (on the sliding and on the
unilateral normal law), and the bonded tendon (k_t -> infinity) — loaded by the soleus alone and
by all three muscles equally.  Per run: status, Newton iterations, cut-backs, wall time, the
soleus elongation and the displacement of each gastrocnemius against the soleus (summary.json
``displacement_differences``) at every level.

    OPENBLAS_NUM_THREADS=1 python scripts/interface_study.py [--elements 4 8] [--jobs 2]
        [--out DIR] [--csv docs/interface_study.csv] [--figure docs/figures/nonuniformity.png]
        [--timeout SECONDS] [--reuse] [--laws LAW ...] [--loadings soleus equal]
        [--supported-ends keep|merge]

Every run is one ancf-solve process (1 rank), as a user runs it.  The CSV has one row per run and
level (the differences u_first − u_second in config order, ``end_<first>|<second>_mm``); the
figure draws soleus − medial gastrocnemius at the far end against the load for each law (the
fewest elements asked for), one colour and marker per law.  ``--reuse`` reads finished runs."""
from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import yaml

from ancf_verify import paths

ROOT = paths.ROOT
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
LOADINGS = {"soleus": "achilles_type3_psi45.yaml", "equal": "achilles_psi45_equal_muscles.yaml"}
#: (label, contact mode, tangential law or None)
LAWS = [("sliding", "sliding", None)]
LAWS += [(f"elastic k_t={k:.0e}", "sliding", {"law": "elastic", "stiffness": k}) for k in (1e8, 1e9, 1e10, 1e11)]
LAWS += [("bonded (k_t=1e14)", "sliding", {"law": "elastic", "stiffness": 1e14})]
LAWS += [(f"coulomb mu={mu:g}", "sliding", {"law": "coulomb", "friction": mu}) for mu in (0.003, 0.03, 0.3, 3.0)]
LAWS += [("unilateral", "unilateral", None)]
LAWS += [(f"unilateral, coulomb mu={mu:g}", "unilateral", {"law": "coulomb", "friction": mu})
         for mu in (0.003, 0.03, 0.3, 3.0)]


#: the pair the figure and the table read: u_soleus − u_medial (first − second in config order)
PAIR = "soleus|medial_gastrocnemius"


def config(loading: str, mode: str, tangential, elements: int, out: str, ends: str | None = None) -> dict:
    with open(os.path.join(ROOT, "configs", LOADINGS[loading])) as fh:
        raw = yaml.safe_load(fh)
    for b in raw["beams"]:
        b["elements"] = elements
        b["section"]["file"] = os.path.join(ROOT, "configs", b["section"]["file"])
    raw["contact"] = {"mode": mode}
    if tangential is not None:
        raw["contact"]["tangential"] = dict(tangential)
        if ends is not None and tangential["law"] == "coulomb":    # friction's held roots folded or kept
            raw["contact"]["tangential"]["supported_ends"] = ends
    raw["output"] = {"dir": out, "vtk": False}
    return raw


def run(case: tuple, out: str, reuse: bool = False, timeout: float | None = None,
        ends: str | None = None) -> dict:
    loading, (label, mode, tangential), elements = case
    tag = f"{loading}_{elements}_{label}".replace(" ", "_").replace("=", "").replace(",", "").replace("(", "").replace(")", "")
    directory = os.path.join(out, tag)
    path = directory + ".yaml"
    if reuse and os.path.exists(os.path.join(directory, "summary.json")):
        with open(os.path.join(directory, "summary.json")) as fh:
            s = json.load(fh)
        return {"loading": loading, "law": label, "elements": elements,
                "status": "stopped" if s["status"] == "running" else s["status"],
                "message": s.get("message", ""), "wall_s": s.get("timings", {}).get("total", float("nan")),
                "steps": s["steps"]}
    with open(path, "w") as fh:
        yaml.safe_dump(config(loading, mode, tangential, elements, directory, ends), fh, sort_keys=False)
    t = time.perf_counter()
    try:
        p = subprocess.run([os.path.join(ROOT, ".venv", "bin", "ancf-solve"), path, "--quiet"],
                           capture_output=True, text=True, env=ENV, timeout=timeout)
        stderr = p.stderr
    except subprocess.TimeoutExpired:
        stderr = f"stopped after {timeout:g} s"
    wall = time.perf_counter() - t
    try:
        with open(os.path.join(directory, "summary.json")) as fh:
            s = json.load(fh)
    except (OSError, ValueError):
        s = {"status": "no summary", "steps": [], "message": stderr.strip()[-300:]}
    if s["status"] == "running":               # stopped by the timeout: the levels it reached
        s = dict(s, status="stopped", message=stderr.strip()[-300:])
    return {"loading": loading, "law": label, "elements": elements, "status": s["status"],
            "message": s.get("message", ""), "wall_s": wall, "steps": s["steps"]}


def rows_of(r: dict) -> list[dict]:
    out = []
    for st in r["steps"]:
        dd = st.get("displacement_differences", {})
        row = {"loading": r["loading"], "law": r["law"], "elements": r["elements"], "status": r["status"],
               "load_N": st["load_factor"], "newton": st["iterations"], "cutbacks": st["cutbacks"],
               "tresca_solves": st.get("tresca_solves", 0), "wall_s": st.get("wall_time", float("nan")),
               "soleus_mm": 1e3 * st["probes"]["soleus"]["displacement"][0]}
        for pair, d in dd.items():
            row[f"end_{pair}_mm"] = 1e3 * d["end"]
        out.append(row)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--elements", type=int, nargs="+", default=[4, 8])
    ap.add_argument("--loadings", nargs="+", default=list(LOADINGS), choices=list(LOADINGS))
    ap.add_argument("--laws", nargs="+", default=[law[0] for law in LAWS], choices=[law[0] for law in LAWS],
                    metavar="LAW", help="the laws to run (labels: " + "; ".join(law[0] for law in LAWS) + ")")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default="/tmp/ancf-interface-study")
    ap.add_argument("--csv", default=None)
    ap.add_argument("--figure", default=None)
    ap.add_argument("--timeout", type=float, default=None, help="stop a run after this many seconds (reported as stopped)")
    ap.add_argument("--reuse", action="store_true", help="read the runs already in --out (their summary.json) instead of solving again")
    ap.add_argument("--supported-ends", choices=("keep", "merge"), default=None,
                    help="contact.tangential.supported_ends of the friction rows (default: the config's default)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    cases = [(lo, law, n) for n in args.elements for lo in args.loadings for law in LAWS if law[0] in args.laws]
    with ThreadPoolExecutor(args.jobs) as pool:
        results = list(pool.map(lambda c: run(c, args.out, args.reuse, args.timeout, args.supported_ends), cases))
    print("| loading | law | elements | status | Newton | cut-backs | Tresca solves | wall [s] | soleus at 400 N [mm] | soleus - MG at the end [mm] |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        rows = rows_of(r)
        last = rows[-1] if rows else {}
        mg = last.get(f"end_{PAIR}_mm", float("nan"))
        print(f"| {r['loading']} | {r['law']} | {r['elements']} | {r['status']} | "
              f"{sum(x['newton'] for x in rows)} | {sum(x['cutbacks'] for x in rows)} | "
              f"{sum(x['tresca_solves'] for x in rows)} | {r['wall_s']:.1f} | "
              f"{last.get('soleus_mm', float('nan')):.4f} | {mg:.4f} |"
              + ("" if r["status"] == "completed" else f" {r['message'][:80]}"))
    if args.csv:
        rows = [row for r in results for row in rows_of(r)]
        keys = sorted({k for row in rows for k in row}, key=lambda k: list(rows[0]).index(k) if k in rows[0] else 99)
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=keys)
            w.writeheader()
            w.writerows(rows)
    if args.figure:
        from ancf_petsc.viz import plot_law_differences
        plot_law_differences(results, [law[0] for law in LAWS], list(LOADINGS), PAIR, min(args.elements), args.figure)
    return 0
