"""The generated block of docs/fibres.md for the soft-matrix bar."""
from __future__ import annotations

import math

from ancf_verify.fibres.cases import LENGTH, SAMPLE_SCALE, STATIONS, STEPS, TWIST
from ancf_verify.fibres.report import replace_block as fibres_replace_block, write_block
from ancf_verify.soft_matrix.cases import BLOCK, BULK_RATIO, FORCE, MATERIAL, WRITER
from ancf_verify.soft_matrix.solid import evaluate


def fmt_e(r: dict) -> str:
    return f"{100 * r['E'][0]:+.2f} … {100 * r['E'][1]:+.2f}" if "E" in r else ""


def fmt_mm(x: float) -> str:
    return "" if math.isnan(x) else f"{1e3 * x:.4f}"


def render_block(rows: list[dict]) -> str:
    """The docs block: every run against the solid's reference, then the rotation along x."""
    ev = evaluate(rows)
    mesh = ", ".join(r["res"].removeprefix("h ").removesuffix(" mm") for r in ev["solid"])
    m = MATERIAL
    lines = [f"Bar of the check above (ellipse 12 x 8 mm, L = {1e3 * LENGTH:g} mm, ψ = {TWIST:g}°, root "
             f"clamped, helical fibres); GOH set alex: μ = {m['mu'] / 1e3:g} kPa, k1 = {m['k1'] / 1e6:g} MPa, "
             f"k2 = {m['k2']:g}, κ = {m['kappa']:g}, K = {BULK_RATIO:g} μ; end force {FORCE:g} N in "
             f"{len(STEPS)} levels. Solid: P2 tetrahedra, h = {mesh} mm, uniform dead end traction; reference: "
             f"u {ev['how']}; rotation {ev['how_rot']} (uncertainty: distance from the finest mesh, "
             f"u {100 * ev['unc_u']:.2f} %, rotation {100 * ev['unc_rot']:.2f} %, face mean "
             f"{100 * ev['unc_mean']:.2f} %; face mean: {ev['how_mean']}). u_x: the end-section centroid's; face mean: "
             "∫ u_x dA / A over the end face (ANCF: Σ m̄_k Δq_k); end face u_x sampled at the section rule's points x "
             f"{SAMPLE_SCALE:g}: span max − min, and the constant of its weighted least-squares fit by the 3363 "
             "section monomials 1, y, z, y²/2, z²/2, yz (ANCF: r_x itself). Ē = I4 − 1 over the middle half "
             "L/4 < X < 3L/4.", "",
             "| model | resolution | Newton its | u_x [mm] | u_x / solid − 1 | \\|u − u_ref\\| / \\|u_ref\\| | "
             "face-mean u_x [mm] | / solid − 1 | rotation [°] | rotation / solid − 1 | Ē range, middle half [%] | "
             "end face u_x: span [mm] | quadratic-fit constant [mm] |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
             f"| solid, reference | | | {1e3 * ev['ref_u'][0]:.4f} | | | {1e3 * ev['ref_mean']:.4f} | | "
             f"{ev['ref_rot']:+.3f} | | | | |"]
    for r in ev["solid"] + sorted(ev["beam"], key=lambda r: (r["model"], r["dofs"])):
        lines.append(f"| {r['model']} | {r['res']} | {r['its']} | {1e3 * r['u'][0]:.4f} | {100 * r['du']:+.2f} % | "
                     f"{100 * r['err_u']:.2f} % | {1e3 * r['ux_mean']:.4f} | {100 * r['dmean']:+.2f} % | "
                     f"{r['rot']:+.3f} | {100 * r['drot']:+.2f} % | {fmt_e(r)} | {fmt_mm(r['span'])} | {fmt_mm(r['fit0'])} |")
    fine = max(ev["beam"], key=lambda r: r["dofs"])["res"]
    cols = sorted((r for r in ev["beam"] if r["res"] == fine), key=lambda r: r["model"]) + ev["solid"][-1:]
    lines += ["", f"Section rotation [°] along the bar at {FORCE:g} N (ANCF {fine}; finest solid):", "",
              "| x/L | " + " | ".join(r["model"].removeprefix("ANCF, ") for r in cols) + " |",
              "|---:|" + "---:|" * len(cols)]
    for i in range(STATIONS):
        lines.append(f"| {(i + 1) / STATIONS:.3f} | " + " | ".join(f"{r['along'][i]:+.3f}" for r in cols) + " |")
    cols = cols[:-1]
    lines += ["", f"Ē range [%] over each element's Gauss points at {FORCE:g} N (ANCF {fine}):", "",
              "| element centre x/L | " + " | ".join(r["model"].removeprefix("ANCF, ") for r in cols) + " |",
              "|---:|" + "---:|" * len(cols)]
    n = len(cols[0]["strain"])
    for i in range(n):
        lines.append(f"| {(i + 0.5) / n:.4f} | " + " | ".join(
            f"{100 * r['strain'][i][0]:+.2f} … {100 * r['strain'][i][1]:+.2f}" for r in cols) + " |")
    return "\n".join(lines)


def replace_block(text: str, block: str) -> str:
    """``text`` with the marked block ``solid_soft_matrix`` replaced by ``block``."""
    return fibres_replace_block(text, block, BLOCK, WRITER)


def write_doc(doc: str, rows: list[dict]) -> None:
    write_block(doc, render_block(rows), BLOCK, WRITER)
