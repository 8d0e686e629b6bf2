"""Table 1 with neo-Hookean and with GOH side by side, and the untwist of the soleus (issue 26).

The paper's three columns (configs/achilles_type3_psi{0,15,45}.yaml: ψ = 0/15/45°, the paper's
13 load levels) are run twice: as they are (neo-Hookean subtendons) and with each subtendon's
material replaced by the GOH law of configs/achilles_type3_psi45_goh.yaml (same neo-Hookean matrix,
fibres along the material lines of the pretwist, k1, k2 from the paper's first author's public
code; nothing fitted to Table 1).  Reported per column: the soleus elongation at every level, the
rotation about x of the soleus' end section at every level and along the soleus at the last level,
and how each run converged (cut-backs, Newton iterations, wall time).

The section rotation at a node is the rotation angle of the polar decomposition of the in-plane
(y, z) part of the section's gradient vectors [r_y r_z] against the reference ones, positive about
+x (the sense of the pretwist, which turns the sections by +ψ x/L).

Usage: OPENBLAS_NUM_THREADS=1 python scripts/table1_goh.py [--elements 4] [--mode sliding]
       [--twists 0 15 45] [--grid] [--out DIR] [--write-docs]
``--write-docs`` (the paper's setup: 4 elements, sliding) replaces the marked block ``table1_goh`` of
docs/fibres.md and writes docs/figures/fibres_table1.png; with ``--grid`` (every column at 4 and 8
elements, both contact laws: 24 runs) it replaces the block ``table1_goh_grid``.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import h5py
import numpy as np
import yaml

from ancf_verify import paths

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = paths.ROOT

from ancf_petsc.paper.inputs import read_paper  # noqa: E402

TWISTS = (0, 15, 45)
LAWS = ("neo-hookean", "goh")
GOH_CONFIG = os.path.join(ROOT, "configs", "achilles_type3_psi45_goh.yaml")
PAPER_CSV = os.path.join(ROOT, "configs", "data", "paper_table1_elongation.csv")
DOC = os.path.join(ROOT, "docs", "fibres.md")
FIGURE = os.path.join(ROOT, "docs", "figures", "fibres_table1.png")
BLOCKS = {"table": "table1_goh", "grid": "table1_goh_grid"}   # marked blocks of docs/fibres.md
PROBE = "soleus"


def load_yaml(path: str) -> dict:
    with open(path) as fh:
        return yaml.safe_load(fh)


def goh_materials() -> dict[str, dict]:
    """The GOH material of each subtendon, by beam name, from the ψ = 45° GOH example config."""
    return {b["name"]: b["material"] for b in load_yaml(GOH_CONFIG)["beams"]}


def column_config(psi: int, law: str, elements: int, mode: str, out_dir: str) -> dict:
    """The paper's column ψ with ``law``; GOH keeps the neo-Hookean config's matrix (checked)."""
    raw = load_yaml(os.path.join(ROOT, "configs", f"achilles_type3_psi{psi}.yaml"))
    goh = goh_materials()
    for b in raw["beams"]:
        b["elements"] = elements
        b["section"]["file"] = os.path.join(ROOT, "configs", b["section"]["file"])
        if law == "goh":
            m, g = b["material"], goh[b["name"]]
            if (m["mu"], m["bulk_modulus"]) != (g["mu"], g["bulk_modulus"]):
                raise SystemExit(f"{GOH_CONFIG}: beam {b['name']}: matrix mu, bulk_modulus "
                                 f"{g['mu']}, {g['bulk_modulus']} differ from the neo-Hookean column's "
                                 f"{m['mu']}, {m['bulk_modulus']}; the comparison needs the same matrix")
            b["material"] = dict(g)
    raw["contact"]["mode"] = mode
    raw["output"] = {"dir": out_dir, "vtk": False}
    return raw


def section_rotation_deg(q: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """Rotation about +x of the sections at nodes (n, 6, 3): polar angle of A A0⁻¹, A = (y, z) rows
    of [r_y r_z]."""
    A, A0 = q[:, 1:3, 1:3].transpose(0, 2, 1), q0[:, 1:3, 1:3].transpose(0, 2, 1)
    M = np.matmul(A, np.linalg.inv(A0))
    return np.degrees(np.arctan2(M[:, 1, 0] - M[:, 0, 1], M[:, 0, 0] + M[:, 1, 1]))


def rotations(h5_path: str, beam: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """x of the beam's nodes, the section rotation at its last node per converged level, and the
    rotation at every node at the last converged level [deg]."""
    with h5py.File(h5_path, "r") as h5:
        q0 = h5["model/reference_nodal_vectors"][:]
        g = h5[f"model/beams/{beam}"]
        nodes = np.unique(g["connectivity"][:])
        x = g["x_nodes"][:]
        order = np.argsort(x)
        nodes, x = nodes[order], x[order]
        k = int(h5["steps"].attrs["converged"])
        end, along = [], np.full(len(nodes), np.nan)
        for s in range(1, k + 1):
            q = h5[f"steps/step_{s:04d}/nodal_vectors"][:]
            rot = section_rotation_deg(q[nodes], q0[nodes])
            end.append(rot[-1])
            along = rot
    return x, np.array(end), along


def run(psi: int, law: str, elements: int, mode: str, out: str) -> dict:
    tag = f"psi{psi}_{law}_{elements}_{mode}"
    out_dir = os.path.join(out, tag)
    path = os.path.join(out, tag + ".yaml")
    with open(path, "w") as fh:
        yaml.safe_dump(column_config(psi, law, elements, mode, out_dir), fh, sort_keys=False)
    exe = os.path.join(ROOT, ".venv", "bin", "ancf-solve")
    t = time.perf_counter()
    p = subprocess.run([exe, path, "--quiet"], capture_output=True, text=True)
    wall = time.perf_counter() - t
    with open(os.path.join(out, tag + ".log"), "w") as fh:
        fh.write(p.stdout + p.stderr)
    s = paths.run_summary(out_dir, p, "table1_goh")
    x, end, along = rotations(os.path.join(out_dir, "results.h5"), PROBE)
    return {"psi": psi, "law": law, "elements": elements, "mode": mode, "status": s["status"],
            "exit": p.returncode, "wall_s": wall,
            "cutbacks": sum(st.get("cutbacks", 0) for st in s["steps"]),
            "newton": sum(st.get("iterations", 0) for st in s["steps"]),
            "loads": [st["load_factor"] for st in s["steps"]],
            "elong_mm": [1e3 * st["probes"][PROBE]["displacement"][0] for st in s["steps"]],
            "end_rotation_deg": end.tolist(), "x": x.tolist(), "rotation_along_deg": along.tolist()}


def lone_bar(out: str) -> dict[str, float]:
    """Rotation of the end section of configs/pretwisted_bar.yaml twisted about its own centroid
    (a lone bar, no contact) at its last level, neo-Hookean and GOH (its matrix, the Achilles
    fibres): the sign of the classic tension-untwist coupling in this script's convention."""
    raw = load_yaml(os.path.join(ROOT, "configs", "pretwisted_bar.yaml"))
    beam = raw["beams"][0]
    centre = beam["section"]["center"]
    raw["geometry"]["twist_axis"] = list(centre)
    fibres = next(iter(goh_materials().values()))
    result = {}
    for law in LAWS:
        cfg = yaml.safe_load(yaml.safe_dump(raw))
        if law == "goh":
            m = cfg["beams"][0]["material"]
            cfg["beams"][0]["material"] = {"model": "goh", "mu": m["mu"], "bulk_modulus": m["bulk_modulus"],
                                           **{k: fibres[k] for k in ("k1", "k2", "kappa", "fibres")}}
        out_dir = os.path.join(out, f"lone_bar_{law}")
        cfg["output"] = {"dir": out_dir, "vtk": False}
        path = out_dir + ".yaml"
        with open(path, "w") as fh:
            yaml.safe_dump(cfg, fh, sort_keys=False)
        p = subprocess.run([os.path.join(ROOT, ".venv", "bin", "ancf-solve"), path, "--quiet"],
                           capture_output=True, text=True)
        if p.returncode:
            raise SystemExit(f"{path}: ancf-solve failed:\n{p.stdout}{p.stderr}")
        result[law] = float(rotations(os.path.join(out_dir, "results.h5"), beam["name"])[1][-1])
    result["twist_deg"] = float(raw["geometry"]["twist_deg"])
    return result


def at_levels(r: dict, key: str, loads: np.ndarray) -> np.ndarray:
    """r[key] at each Table 1 level (nan where the run did not get there)."""
    out = np.full(len(loads), np.nan)
    for f, v in zip(r["loads"], r[key]):
        hit = np.flatnonzero(np.isclose(loads, f))
        if len(hit):
            out[hit[0]] = v
    return out


def fmt(v: float, spec: str) -> str:
    return format(v, spec) if np.isfinite(v) else "—"


def markdown(rows: dict, paper: dict, bar: dict) -> str:
    loads = paper["load_N"]
    el = {k: at_levels(r, "elong_mm", loads) for k, r in rows.items()}
    rot = {k: at_levels(r, "end_rotation_deg", loads) for k, r in rows.items()}
    r0 = next(iter(rows.values()))
    head = (f"{r0['elements']} elements per subtendon, {r0['mode']} contact, 1 rank. "
            "Soleus elongation [mm] (x-displacement of its last node); the paper's numbers are for "
            "**neo-Hookean** subtendons, GOH is not fitted to them.")
    lines = [head, "", "| load [N] | " + " | ".join(
        f"ψ={p}° paper | ψ={p}° NH | ψ={p}° GOH | GOH/NH" for p in TWISTS) + " |",
        "|---:|" + "---:|---:|---:|---:|" * len(TWISTS)]
    for i, f in enumerate(loads):
        cells = []
        for p in TWISTS:
            nh, goh = el[(p, "neo-hookean")][i], el[(p, "goh")][i]
            cells.append(f"{paper[f'psi{p}_mm'][i]:.3f} | {fmt(nh, '.3f')} | {fmt(goh, '.3f')} | "
                         f"{fmt(goh / nh, '.3f')}")
        lines.append(f"| {f:g} | " + " | ".join(cells) + " |")
    lines += ["", "Rotation of the soleus' end section about x [deg] (positive: the pretwist's sense; "
                  "the paper reports none):", "",
              "| load [N] | " + " | ".join(f"ψ={p}° NH | ψ={p}° GOH" for p in TWISTS) + " |",
              "|---:|" + "---:|---:|" * len(TWISTS)]
    for i, f in enumerate(loads):
        lines.append(f"| {f:g} | " + " | ".join(
            f"{fmt(rot[(p, 'neo-hookean')][i], '+.3f')} | {fmt(rot[(p, 'goh')][i], '+.3f')}"
            for p in TWISTS) + " |")
    d = {law: {p: rot[(p, law)][-1] - rot[(0, law)][-1] for p in TWISTS[1:]} for law in LAWS}
    lines += ["", f"ψ = 0 turns too, so that part is not caused by the pretwist; what the pretwist adds at "
                  f"{loads[-1]:g} N (rotation at ψ minus rotation at ψ = 0): "
              + "; ".join(f"ψ={p}°: NH {d['neo-hookean'][p]:+.3f}°, GOH {d['goh'][p]:+.3f}°"
                          for p in TWISTS[1:]) + ".",
              "", f"For the sign: a lone bar (configs/pretwisted_bar.yaml, ψ = {bar['twist_deg']:g}° about "
                  f"its own centroid, no contact, the same fibres on its matrix) turns its end section by "
                  f"{bar['neo-hookean']:+.3f}° (neo-Hookean) and {bar['goh']:+.3f}° (GOH) at its last level."]
    lines += ["", "How each run converged:", "",
              "| ψ | law | status | cut-backs | Newton iterations | wall [s] |", "|---|---|---|---:|---:|---:|"]
    for (p, law), r in rows.items():
        lines.append(f"| {p}° | {law} | {r['status']} | {r['cutbacks']} | {r['newton']} | {r['wall_s']:.1f} |")
    return "\n".join(lines)


def figure(rows: dict, paper: dict, path: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    colours = {0: "tab:blue", 15: "tab:orange", 45: "tab:green"}
    for (p, law), r in rows.items():
        style = "-" if law == "neo-hookean" else "--"
        label = f"ψ={p}° {'neo-Hookean' if law == 'neo-hookean' else 'GOH'}"
        a.plot(r["elong_mm"], r["loads"], style, color=colours[p], label=label)
        b.plot(1e3 * np.array(r["x"]), r["rotation_along_deg"], style + "o", ms=3, color=colours[p],
               label=label)
    for p in TWISTS:
        a.plot(paper[f"psi{p}_mm"], paper["load_N"], "x", color=colours[p], label=f"paper ψ={p}° (NH)")
    a.set_xlabel("soleus elongation [mm]")
    a.set_ylabel("force [N]")
    a.set_title("Table 1 levels: neo-Hookean (solid), GOH (dashed)")
    a.legend(fontsize=7, ncol=2)
    b.axhline(0.0, color="0.7", lw=0.8)
    b.set_xlabel("x along the soleus [mm]")
    b.set_ylabel("section rotation about x [deg]")
    b.set_title(f"soleus at {rows[(TWISTS[0], LAWS[0])]['loads'][-1]:g} N")
    b.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def grid_markdown(rows: dict) -> str:
    """Convergence, elongation and end rotation at the last level of every (elements, contact, ψ, law)."""
    lines = ["| ψ | elements | contact | law | status | cut-backs | Newton | wall [s] | GOH/NH wall | "
             "soleus elongation at 400 N [mm] | end rotation at 400 N [deg] |",
             "|---|---:|---|---|---|---:|---:|---:|---:|---:|---:|"]
    for (n, mode, p, law), r in rows.items():
        nh = rows[(n, mode, p, "neo-hookean")]
        ratio = f"{r['wall_s'] / nh['wall_s']:.2f}" if law == "goh" else ""
        done = r["loads"] and np.isclose(r["loads"][-1], 400.0)
        el = f"{r['elong_mm'][-1]:.3f}" if done else "—"
        rot = f"{r['end_rotation_deg'][-1]:+.3f}" if done else "—"
        lines.append(f"| {p}° | {n} | {mode} | {law} | {r['status']} | {r['cutbacks']} | {r['newton']} | "
                     f"{r['wall_s']:.1f} | {ratio} | {el} | {rot} |")
    return "\n".join(lines)


def write_docs(block: str, text: str) -> None:
    """Replace the marked block ``block`` of docs/fibres.md with ``text``."""
    begin = f"<!-- {block}: begin (written by scripts/table1_goh.py --write-docs; do not edit) -->"
    end = f"<!-- {block}: end -->"
    with open(DOC) as fh:
        doc = fh.read()
    if begin not in doc or end not in doc:
        raise SystemExit(f"{DOC}: the markers {begin!r} ... {end!r} are missing; add them where the "
                         "block belongs")
    head, rest = doc.split(begin, 1)
    tail = rest.split(end, 1)[1]
    with open(DOC, "w") as fh:
        fh.write(head + begin + "\n" + text + "\n" + end + tail)


def main() -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--elements", type=int, default=4)
    ap.add_argument("--mode", default="sliding", choices=["sliding", "unilateral"])
    ap.add_argument("--twists", type=int, nargs="+", default=list(TWISTS), choices=list(TWISTS))
    ap.add_argument("--grid", action="store_true",
                    help="every column at 4 and 8 elements, sliding and unilateral: convergence, "
                         "elongation and end rotation at 400 N")
    ap.add_argument("--out", default="/tmp/ancf-table1-goh")
    ap.add_argument("--write-docs", action="store_true")
    args = ap.parse_args()
    if args.write_docs and (args.elements != 4 or args.mode != "sliding" or args.twists != list(TWISTS)):
        raise SystemExit("--write-docs is for the paper's setup: 4 elements, sliding, all three twists")
    os.makedirs(args.out, exist_ok=True)
    if args.grid:
        rows = {}
        for n in (4, 8):
            for mode in ("sliding", "unilateral"):
                for p in args.twists:
                    for law in LAWS:
                        rows[(n, mode, p, law)] = r = run(p, law, n, mode, args.out)
                        print(json.dumps({k: r[k] for k in ("psi", "law", "elements", "mode", "status",
                                                             "cutbacks", "newton", "wall_s")}), flush=True)
        text = grid_markdown(rows)
        print(text)
        if args.write_docs:
            write_docs(BLOCKS["grid"], text)
        return 0
    rows = {}
    for p in args.twists:
        for law in LAWS:
            r = run(p, law, args.elements, args.mode, args.out)
            rows[(p, law)] = r
            print(json.dumps({k: r[k] for k in ("psi", "law", "elements", "mode", "status", "cutbacks",
                                                 "newton", "wall_s")}), flush=True)
    if args.twists != list(TWISTS):
        return 0
    paper = read_paper(PAPER_CSV)
    text = markdown(rows, paper, lone_bar(args.out))
    print(text)
    if args.write_docs:
        figure(rows, paper, FIGURE)
        fig = os.path.relpath(FIGURE, os.path.dirname(DOC))
        write_docs(BLOCKS["table"], f"{text}\n\n![Table 1 levels and the soleus' section rotation]({fig})")
    return 0
