"""CSV, figure and the generated block of docs/fibres.md for the fibre bar."""
from __future__ import annotations

import csv
import math
import os
import shutil

import numpy as np

from ancf_verify.bars.cases import Case
from ancf_verify.convergence import richardson
from ancf_verify.fibres.cases import (ANCF, ANCF_MIXED, ANCF_MODELS, ANCF_VOL, BLOCK, BULK_RATIOS, DOC,
    FIBRES, FIGURE, FORCE, LAWS, LENGTH, MU, SECTION, STATIONS, STEPS, TWIST, VOLUMETRIC_DEGREE)
from ancf_verify.fibres.measures import rim_inclination_deg
from ancf_verify.stack import SolidError


# --------------------------------------------------------------------------------------------
# CSV: one row per run and level (kind "end": the end section) and, at the last level, per
# station x = k L / 8 (kind "along": the section rotation there)
# --------------------------------------------------------------------------------------------
COLUMNS = ["case", "law", "bulk_ratio", "model", "resolution", "dofs", "wall_s", "solid_mesh_s",
           "newton_its", "kind", "load_N", "x_m", "ux_m", "uy_m", "uz_m", "rot_deg", "vol_share",
           "fibre_field_err"]


def csv_rows(case: Case, law: str, ratio: float, runs: list) -> list[dict]:
    """The CSV rows of one case's runs."""
    out = []
    for r in runs:
        base = {"case": case.key, "law": law, "bulk_ratio": f"{ratio:g}", "model": r["model"],
                "resolution": r["res"], "dofs": r["dofs"], "wall_s": f"{r['wall']:.4f}",
                "solid_mesh_s": "" if math.isnan(r.get("mesh", math.nan)) else f"{r['mesh']:.4f}",
                "newton_its": r["its"],
                "fibre_field_err": "" if math.isnan(r["field_err"]) else f"{r['field_err']:.3e}"}
        for lv in r["levels"]:
            out.append({**base, "kind": "end", "load_N": f"{lv['load']:g}", "x_m": f"{case.length:g}",
                        **{f"u{c}_m": f"{v:.9e}" for c, v in zip("xyz", lv["u"])},
                        "rot_deg": f"{lv['rot']:.7f}",
                        "vol_share": f"{lv['vol_share']:.5e}" if "vol_share" in lv else ""})
        for k, rot in enumerate(r["levels"][-1]["along"]):
            out.append({**base, "kind": "along", "load_N": f"{r['levels'][-1]['load']:g}",
                        "x_m": f"{(k + 1) * case.length / STATIONS:.6g}", "ux_m": "", "uy_m": "",
                        "uz_m": "", "rot_deg": f"{rot:.7f}", "vol_share": ""})
    return out


def write_csv(path: str, rows: list[dict], columns: list[str] = COLUMNS) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=columns)
        w.writeheader()
        w.writerows(rows)


def read_csv(path: str) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


# --------------------------------------------------------------------------------------------
# Evaluation (from the CSV rows only, so that the committed CSV regenerates the docs)
# --------------------------------------------------------------------------------------------
def runs_of(rows: list[dict]) -> dict:
    """{case: {"law", "ratio", "ancf": [run], "solid": [run coarse to fine]}}; a run holds its
    final end displacement u, rotation, volumetric share, rotation along x and per-level values."""
    out: dict = {}
    for d in rows:
        c = out.setdefault(d["case"], {"law": d["law"], "ratio": float(d["bulk_ratio"]), "runs": {}})
        r = c["runs"].setdefault((d["model"], d["resolution"]), {
            "model": d["model"], "res": d["resolution"], "dofs": int(d["dofs"]), "wall": float(d["wall_s"]),
            "its": int(d["newton_its"]), "field_err": float(d["fibre_field_err"] or "nan"),
            "loads": [], "rots": [], "along": [], "x": []})
        if d["kind"] == "end":
            r["loads"].append(float(d["load_N"]))
            r["rots"].append(float(d["rot_deg"]))
            r["u"] = np.array([float(d[f"u{c}_m"]) for c in "xyz"])
            r["rot"] = float(d["rot_deg"])
            if d["vol_share"]:
                r["vol_share"] = float(d["vol_share"])
        else:
            r["x"].append(float(d["x_m"]))
            r["along"].append(float(d["rot_deg"]))
    for c in out.values():
        runs = list(c.pop("runs").values())
        c["ancf"] = [r for r in runs if r["model"] == ANCF]
        c["vol"] = [r for r in runs if r["model"] == ANCF_VOL]
        c["mixed"] = [r for r in runs if r["model"] == ANCF_MIXED]
        c["solid"] = sorted((r for r in runs if r["model"] not in ANCF_MODELS), key=lambda r: r["dofs"])
        ref_u, unc_u, _ = richardson(c["solid"])
        ref_r, unc_r, _ = richardson([{"u": np.array([r["rot"]]), "dofs": r["dofs"]} for r in c["solid"]])
        c.update(ref_u=ref_u, unc_u=unc_u, ref_rot=float(ref_r[0]), unc_rot=unc_r)
        for r in runs:
            r["err_u"] = float(np.linalg.norm(r["u"] - ref_u) / np.linalg.norm(ref_u))
            r["err_rot"] = abs(r["rot"] - c["ref_rot"]) / abs(c["ref_rot"])
    return out


def pct(x: float) -> str:
    return f"{100 * x:.2f} %"


def ancf_label(c: dict, elements: int, kind: str = "ancf") -> dict:
    return next(r for r in c[kind] if r["res"] == f"{elements} el.")


def render_block(rows: list[dict]) -> str:
    """The docs/fibres.md block: summary of every case, the main cases' runs, rotation along x."""
    cases = runs_of(rows)
    fine = max(int(r["res"].split()[0]) for c in cases.values() for r in c["ancf"])
    mid = fine // 2
    first = next(iter(cases.values()))
    by_ratio: dict = {}
    for c in cases.values():
        by_ratio.setdefault(", ".join(r["res"].removeprefix("h ").removesuffix(" mm") for r in c["solid"]),
                            []).append(f"{c['ratio']:g}")
    meshes = "; ".join(f"h = {h} mm at K/μ = {', '.join(sorted(set(rs), key=float, reverse=True))}"
                       for h, rs in by_ratio.items())
    lines = [f"Bar: ellipse {2e3 * SECTION['semi_axes'][0]:g} x {2e3 * SECTION['semi_axes'][1]:g} mm centred "
             f"on the twist axis, L = {1e3 * LENGTH:g} mm, ψ = {TWIST:g}°, root clamped, end traction "
             f"{FORCE:g} N along x in {len(STEPS)} levels; fibre inclination at the rim of the major axis "
             f"atan(ρψ/L) = {rim_inclination_deg():.1f}°. Matrix μ = {MU / 1e6:g} MPa; fibres k1 = "
             f"{FIBRES['k1'] / 1e6:g} MPa, k2 = {FIBRES['k2']:g}, κ = {FIBRES['kappa']:g}. ANCF: 3363, 2 axial "
             f"Gauss points, {', '.join(r['res'].split()[0] for r in first['ancf'])} elements. Solid: P2 "
             f"tetrahedra, {meshes}; reference = Richardson extrapolation "
             "of the finest three meshes (uncertainty: its distance from the finest). Errors against the reference; "
             "rotation = end-section rotation about x (negative: untwist).", "",
             f"| law | K/μ | solid: u_x [mm] | solid: rotation [°] | ANCF {mid} el.: u / rotation error | "
             f"ANCF {fine} el.: u / rotation error | **locking: mixed**, {mid} el.: u / rotation error | "
             f"**locking: mixed**, {fine} el.: u / rotation error | rotation ANCF / solid − 1, {fine} el.: "
             f"none / mixed | volumetric share of the energy, {fine} el.: none / mixed / finest solid | "
             f"diagnosis: ANCF {fine} el. with K/2 (J−1)² on a degree-{VOLUMETRIC_DEGREE} section rule: "
             "u / rotation error |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for c in cases.values():
        a, b = ancf_label(c, mid), ancf_label(c, fine)
        ma, mb = ancf_label(c, mid, "mixed"), ancf_label(c, fine, "mixed")
        vb = ancf_label(c, fine, "vol")
        lines.append(f"| {c['law']} | {c['ratio']:g} | {1e3 * c['ref_u'][0]:.4f} (± {pct(c['unc_u'])}) | "
                     f"{c['ref_rot']:+.3f} (± {pct(c['unc_rot'])}) | {pct(a['err_u'])} / {pct(a['err_rot'])} | "
                     f"{pct(b['err_u'])} / {pct(b['err_rot'])} | "
                     f"{pct(ma['err_u'])} / {pct(ma['err_rot'])} | {pct(mb['err_u'])} / {pct(mb['err_rot'])} | "
                     f"{100 * (b['rot'] / c['ref_rot'] - 1):+.2f} % / {100 * (mb['rot'] / c['ref_rot'] - 1):+.2f} % | "
                     f"{100 * b['vol_share']:.2f} % / {100 * mb['vol_share']:.2f} % / "
                     f"{100 * c['solid'][-1]['vol_share']:.2f} % | {pct(vb['err_u'])} / {pct(vb['err_rot'])} |")
    for key, c in cases.items():
        if c["law"] != "goh_twist":
            continue
        lines += ["", f"Runs of {key} (GOH, helical fibres, K/μ = {c['ratio']:g}), end values at {FORCE:g} N:", "",
                  "| model | resolution | DOFs | Newton its | u_x [mm] | rotation [°] | u error | rotation error | "
                  "fibre field vs ANCF's |", "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
        for r in c["ancf"] + c["mixed"] + c["vol"] + c["solid"]:
            fe = "" if math.isnan(r["field_err"]) else f"{r['field_err']:.1e}"
            lines.append(f"| {r['model']} | {r['res']} | {r['dofs']} | {r['its']} | {1e3 * r['u'][0]:.4f} | "
                         f"{r['rot']:+.4f} | {pct(r['err_u'])} | {pct(r['err_rot'])} | {fe} |")
    ref = [k for k, c in cases.items() if c["ratio"] == max(BULK_RATIOS)]
    lines += ["", f"Section rotation [°] along the bar at {FORCE:g} N, K/μ = {max(BULK_RATIOS):g}: ANCF {fine} el. "
              "(r_y, r_z at the node) without and with `locking: mixed` / finest solid (least-squares fit over "
              "the section rule's points):", "",
              "| x/L | " + " | ".join(f"{cases[k]['law']} ANCF | mixed | solid" for k in ref) + " |",
              "|---:|" + "---:|---:|---:|" * len(ref)]
    for i in range(STATIONS):
        cells = []
        for k in ref:
            a, m, s = ancf_label(cases[k], fine), ancf_label(cases[k], fine, "mixed"), cases[k]["solid"][-1]
            cells.append(f"{a['along'][i]:+.3f} | {m['along'][i]:+.3f} | {s['along'][i]:+.3f}")
        lines.append(f"| {(i + 1) / STATIONS:.3f} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def replace_block(text: str, block: str, name: str = BLOCK, writer: str = "scripts/verify_solid_fibres.py") -> str:
    """``text`` with the marked block ``name`` (written by the script ``writer``) replaced by
    ``block``."""
    begin = f"<!-- {name}: begin (written by {writer}; do not edit) -->"
    end = f"<!-- {name}: end -->"
    i, j = text.find(begin), text.find(end)
    if i < 0 or j < i:
        raise SolidError(f"{DOC}: the markers of block {name} are missing")
    return text[:i + len(begin)] + "\n" + block + "\n" + text[j:]


def page_for(out: str, doc: str | None) -> str:
    """The page whose block a run writes: ``doc`` if given; else docs/fibres.md for a run into
    docs/, and for a run into another ``out`` a copy of it there (the committed page stays as it is)."""
    if doc is not None:
        return doc
    if os.path.realpath(out) == os.path.realpath(os.path.dirname(DOC)):
        return DOC
    mine = os.path.join(out, os.path.basename(DOC))
    if not os.path.exists(mine):
        os.makedirs(out, exist_ok=True)
        shutil.copyfile(DOC, mine)
    return mine


def write_block(doc: str, block: str, name: str = BLOCK, writer: str = "scripts/verify_solid_fibres.py") -> None:
    """The page ``doc`` with its block ``name`` replaced (``replace_block``); the page is only
    opened for writing once the new text stands (missing markers leave it as it was)."""
    with open(doc, encoding="utf-8") as fh:
        text = replace_block(fh.read(), block, name, writer)
    with open(doc, "w", encoding="utf-8") as fh:
        fh.write(text)


def plot(path: str, rows: list[dict]) -> None:
    """(a) end rotation against load, (b) rotation along x at the last level, both at the largest
    K/μ, ANCF (lines) and finest solid (markers); (c) ANCF's rotation error against K/μ."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cases = runs_of(rows)
    fine = max(int(r["res"].split()[0]) for c in cases.values() for r in c["ancf"])
    fig, ax = plt.subplots(1, 3, figsize=(15, 5.8))
    colours = {law.key: f"C{i}" for i, law in enumerate(LAWS)}
    for key, c in cases.items():
        col = colours[c["law"]]
        if c["ratio"] == max(BULK_RATIOS):
            a, s, m = ancf_label(c, fine), c["solid"][-1], ancf_label(c, fine, "mixed")
            ax[0].plot([0] + a["loads"], [0] + a["rots"], "-", color=col, label=f"{c['law']}: ANCF {fine} el.")
            ax[0].plot([0] + m["loads"], [0] + m["rots"], "--", color=col,
                       label=f"{c['law']}: ANCF {fine} el., locking: mixed")
            ax[1].plot([0] + m["x"], [0] + m["along"], "--", color=col)
            ax[0].plot([0] + s["loads"], [0] + s["rots"], "o", color=col, mfc="none",
                       label=f"{c['law']}: solid {s['res']}")
            ax[1].plot([0] + a["x"], [0] + a["along"], "-", color=col)
            ax[1].plot([0] + s["x"], [0] + s["along"], "o", color=col, mfc="none")
    for law in LAWS:
        cs = sorted((c for c in cases.values() if c["law"] == law.key), key=lambda c: c["ratio"])
        ratios, col = [c["ratio"] for c in cs], colours[law.key]
        ax[2].loglog(ratios, [100 * ancf_label(c, fine)["err_rot"] for c in cs], "o-", color=col,
                     label=f"{law.key}: rotation")
        ax[2].loglog(ratios, [100 * ancf_label(c, fine)["err_u"] for c in cs], "s--", color=col, mfc="none",
                     label=f"{law.key}: displacement")
        ax[2].loglog(ratios, [100 * ancf_label(c, fine, "vol")["err_rot"] for c in cs], "^:", color=col,
                     label=f"{law.key}: rotation, vol. term degree {VOLUMETRIC_DEGREE}")
        ax[2].loglog(ratios, [100 * ancf_label(c, fine, "mixed")["err_rot"] for c in cs], "D-.", color=col, lw=2,
                     label=f"{law.key}: rotation, locking: mixed")
    ax[2].axhline(1.0, color="k", lw=0.8, ls=":")
    ax[0].set(xlabel="end force [N]", ylabel="end-section rotation about x [deg]",
              title=f"untwist under tension, K/μ = {max(BULK_RATIOS):g}")
    ax[1].set(xlabel="x [m]", ylabel="section rotation [deg]", title=f"along the bar at {FORCE:g} N")
    ax[2].set(xlabel="matrix K/μ", ylabel=f"ANCF {fine} el. error vs solid [%]",
              title="error against the matrix's compressibility")
    for a in ax:
        a.grid(True, lw=0.3)
    ax[2].set_xticks(sorted(BULK_RATIOS), [f"{r:g}" for r in sorted(BULK_RATIOS)])
    ax[2].minorticks_off()
    ax[0].legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
    ax[2].legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.42, -0.14), ncol=2)
    fig.subplots_adjust(left=0.05, right=0.98, top=0.93, bottom=0.33, wspace=0.28)
    fig.savefig(path, dpi=120)
    plt.close(fig)


# --------------------------------------------------------------------------------------------
def write_outputs(out: str, rows: list[dict], doc: str) -> None:
    """CSV (unless it is the input), the docs block and the figure."""
    os.makedirs(os.path.join(out, "figures"), exist_ok=True)
    plot(os.path.join(out, FIGURE), rows)
    write_block(doc, render_block(rows))
