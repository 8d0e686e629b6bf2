"""The Achilles psi = 45 deg column with GOH against neo-Hookean (issue 26): cut-backs, Newton
iterations and wall time at 4 and 8 elements, sliding and unilateral contact, 1 rank.
Usage: OPENBLAS_NUM_THREADS=1 python scripts/bench_goh_achilles.py [--elements 4 8] [--out DIR]"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import yaml

from ancf_verify import paths

ROOT = paths.ROOT
CONFIGS = {"neo-hookean": "achilles_type3_psi45.yaml", "goh": "achilles_type3_psi45_goh.yaml",
           "goh-published-matrix": "achilles_type3_psi45_goh.yaml"}


def run(law: str, elements: int, mode: str, out: str) -> dict:
    with open(os.path.join(ROOT, "configs", CONFIGS[law])) as fh:
        raw = yaml.safe_load(fh)
    for b in raw["beams"]:
        b["elements"] = elements
        if law == "goh-published-matrix":    # Tendon-model's matrix: c10 = 30.6 kPa, 1e8 (J - 1)^2
            b["material"].update(mu=61.2e3, bulk_modulus=2.0e8)
        b["section"]["file"] = os.path.join(ROOT, "configs", b["section"]["file"])
    raw["contact"]["mode"] = mode
    tag = f"{law}_{elements}_{mode}"
    raw["output"] = {"dir": os.path.join(out, tag), "vtk": False}
    path = os.path.join(out, tag + ".yaml")
    with open(path, "w") as fh:
        yaml.safe_dump(raw, fh, sort_keys=False)
    exe = os.path.join(ROOT, ".venv", "bin", "ancf-solve")
    t = time.perf_counter()
    p = subprocess.run([exe, path], capture_output=True, text=True)
    wall = time.perf_counter() - t
    text = p.stdout + p.stderr
    with open(os.path.join(out, tag + ".log"), "w") as fh:
        fh.write(text)
    s = paths.run_summary(os.path.join(out, tag), p, "bench_goh_achilles")
    last = s["steps"][-1]["probes"]["soleus"]["displacement"][0] if s["steps"] else float("nan")
    return {"law": law, "elements": elements, "mode": mode, "status": s["status"], "exit": p.returncode,
            "cutbacks": sum(st.get("cutbacks", 0) for st in s["steps"]),
            "newton": sum(st.get("iterations", 0) for st in s["steps"]),
            "wall_s": wall, "soleus_mm_at_400N": 1e3 * last}


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--elements", type=int, nargs="+", default=[4, 8])
    ap.add_argument("--modes", nargs="+", default=["sliding", "unilateral"], choices=["sliding", "unilateral"])
    ap.add_argument("--laws", nargs="+", default=["neo-hookean", "goh"], choices=list(CONFIGS))
    ap.add_argument("--out", default="/tmp/ancf-bench-goh")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for n in args.elements:
        for mode in args.modes:
            for law in args.laws:
                r = run(law, n, mode, args.out)
                rows.append(r)
                print(json.dumps(r), flush=True)
    print("\n| elements | contact | law | status | cut-backs | Newton | wall [s] | soleus [mm] at 400 N | GOH/NH wall |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        nh = next((x for x in rows if x["elements"] == r["elements"] and x["mode"] == r["mode"]
                  and x["law"] == "neo-hookean"), r)
        ratio = f"{r['wall_s'] / nh['wall_s']:.2f}" if r["law"] != "neo-hookean" else ""
        print(f"| {r['elements']} | {r['mode']} | {r['law']} | {r['status']} | {r['cutbacks']} | "
              f"{r['newton']} | {r['wall_s']:.1f} | {r['soleus_mm_at_400N']:.3f} | {ratio} |")
