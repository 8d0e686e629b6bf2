"""Verification report: runs the core verification problems and prints Markdown tables.

Figures go to docs/figures/.  docs/verification.md is this output (with its words around it).
Usage: python scripts/verification_report.py [--out docs/figures]
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile

from ancf_verify import paths

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = paths.ROOT
CONFIGS = os.path.join(ROOT, "configs")

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ancf_petsc.config.specs import DEFAULT_AXIAL_POINTS
from ancf_petsc.physics.materials import NeoHookean
from ancf_petsc.physics.reference_solutions import elastica_tip, uniaxial_stretches
import yaml  # noqa: E402

import ancf_petsc  # noqa: E402


def load_raw(name: str) -> dict:
    """A config of configs/ as a dict."""
    with open(os.path.join(CONFIGS, name)) as fh:
        return yaml.safe_load(fh)


def run_inline(raw: dict, out_dir: str) -> dict:
    """Solve a config dict in this process (1 rank, quietly); its summary."""
    raw = dict(raw, output={**raw.get("output", {}), "dir": out_dir})
    return ancf_petsc.solve(ancf_petsc.parse_config(raw, base_dir=CONFIGS), log=lambda *_: None).summary


def newton_counts(summary):
    return "/".join(str(s["iterations"]) for s in summary["steps"])


def uniaxial(tmp, figdir):
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["output"]["vtk"] = False
    s = run_inline(raw, os.path.join(tmp, "uni"))
    area = s["sections"]["bar"]["area"]
    m = raw["beams"][0]["material"]
    mat = NeoHookean(m["mu"], m["bulk_modulus"])
    F = raw["loads"][0]["traction_force"][0]
    L = raw["geometry"]["length"]
    print("### Uniaxial tension, neo-Hookean, 1 element (`configs/uniaxial_neohookean.yaml`)\n")
    print(f"default axial rule: {DEFAULT_AXIAL_POINTS} Gauss points\n")
    print("| load [N] | strain FE | strain exact | rel. error | Newton its |")
    print("|---:|---:|---:|---:|---:|")
    fe, ex = [], []
    for st in s["steps"]:
        lam, _ = uniaxial_stretches(mat, st["load_factor"] * F / area)
        u = st["probes"]["tip"]["displacement"][0]
        fe.append(u / L)
        ex.append(lam - 1)
        print(f"| {st['load_factor'] * F:.1f} | {u / L:.6f} | {lam - 1:.6f} | "
              f"{abs(u / L / (lam - 1) - 1):.1e} | {st['iterations']} |")
    loads = [st["load_factor"] * F for st in s["steps"]]
    fig, ax = plt.subplots(figsize=(4.5, 3.2))
    ax.plot(ex, loads, "k-", label="exact")
    ax.plot(fe, loads, "o", label="ANCF 3363, 1 element")
    ax.set_xlabel("engineering strain")
    ax.set_ylabel("force [N]")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(figdir, "uniaxial.png"), dpi=130)
    plt.close(fig)


def elastica(tmp, figdir):
    print("\n### Euler elastica, SVK nu = 0, L/h = 100 (`configs/elastica_svk.yaml`)\n")
    print("| elements | axial points | PL²/EI | u/L FE | u/L elastica | w/L FE | w/L elastica | "
          "err u | err w | Newton its |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    fig, ax = plt.subplots(figsize=(7.4, 3.4))
    alphas = np.linspace(0.05, 5, 60)
    ex = np.array([elastica_tip(a) for a in alphas])
    ax.plot(alphas, ex[:, 1], "k-", label="exact: deflection w/L (filled)")
    ax.plot(alphas, -ex[:, 0], "k--", label="exact: shortening −u/L (open)")
    default = DEFAULT_AXIAL_POINTS
    for ne, ax_pts, mk in ((8, 3, "^"), (16, 3, "s"), (32, 3, "o"), (8, 2, "x"), (16, 2, "+")):
        raw = load_raw("elastica_svk.yaml")
        raw["beams"][0]["elements"] = ne
        raw["beams"][0]["axial_points"] = ax_pts
        raw["output"]["vtk"] = False
        s = run_inline(raw, os.path.join(tmp, f"el{ne}{ax_pts}"))
        a_fe, w_fe, u_fe = [], [], []
        for st in s["steps"]:
            a = 5.0 * st["load_factor"]
            ux, w = elastica_tip(a)
            d = st["probes"]["tip"]["displacement"]
            a_fe.append(a)
            w_fe.append(d[2])
            u_fe.append(-d[0])
            print(f"| {ne} | {ax_pts} | {a:g} | {d[0]:.5f} | {ux:.5f} | {d[2]:.5f} | {w:.5f} | "
                  f"{d[0] / ux - 1:+.1e} | {d[2] / w - 1:+.1e} | {st['iterations']} |")
        ax.plot(a_fe, w_fe, mk, label=f"{ne} elements, {ax_pts} axial points"
                + (" (the default rule)" if ax_pts == default else ""))
        ax.plot(a_fe, u_fe, mk, mfc="none", color=ax.lines[-1].get_color())
    ax.set_xlabel("P L² / EI")
    ax.set_ylabel("tip displacement / L")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    fig.tight_layout()
    fig.savefig(os.path.join(figdir, "elastica.png"), dpi=130, bbox_inches="tight")
    plt.close(fig)


def pretwisted(tmp, figdir):
    print("\n### Pretwisted bar, psi = 60°, section off the twist axis (`configs/pretwisted_bar.yaml`)\n")
    print("| elements | elongation [mm] | change | untwist [deg] | change | Newton its per level |")
    print("|---:|---:|---:|---:|---:|---|")
    raw = load_raw("pretwisted_bar.yaml")
    raw["output"]["vtk"] = False
    raw["petsc"] = {"snes_linesearch_type": "bt"}
    prev = None
    rows = []
    for ne in (1, 2, 4, 8, 16, 32):
        raw["beams"][0]["elements"] = ne
        s = run_inline(raw, os.path.join(tmp, f"tw{ne}"))
        st = s["steps"][-1]
        u = st["probes"]["tip"]["displacement"][0]
        ry = np.array(st["probes"]["tip_r_y"]["value"])
        ry0 = ry - np.array(st["probes"]["tip_r_y"]["displacement"])
        tw = math.degrees(math.atan2(ry0[2], ry0[1]) - math.atan2(ry[2], ry[1]))
        ch = "" if prev is None else f"{1e3 * (u - prev[0]):+.5f}"
        cht = "" if prev is None else f"{tw - prev[1]:+.5f}"
        print(f"| {ne} | {1e3 * u:.5f} | {ch} | {tw:.5f} | {cht} | {newton_counts(s)} |")
        prev = (u, tw)
        rows.append((ne, u, tw))


def main():
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "figures"))
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        uniaxial(tmp, args.out)
        elastica(tmp, args.out)
        pretwisted(tmp, args.out)
