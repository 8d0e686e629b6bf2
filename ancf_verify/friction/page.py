"""The section 'Against a 3D solid with friction' of docs/interface.md and its figures, from the CSVs."""
from __future__ import annotations

import csv
import os

import numpy as np

from ancf_verify.friction.across import across_md
from ancf_verify.friction.refined import refined_md
from ancf_verify.friction.rows import (ANCF, BASE, BEGIN, BODIES, CHECK, DEFAULT_SPACE, END, IFACES, SOLID,
    SPACE, SPACES, ZONE, ancf_columns, ancf_errors, differences, errors, num, read_csv, reference, solid_runs,
    stick_order, variant_space, variant_value, write_csv)


HEAD = "## Against a 3D solid with friction"

TOL = 0.01

SHOW = (10.0, 20.0, 40.0, 100.0, 200.0, 300.0, 400.0)


def pct(x: float, digits: int = 2) -> str:
    return "—" if not np.isfinite(x) else f"{100 * x:+.{digits}f} %"


def apct(x: float, digits: int = 2) -> str:
    return "—" if not np.isfinite(x) else f"{100 * abs(x):.{digits}f} %"


def read_profiles(path: str) -> list:
    if not os.path.exists(path):
        return []
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def checks_md(rows: list, psi: float) -> list:
    """The solid's own checks: FD tangent, mesh, regularisation, slip measure, increments."""
    L = ["| check | soleus | medial | lateral | medial, relative | lateral, relative |",
         "|---|---:|---:|---:|---:|---:|"]
    runs = solid_runs(rows, psi)
    hs = sorted(runs)
    pairs = []
    if len(hs) > 1:
        pairs.append((f"mesh: h {1e3 * hs[1]:.2f} → {1e3 * hs[0]:.2f} mm", runs[hs[1]], runs[hs[0]]))
    variants = sorted({r["variant"] for r in rows if r["model"] == SOLID and r["variant"] != BASE
                       and ZONE not in r["variant"] and num(r["psi_deg"]) == psi})
    for v in variants:
        other = solid_runs(rows, psi, v)
        for h, lv in other.items():
            if h in runs:
                pairs.append((f"{v} (against {BASE}; h {1e3 * h:.2f} mm)", lv, runs[h]))
    for name, a, b in pairs:
        d = differences(a, b)
        n = len(d["loads"])
        L.append(f"| {name} ({n} levels) | " + " | ".join(apct(d[f'{x}_abs'], 3) for x in BODIES) + " | "
                 + " | ".join(apct(d[f'{x}_rel'], 1) for x in BODIES[1:]) + " |")
    return L


def reference_md(rows: list, psi: float) -> list:
    ref = reference(rows, psi)
    L = ["| load [N] | soleus u_x [mm] | medial u_x [µm] | lateral u_x [µm] | mesh change medial / lateral [µm] "
         "| friction on medial from soleus [N] | on lateral from soleus [N] | on medial from lateral [N] "
         "| stick share (mg_sol, lg_sol, lg_mg) |",
         "|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for F in sorted(ref):
        r = ref[F]["row"]
        L.append(f"| {F:g} | {1e3 * ref[F]['soleus'][0]:.5f} | {1e6 * ref[F]['medial'][0]:+.2f} | "
                 f"{1e6 * ref[F]['lateral'][0]:+.2f} | {1e6 * ref[F]['medial'][1]:.2f} / {1e6 * ref[F]['lateral'][1]:.2f} | "
                 + " | ".join(f"{num(r[f'fx_{i}_N']):+.2f}" for i in IFACES) + " | "
                 + ", ".join(f"{num(r[f'stick_{i}']):.2f}" for i in IFACES) + " |")
    return L


def ancf_md(rows: list, psi: float) -> list:
    errs = ancf_errors(rows, psi)
    cols = ancf_columns(rows, psi)
    ref = reference(rows, psi)
    fs100 = friction_on_gastrocnemii(ref[100.0]["row"]) if 100.0 in ref else float("nan")
    L = ["| pressure space | augmentation c | elements | levels reached | soleus, relative | medial, relative "
         "| lateral, relative | medial / u_soleus | lateral / u_soleus | within 1 % | friction on the gastrocnemii "
         "from the soleus at 100 N (solid " + (f"{fs100:.1f}" if np.isfinite(fs100) else "—") + ") [N] |",
         "|---|---|---:|---|---:|---:|---:|---:|---:|---|---:|"]
    for (v, ne) in sorted(cols, key=lambda k: (stick_order(k[0]), k[1])):
        e, col = errs.get((v, ne), {}), cols[(v, ne)]
        reached = max(col["levels"], default=0.0)
        status = f"all {len(ref)}" if not col["failed"] and len(e) == len(ref) else \
            f"to {reached:g} N ({col['failed'].replace('FAILED: ', '').split(' with ')[-1] if col['failed'] else 'partial'})"
        worst = {b: max((e[F][b][0] for F in e), key=abs, default=float("nan")) for b in BODIES}
        worsta = {b: max((e[F][b][1] for F in e), key=abs, default=float("nan")) for b in BODIES}
        ok_rel = all(abs(worst[b]) <= TOL for b in BODIES) and e
        ok_abs = all(abs(worsta[b]) <= TOL for b in BODIES) and abs(worst["soleus"]) <= TOL and e
        verdict = "relative: yes" if ok_rel else ("against u_soleus only" if ok_abs else "no")
        if col["failed"] or len(e) < len(ref):
            verdict += " (not all levels)"
        f100 = friction_on_gastrocnemii(col["levels"][100.0]) if 100.0 in col["levels"] else float("nan")
        L.append(f"| {variant_space(v)} | {variant_value(v)} | {ne} | {status} | {pct(worst['soleus'])} | "
                 f"{pct(worst['medial'], 0)} | {pct(worst['lateral'], 0)} | {pct(worsta['medial'])} | "
                 f"{pct(worsta['lateral'])} | {verdict} | " + (f"{f100:.1f}" if np.isfinite(f100) else "—") + " |")
    return L


def friction_on_gastrocnemii(r: dict) -> float:
    """The x-friction on the two gastrocnemii from the soleus [N] of a CSV row."""
    return num(r["fx_mg_sol_N"]) + num(r["fx_lg_sol_N"])


def worst(e: dict) -> tuple:
    """Signed worst over the levels of a column's errors: (relative, against u_soleus) per body."""
    return ({b: max((e[F][b][0] for F in e), key=abs, default=float("nan")) for b in BODIES},
            {b: max((e[F][b][1] for F in e), key=abs, default=float("nan")) for b in BODIES})


def zone_md(rows: list, psi: float) -> list:
    """The free-zone diagnostic: each ANCF column without friction below x = zone against the
    solid run with the same zone (coarse mesh), beside the same column with friction everywhere
    against the plain solid on that mesh."""
    zcols = ancf_columns(rows, psi, zone=True)
    if not zcols:
        return []
    plain = ancf_columns(rows, psi)
    L = ["| augmentation c | elements | friction near the clamp | levels | solid | soleus, relative "
         "| medial / u_soleus | lateral / u_soleus | friction on the gastrocnemii from the soleus at 100 N, "
         "solid / ANCF [N] |", "|---|---:|---|---:|---|---:|---:|---:|---:|"]
    for (v, ne) in sorted(zcols, key=lambda k: (stick_order(k[0]), k[1])):
        base, zone = v.split(ZONE)
        for label, col, variant in (("everywhere", plain.get((base, ne)), BASE),
                                    (f"none below x = {zone}", zcols[(v, ne)], f"{BASE}{ZONE}{zone}")):
            runs = solid_runs(rows, psi, variant)
            h = max(runs, default=None)
            if col is None or h is None:
                continue
            e = errors(col["levels"], runs[h])
            rel, ab = worst(e)
            f = [num(r["fx_mg_sol_N"]) + num(r["fx_lg_sol_N"]) for r in (runs[h].get(100.0), col["levels"].get(100.0))
                 if r is not None]
            reached = f"{len(e)}" + ("" if not col["failed"] else f" (to {max(col['levels'], default=0):g} N)")
            L.append(f"| {variant_value(base)} | {ne} | {label} | {reached} | {variant}, h {1e3 * h:.2f} mm | "
                     f"{pct(rel['soleus'])} | {pct(ab['medial'])} | {pct(ab['lateral'])} | "
                     + (" / ".join(f"{x:.1f}" for x in f) if len(f) == 2 else "—") + " |")
    return L


def per_load_md(rows: list, psi: float, key) -> list:
    ref = reference(rows, psi)
    col = ancf_columns(rows, psi).get(key, {"levels": {}})["levels"]
    L = ["| load [N] | soleus solid / ANCF [mm] | medial solid / ANCF [µm] | lateral solid / ANCF [µm] "
         "| friction on the gastrocnemii from the soleus, solid / ANCF [N] |", "|---:|---:|---:|---:|---:|"]
    for F in sorted(ref):
        r, a = ref[F]["row"], col.get(F)
        fs = num(r["fx_mg_sol_N"]) + num(r["fx_lg_sol_N"])
        if a is None:
            L.append(f"| {F:g} | {1e3 * ref[F]['soleus'][0]:.4f} / — | {1e6 * ref[F]['medial'][0]:+.1f} / — | "
                     f"{1e6 * ref[F]['lateral'][0]:+.1f} / — | {fs:.1f} / — |")
            continue
        fa = num(a["fx_mg_sol_N"]) + num(a["fx_lg_sol_N"])
        L.append(f"| {F:g} | {1e3 * ref[F]['soleus'][0]:.4f} / {1e3 * num(a['soleus_ux_m']):.4f} | "
                 f"{1e6 * ref[F]['medial'][0]:+.1f} / {1e6 * num(a['medial_ux_m']):+.1f} | "
                 f"{1e6 * ref[F]['lateral'][0]:+.1f} / {1e6 * num(a['lateral_ux_m']):+.1f} | {fs:.1f} / {fa:.1f} |")
    return L

NEAR = 10e-3     # [m] the clamp zone of the profile table


def profiles_md(prof: list) -> list:
    """Per interface: compressive and tensile normal force, friction force, within NEAR of the
    clamp and beyond."""
    if not prof:
        return []

    def order(k):
        res = k[2].split()
        return (k[0] != SOLID, k[1].split(",")[0], SPACE in k[1], num(res[0]) if k[0] == ANCF else -num(res[1]), k[3])
    keys = sorted({(p["model"], p["variant"], p["resolution"], num(p["load_N"])) for p in prof}, key=order)
    L = ["| model | variant | load [N] | " + " | ".join(f"{i}: Q⁺ / Q⁻ / F_x [N], x < {NEAR * 1e3:g} mm · beyond"
                                                    for i in IFACES) + " |",
         "|---|---|---:|" + "---:|" * len(IFACES)]
    for k in keys:
        cells = []
        for i in IFACES:
            pr = [p for p in prof if (p["model"], p["variant"], p["resolution"], num(p["load_N"])) == k
                  and p["interface"] == i]
            part = []
            for near in (True, False):
                sel = [p for p in pr if (num(p["x_lo_m"]) < NEAR - 1e-12) == near]
                w = [num(p["x_hi_m"]) - num(p["x_lo_m"]) for p in sel]
                q = [sum(num(p[c]) * d for p, d in zip(sel, w)) for c in ("q_plus_N_per_m", "q_minus_N_per_m",
                                                                          "fx_N_per_m")]
                part.append(f"{q[0]:.0f} / {q[1]:.0f} / {q[2]:+.1f}")
            cells.append(" · ".join(part))
        L.append(f"| {k[0]} {k[2]} | {k[1]} | {k[3]:g} | " + " | ".join(cells) + " |")
    return L


def spaces_keys(keys: dict) -> str:
    """A SPACES entry as the contact keys a user writes: 'curve_points: 3, projection: {...}'."""
    return ", ".join(f"{k}: " + ("{" + ", ".join(f"{a}: {b}" for a, b in v.items()) + "}" if isinstance(v, dict) else f"{v}")
                     for k, v in keys.items())


def fd_md(rows: list) -> list:
    L = []
    for r in rows:
        if r["model"] == CHECK:
            L.append(f"* {r['variant']}: {num(r['value']):.1e} ({r['note']}).")
    return L


def section(rows: list, prof: list, meta: dict, notes: str = "", across: list | None = None,
            refined_notes: str = "") -> str:
    """The whole section (from its heading to the end marker's line, exclusive)."""
    psis = sorted({num(r["psi_deg"]) for r in rows if r["model"] == SOLID}, key=lambda p: -p)
    mus = sorted({num(r["mu"]) for r in rows if r["model"] == SOLID})
    L = [HEAD, "", BEGIN, ""]
    gen = ("Generated by `scripts/verify_solid_friction.py` (`make verify-solid-friction`) from "
           "`docs/solid_friction.csv` and `docs/solid_friction_profiles.csv`, with the discussion from "
           "`docs/solid_friction.notes`; `--replot` redoes this section and the figure from them")
    if meta.get("argv") is not None:
        gen += f" (last invocation: `{meta['argv']}`" + (f", {meta['total'] / 60:.0f} min)" if meta.get("total") else ")")
    L += [gen + ".", ""]
    L += ["Issue 27, verification point 3: the three-subtendon tendon of `docs/solid_contact.md` (dolfinx P2 "
          "tetrahedra, three bodies, mortar-type weighted gaps held at zero by exact multipliers, clamped roots, "
          "uniform dead traction on the soleus end face) with the beam model's Coulomb law at μ = "
          + ", ".join(f"{m:g}" for m in mus) + " on the sliding normal law (`ancf_verify/friction/model.py`): every "
          "slave Gauss point keeps its reference partner on the master, the incremental return mapping "
          "σ = proj_{|σ| ≤ μ p⁺}(P(σ₀ + k (d − d₀))) runs from the last accepted increment, P projects on the "
          "master's tangent plane at the current closest point, p is the solid's contact pressure at the point "
          "(the weighted-gap multipliers' nodal pressures interpolated with their hats), stick is regularised by "
          "k = 100 μ_max/h (Pa/m); consistent unsymmetric tangent, MUMPS LU; Table 1's 13 load levels, every "
          "converged increment accepted into the history (as ancf-solve does).  The beams: "
          "`verify_solid_contact.tendon_config` (`fix: clamped`, `traction_force` on the soleus' last node, "
          "2 axial points) with `contact.tangential: {law: coulomb, friction: 0.3}` (tangential multipliers, "
          "exact stick: `docs/interface.md`, first sections), at the default augmentation c (1) and at c = 10 and "
          "0.1 (c only steers the semi-smooth Newton iteration; the answer must not depend on it); in the default "
          "pressure (and tangential multiplier) space, linear along × linear across (friction's default since "
          "2026-12-07: \"Friction's pressure along the beam\"; the quadratic pressure's rows before are in the "
          "history of docs/solid_friction.csv), and in richer ones (the "
          "first two: those of `docs/solid_contact.md`): " + "; ".join(f"{n}: `{spaces_keys(k)}`" for n, k in SPACES.items())
          + " (`--ancf-spaces`).  Quantities: u_x at the end-section centroids (the soleus' is its "
          "elongation; the gastrocnemii move by tens of µm).", ""]
    for psi in psis:
        L += [f"### ψ = {psi:g}°", "", "**The solid's own checks.**  Largest change over the load levels, "
              "against the soleus elongation (|Δu|/u_soleus) and relative to the body's own displacement "
              "(|Δu|/|u|; the gastrocnemius displacements pass through zero, where this ratio is unbounded):", ""]
        L += checks_md(rows, psi) + [""]
        L += ["**Solid reference** (the finest mesh; the friction forces are the x-forces on the body named "
              "first):", ""] + reference_md(rows, psi) + [""]
        L += ["**ANCF against the solid.**  Worst error over the levels reached (signed); the target is 1 % "
              "for the soleus and for each gastrocnemius, relative or against the soleus elongation:", ""]
        L += ancf_md(rows, psi) + [""]
        cols = ancf_columns(rows, psi)
        full = [k for k in sorted(cols, key=lambda k: (stick_order(k[0]), k[1])) if not cols[k]["failed"]
                and (variant_space(k[0]) == DEFAULT_SPACE or variant_value(k[0]) == "default")]
        for key in full or sorted(cols, key=lambda k: (-len(cols[k]["levels"]), k[1]))[:1]:
            L += [f"Per level, {key[0]}, {key[1]} elements:", ""] + per_load_md(rows, psi, key) + [""]
        zm = zone_md(rows, psi)
        if zm:
            L += ["**Diagnostic: no friction near the clamp.**  The same columns with the Coulomb law switched off "
                  "below the given x: for the beams, no friction carried by the tangential multiplier functions "
                  "whose support is centred there (their bound set to zero), for the solid at its slave points there, each model against the "
                  "solid run with the same change on the coarse mesh (h = 2.00 mm; the first row of each pair: "
                  "friction everywhere, against the plain solid on that mesh).  Worst error over the levels:", ""]
            L += zm + [""]
        rm = refined_md(rows, psi)
        if rm:
            L += ["#### The friction reference, locally refined at the soleus–medial interface (issue 41)", ""]
            L += rm + ([refined_notes.rstrip(), ""] if refined_notes else [])
    if prof:
        L += ["### Where the friction comes from", "",
              "Normal force carried in compression (Q⁺ = ∫ p⁺ dA, Coulomb's bound is μ Q⁺) and in tension "
              "(Q⁻ = ∫ p⁻ dA) on each interface, and the friction force F_x on the body named first, ψ = 45°, "
              "within 10 mm of the clamped roots and beyond (`docs/solid_friction_profiles.csv`, 2.5 mm bins):", ""]
        L += profiles_md(prof) + [""]
    if across:
        F = num(across[0]["load_N"])
        L += [f"**Across the interface** (`scripts/solid_friction_across.py`, `docs/solid_friction_across.csv`): "
              f"the mean compressive / tensile pressure Σ w p⁺ / Σ w and Σ w p⁻ / Σ w [kPa] over the contact "
              f"points within 3.5 mm of x at {F:g} N (μ Σ w p⁺ / Σ w is the mean friction bound per area); the "
              "distributions across the strip are drawn in the second figure (s: arc length along the interface "
              "curve from the triple point where the three subtendons meet):", ""]
        L += across_md(across) + ["", "![pressure across the interfaces](figures/solid_friction_across.png)", ""]
    L += ["![solid vs ANCF with friction](figures/solid_friction.png)", ""]
    fd = fd_md(rows)
    if fd:
        L += ["**The friction tangent against finite differences** (|FD − J d|/|J d|; the error falls as ε² "
              "while no point changes between stick and slip):", ""] + fd + [""]
    if notes:
        L += [notes.rstrip(), ""]
    L += [END]
    return "\n".join(L) + "\n"


def write_page(path: str, text: str) -> None:
    """Replace the section (its heading through the end marker) in docs/interface.md, or append
    it; the page is created with a title when it does not exist."""
    page = open(path, encoding="utf-8").read() if os.path.exists(path) else \
        "# Interfaces between subtendons: shear, friction, displacement control\n\n"
    if HEAD in page and END in page:
        a = page.index(HEAD)
        b = page.index(END) + len(END)
        page = page[:a] + text.rstrip("\n") + page[b:]
    else:
        page = page.rstrip("\n") + "\n\n" + text
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(page)


def plot(path: str, rows: list, prof: list, psi: float = 45.0) -> None:
    """(a) soleus elongation, (b) gastrocnemius end displacements, (c) friction on the
    gastrocnemii from the soleus, against the load; (d) the compressive normal force along x."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(2, 2, figsize=(11, 8.2))
    runs = solid_runs(rows, psi)
    ref = reference(rows, psi)
    if not ref:
        return
    for i, h in enumerate(sorted(runs, reverse=True)):
        lv = runs[h]
        Fs = np.array(sorted(lv))
        sty = dict(color="k", lw=2.2 - 0.8 * i, ls="-" if i else "--", label=f"solid h {1e3 * h:.2f} mm")
        ax[0, 0].plot(Fs, [100 * (num(lv[f]["soleus_ux_m"]) / ref[f]["soleus"][0] - 1) if f in ref else np.nan
                           for f in Fs], **sty)
        ax[0, 1].plot(Fs, [1e6 * num(lv[f]["medial_ux_m"]) for f in Fs], **sty)
        ax[0, 1].plot(Fs, [1e6 * num(lv[f]["lateral_ux_m"]) for f in Fs], **(sty | {"label": None, "color": "0.5"}))
        ax[1, 0].plot(Fs, [num(lv[f]["fx_mg_sol_N"]) + num(lv[f]["fx_lg_sol_N"]) for f in Fs], **sty)
    cols = ancf_columns(rows, psi)
    colors = {4: "C0", 8: "C1", 16: "C2"}
    marks = {}
    for (v, ne), col in sorted(cols.items()):
        lv = col["levels"]
        if not lv:
            continue
        mk = marks.setdefault(v, "osv^"[len(marks) % 4])
        Fa = np.array(sorted(lv))
        sty = dict(color=colors.get(ne, "C3"), marker=mk, ms=4, lw=0.9, label=f"ANCF {ne} el., {v}")
        ax[0, 0].plot(Fa, [100 * (num(lv[f]["soleus_ux_m"]) / ref[f]["soleus"][0] - 1) if f in ref else np.nan
                           for f in Fa], **sty)
        ax[0, 1].plot(Fa, [1e6 * num(lv[f]["medial_ux_m"]) for f in Fa], **sty)
        ax[0, 1].plot(Fa, [1e6 * num(lv[f]["lateral_ux_m"]) for f in Fa], **(sty | {"label": None, "ls": ":"}))
        ax[1, 0].plot(Fa, [num(lv[f]["fx_mg_sol_N"]) + num(lv[f]["fx_lg_sol_N"]) for f in Fa], **sty)
    ax[0, 0].axhspan(-1, 1, color="0.9", zorder=0)
    ax[0, 0].set_ylabel("soleus elongation: (u − u_ref)/u_ref [%]")
    ax[0, 1].set_ylabel("end-centroid u_x [µm] (medial solid, lateral dotted/grey)")
    ax[1, 0].set_ylabel("friction on the gastrocnemii from the soleus [N]")
    for a in (ax[0, 0], ax[0, 1], ax[1, 0]):
        a.set_xlabel("soleus load [N]")
        a.grid(True, lw=0.3)
    ax[0, 0].legend(fontsize=7, ncol=1)
    plot_profiles(ax[1, 1], prof)
    fig.suptitle(f"Three subtendons with Coulomb friction (ψ = {psi:g}°): 3D solid against ANCF; grey band ±1 %",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.96))
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_profiles(ax, prof: list) -> None:
    """Cumulative compressive normal force ∫_0^x q⁺ over the three interfaces at the highest
    profiled load, per model (dashed: frictionless)."""
    if not prof:
        return
    top = max(num(p["load_N"]) for p in prof)
    keys = sorted({(p["model"], p["variant"], p["resolution"]) for p in prof if num(p["load_N"]) == top})
    colors = {"4 el.": "C0", "8 el.": "C1", "16 el.": "C2"}
    for k in keys:
        pr = [p for p in prof if (p["model"], p["variant"], p["resolution"]) == k and num(p["load_N"]) == top]
        x = sorted({num(p["x_lo_m"]) for p in pr})
        q = [sum(num(p["q_plus_N_per_m"]) * (num(p["x_hi_m"]) - num(p["x_lo_m"])) for p in pr
                 if num(p["x_lo_m"]) == xx) for xx in x]
        sty = {"color": "k" if k[0] == SOLID else colors.get(k[2], "C3"), "lw": 2 if k[0] == SOLID else 1,
               "ls": "--" if k[1] == "mu 0" else "-", "marker": None if k[0] == SOLID else "."}
        ax.plot(1e3 * (np.array(x) + 1.25e-3), np.cumsum(q), label=f"{k[0]} {k[2]}, {k[1]}", **sty)
    ax.set_xlabel("x [mm] (clamped roots at 0)")
    ax.set_ylabel(f"∫₀ˣ Q⁺ over the three interfaces at {top:g} N [N]")
    ax.set_yscale("symlog", linthresh=10)
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=6.5)


def finish(paths, rows: list, meta: dict) -> None:
    """CSV, figure and the page section from the rows (and the profiles CSV)."""
    write_csv(paths.csv, rows)
    rows = read_csv(paths.csv)
    prof = read_profiles(os.path.join(os.path.dirname(paths.csv), "solid_friction_profiles.csv"))
    os.makedirs(os.path.dirname(paths.png), exist_ok=True)
    plot(paths.png, rows, prof)
    text = {}
    for key in ("", "_refined"):
        notes = os.path.join(os.path.dirname(paths.csv), f"solid_friction{key}.notes")
        text[key] = open(notes, encoding="utf-8").read() if os.path.exists(notes) else ""
    write_page(paths.md, section(rows, prof, meta, text[""], read_profiles(across_csv(paths.csv)), text["_refined"]))


def across_csv(csv_path: str) -> str:
    """docs/solid_friction_across.csv beside docs/solid_friction.csv."""
    return os.path.join(os.path.dirname(csv_path), "solid_friction_across.csv")
