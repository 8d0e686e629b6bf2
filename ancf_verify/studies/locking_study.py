"""``locking: mixed`` measured (issue 26): the numbers of docs/locking.md.

Parts (all by default; each prints a markdown table):

* ``space``: which pressure space.  The bar of scripts/verify_solid_fibres.py (three laws, K/μ = 50,
  16 elements) and the tension/bending bars of scripts/verify_solid.py (8 elements) with the
  dilatation projected per axial station onto {1} (F-bar of the mean), {1, y, z} (``mixed``),
  {1, y, z, y² + z²} and the complete quadratics, against the committed solid references
  (docs/solid_fibres.csv, docs/solid_comparison.csv).  The variants other than {1, y, z} are a
  diagnosis here (``BeamSpec.pressure_columns``, set in code), not config keys.
* ``solids``: the four bars of docs/solid_comparison.md, 2-16 elements, without and with ``mixed``.
* ``pretwisted``: configs/pretwisted_bar.yaml's refinement (docs/verification.md) with ``mixed``.
* ``paper``: Table 1's columns (4 elements, the paper's 3 axial points, sliding contact) and Table
  2's ψ = 45° column (1-16 elements; 3 and 2 axial points), without and with ``mixed``.
* ``point``: the lone soleus under the paper's point force on r against a uniform traction.
* ``published``: the lone soleus with tendon_model_2023's GOH set and its penalty K = 3268 μ
  (scripts/goh_published_sets.py), which did not get past 8.4 N without a remedy.

Usage: OPENBLAS_NUM_THREADS=1 python scripts/locking_study.py [space solids pretwisted paper point published]
"""
from __future__ import annotations

import copy
import csv
import os
import sys
import tempfile
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import yaml  # noqa: E402

from ancf_verify import paths  # noqa: E402
from ancf_verify.bars.cases import CASES, Case, ancf_config  # noqa: E402
from ancf_verify.fibres.beams import run_ancf  # noqa: E402
from ancf_verify.fibres.cases import ANCF, ANCF_MIXED, LAWS, case_key, make_case  # noqa: E402
from ancf_verify.fibres.report import read_csv, runs_of  # noqa: E402
from ancf_verify.stack import SolidError  # noqa: E402

ROOT = paths.ROOT
CONFIGS = os.path.join(ROOT, "configs")
#: pressure spaces per station, as columns of the complete quadratic basis (1, y, z, y², yz, z²)
SPACES = {"{1}": [[0]], "{1, y, z} (mixed)": [[0], [1], [2]], "{1, y, z, y²+z²}": [[0], [1], [2], [3, 5]],
          "quadratic": [[0], [1], [2], [3], [4], [5]]}


def columns_of(name: str | None) -> tuple | None:
    """``BeamSpec.pressure_columns`` of the space ``name`` of SPACES (None: {1, y, z}, mixed's own)."""
    return None if name is None or SPACES[name] == SPACES["{1, y, z} (mixed)"] else tuple(map(tuple, SPACES[name]))


def solve(raw: dict, columns: tuple | None = None) -> dict:
    """``raw`` solved in-process; ``columns``: every beam's ``BeamSpec.pressure_columns``."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    t0 = time.perf_counter()
    spec = parse_config(copy.deepcopy(raw), base_dir=CONFIGS)
    for b in spec.beams:
        b.pressure_columns = columns
    res = run_model(spec, log=lambda *_: None)
    s = res.summary
    s["wall"] = time.perf_counter() - t0
    return s


def _ok(s: dict) -> bool:
    return s["status"] == "completed"


def _stopped(s: dict) -> str:
    return f"stops at {s['steps'][-1]['load_factor']:g}" if s["steps"] else "stops at the first level"


def solid_refs() -> dict:
    with open(os.path.join(ROOT, "docs", "solid_comparison.csv"), newline="") as fh:
        return {r["case"]: np.array([float(r[f"ref_u{c}_m"]) for c in "xyz"]) for r in csv.DictReader(fh)}


def bar(case: Case, elements: int, locking: str, tmp: str, columns: tuple | None = None) -> dict:
    raw = ancf_config(case, elements, 2, os.path.join(tmp, f"{case.key}_{elements}_{locking}"))
    raw["beams"][0]["locking"] = locking
    return solve(raw, columns)


def _err(s: dict, ref: np.ndarray) -> str:
    if not _ok(s):
        return _stopped(s)
    u = np.array(s["steps"][-1]["probes"]["tip"]["displacement"])
    return f"{100 * np.linalg.norm(u - ref) / np.linalg.norm(ref):.2f} % ({100 * (np.linalg.norm(u) / np.linalg.norm(ref) - 1):+.2f} %)"


def space() -> None:
    fib = runs_of(read_csv(os.path.join(ROOT, "docs", "solid_fibres.csv")))
    refs = solid_refs()
    cases = {c.key: c for c in CASES}
    print("| pressure space per station | " + " | ".join(f"{law.key}, K/μ = 50, 16 el.: rotation / solid − 1"
                                                          for law in LAWS)
          + " | tension, 8 el.: u error (signed) | bending, 8 el.: u error (signed) |")
    print("|---|" + "---:|" * (len(LAWS) + 2))
    with tempfile.TemporaryDirectory() as tmp:
        for lock, name in [("none", None)] + [("mixed", n) for n in SPACES]:
            cells = []
            for law in LAWS:
                c = fib[case_key(law.key, 50.0)]
                try:
                    r = run_ancf(make_case(law, 50.0), 16, tmp, ANCF if name is None else ANCF_MIXED,
                                 pressure_columns=columns_of(name))
                    cells.append(f"{100 * (r['rot'] / c['ref_rot'] - 1):+.2f} %")
                except SolidError:
                    cells.append("fails")
            for key in ("tension", "bending"):
                cells.append(_err(bar(cases[key], 8, lock, tmp, columns_of(name)), refs[key]))
            print(f"| {'none (pointwise K/2 (J−1)²)' if name is None else name} | " + " | ".join(cells) + " |",
                  flush=True)


def solids() -> None:
    refs = solid_refs()
    print("| case | locking | 2 el. | 4 el. | 8 el. | 16 el. |\n|---|---|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for case in CASES:
            for lock in ("none", "mixed"):
                print(f"| {case.key} | {lock} | " + " | ".join(_err(bar(case, n, lock, tmp), refs[case.key])
                                                          for n in (2, 4, 8, 16)) + " |", flush=True)


def column(psi: int, elements: int, axial_points: int, locking: str, tmp: str) -> dict:
    with open(os.path.join(CONFIGS, f"achilles_type3_psi{psi}.yaml")) as fh:
        raw = yaml.safe_load(fh)
    for b in raw["beams"]:
        b.update(elements=elements, axial_points=axial_points, locking=locking)
    raw["output"] = {"dir": os.path.join(tmp, f"{psi}_{elements}_{axial_points}_{locking}"), "vtk": False}
    return solve(raw)


def _soleus(s: dict, k: int = -1) -> float:
    return 1e3 * s["steps"][k]["probes"]["soleus"]["displacement"][0]


def paper() -> None:
    print("Table 1's columns (4 elements, 3 axial points, sliding contact): soleus elongation [mm]\n")
    print("| ψ | 10 N none | 10 N mixed | change | 400 N none | 400 N mixed | change | Newton none / mixed |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for psi in (0, 15, 45):
            a, b = (column(psi, 4, 3, lock, tmp) for lock in ("none", "mixed"))
            its = [sum(st["iterations"] for st in s["steps"]) for s in (a, b)]
            print(f"| {psi}° | {_soleus(a, 0):.4f} | {_soleus(b, 0):.4f} | {100 * (_soleus(b, 0) / _soleus(a, 0) - 1):+.2f} % "
                  f"| {_soleus(a):.4f} | {_soleus(b):.4f} | {100 * (_soleus(b) / _soleus(a) - 1):+.2f} % | "
                  f"{its[0]} / {its[1]} |", flush=True)
        print("\nTable 2's ψ = 45° column: soleus elongation at 400 N [mm]\n")
        print("| axial points | locking | 1 el. | 2 el. | 4 el. | 8 el. | 16 el. |\n|---:|---|---:|---:|---:|---:|---:|")
        for ap in (3, 2):
            for lock in ("none", "mixed"):
                cells = [f"{_soleus(s):.4f}" if _ok(s) else _stopped(s)
                         for s in (column(45, n, ap, lock, tmp) for n in (1, 2, 4, 8, 16))]
                print(f"| {ap} | {lock} | " + " | ".join(cells) + " |", flush=True)


def lone_soleus(load_key: str, fix: str, elements: int, locking: str, out: str) -> dict:
    with open(os.path.join(CONFIGS, "achilles_type3_psi45.yaml")) as fh:
        raw = yaml.safe_load(fh)
    raw["beams"] = raw["beams"][:1]
    raw["beams"][0].update(elements=elements, axial_points=2, locking=locking)
    raw["boundary_conditions"] = [{"beam": "soleus", "node": "first", "fix": fix}]
    raw["loads"] = [{"beam": "soleus", "node": "last", load_key: [1.0, 0.0, 0.0]}]
    raw["probes"] = raw["probes"][:1]
    raw.pop("contact")
    raw["output"] = {"dir": out, "vtk": False}
    return solve(raw)


def point() -> None:
    print("Lone soleus (ψ = 45°, 2 axial points): elongation of its last node [mm] at 10 N and 400 N\n")
    print("| load | support | elements | none: 10 N / 400 N | mixed: 10 N / 400 N | change at 400 N |")
    print("|---|---|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for load in ("force", "traction_force"):
            for fix in ("reduced", "clamped"):
                for n in (4, 16):
                    a, b = (lone_soleus(load, fix, n, lock, os.path.join(tmp, f"{load}{fix}{n}{lock}"))
                            for lock in ("none", "mixed"))
                    print(f"| {load} | {fix} | {n} | {_soleus(a, 0):.4f} / {_soleus(a):.4f} | "
                          f"{_soleus(b, 0):.4f} / {_soleus(b):.4f} | {100 * (_soleus(b) / _soleus(a) - 1):+.2f} % |",
                          flush=True)


def pretwisted() -> None:
    import math
    with open(os.path.join(CONFIGS, "pretwisted_bar.yaml")) as fh:
        base = yaml.safe_load(fh)
    print("configs/pretwisted_bar.yaml (ψ = 60°, section off the twist axis, K/μ = 50, `reduced` root, "
          "traction 4 N; the untwist from r_y of the tip as in docs/verification.md)\n")
    print("| elements | none: elongation [mm] / untwist [°] | mixed: elongation [mm] / untwist [°] |\n|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for n in (1, 2, 4, 8, 16, 32):
            cells = []
            for lock in ("none", "mixed"):
                raw = copy.deepcopy(base)
                raw["beams"][0].update(elements=n, locking=lock)
                raw["output"] = {"dir": os.path.join(tmp, f"{n}{lock}"), "vtk": False}
                raw["petsc"] = {"snes_linesearch_type": "bt"}
                st = solve(raw)["steps"][-1]
                ry = np.array(st["probes"]["tip_r_y"]["value"])
                ry0 = ry - np.array(st["probes"]["tip_r_y"]["displacement"])
                tw = math.degrees(math.atan2(ry0[2], ry0[1]) - math.atan2(ry[2], ry[1]))
                cells.append(f"{1e3 * st['probes']['tip']['displacement'][0]:.5f} / {tw:.5f}")
            print(f"| {n} | " + " | ".join(cells) + " |", flush=True)


def published() -> None:
    from ancf_verify.studies import goh_sets as g
    base = {k: g.PUBLISHED[k] for k in ("mu", "k1", "k2")}
    print("Lone soleus, tendon_model_2023 (μ = 61.2 kPa, K = 0.2 GPa = 3268 μ, k1 = 3.7859 MPa, k2 = 7.8085), "
          "4 elements, Table 1's 13 levels\n")
    print("| axial points | locking | status | last level [N] | cut-backs | Newton | soleus [mm] |\n"
          "|---:|---|---|---:|---:|---:|---:|")
    for ap in (2, 3):
        for lock in ("none", "mixed"):
            raw = g.column(**base, K=g.PUBLISHED["K"], mode=None, elements=4, axial_points=ap)
            for b in raw["beams"]:
                b["locking"] = lock
            s = g.solve(raw)
            print(f"| {ap} | {lock} | {s['status']} | {s['last']:g} | {s['cutbacks']} | {s['newton']} | "
                  f"{s['soleus_mm']:.3f} |", flush=True)


PARTS = {"space": space, "solids": solids, "pretwisted": pretwisted, "paper": paper, "point": point,
         "published": published}


def main(argv: list[str]) -> int:
    from ancf_verify.cli import study_parts
    for name in study_parts("locking_study.py", __doc__, PARTS, argv) or list(PARTS):
        if name not in PARTS:
            print(f"locking_study: unknown part {name!r}; parts: {', '.join(PARTS)}", file=sys.stderr)
            return 2
        t0 = time.perf_counter()
        print(f"\n## {name}  ({time.strftime('%Y-%m-%d')})\n", flush=True)
        PARTS[name]()
        print(f"\n({time.perf_counter() - t0:.0f} s)", flush=True)
    return 0
