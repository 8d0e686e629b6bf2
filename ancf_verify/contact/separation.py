"""How much the soleus gains by separating from its neighbours: the unilateral against the sliding
soleus elongation per solid mesh, per beam element count, and on plane against clamped roots
(docs/solid_contact.md, "The unilateral 10 N question on plane roots"), from the CSVs alone
(docs/solid_contact_plane.csv and docs/solid_contact.csv)."""
from __future__ import annotations

import re

import numpy as np

from ancf_verify.contact.rows import ANCF, PENALTY, REF, SOLID, ancf_errors, num

#: the heading of the page's section
SECTION = "## The unilateral 10 N question on plane roots"


def elongations(rows: list, law: str, psi: float = 45.0) -> dict:
    """(label, load [N]) → soleus u_x [m] of one law: labels ``h 2.00 mm`` (solid meshes),
    ``reference`` (the solid reference) and ``4 el.`` (beams)."""
    out = {}
    for r in rows:
        if r["law"] != law or r["model"] not in (SOLID, REF, ANCF) or r["load_N"] in ("", None) \
                or num(r["psi_deg"]) != psi:
            continue
        label = "reference" if r["model"] == REF else r["resolution"]
        out[(label, num(r["load_N"]))] = num(r["soleus_ux_m"])
    return out


def gains(rows: list, psi: float = 45.0) -> dict:
    """(label, load) → (u sliding, u unilateral, gain = (u_uni − u_sli)/u_sli) where both laws exist."""
    s, u = elongations(rows, "sliding", psi), elongations(rows, "unilateral", psi)
    return {k: (s[k], u[k], (u[k] - s[k]) / s[k]) for k in s if k in u}


def solid_loads(rows: list, psi: float = 45.0) -> list:
    """The solid's load levels [N] at which both laws have a reference."""
    return sorted({k[1] for k in gains(rows, psi) if k[0] == "reference"})


def meshes(rows: list, psi: float = 45.0) -> list:
    """The solid meshes (labels, coarse to fine) on which both laws were solved."""
    hs = {r["resolution"]: num(r["h_m"]) for r in rows if r["model"] == SOLID and r["load_N"] not in ("", None)}
    both = {k[0] for k in gains(rows, psi)}
    return sorted((m for m in hs if m in both), key=lambda m: -hs[m])


def pct(x: float, digits: int = 2) -> str:
    return "—" if not np.isfinite(x) else f"{100 * x:+.{digits}f} %"


def points(x: float) -> str:
    return "—" if not np.isfinite(x) else f"{100 * x:+.2f}"


def solid_table(plane: list, clamped: list) -> list:
    """Markdown lines: the solid's sliding and unilateral soleus elongation and the gain, per roots,
    mesh and load."""
    L = ["| roots | h [mm] | load [N] | sliding [mm] | unilateral [mm] | gain |", "|---|---:|---:|---:|---:|---:|"]
    for name, rows in (("plane", plane), ("clamped", clamped)):
        g = gains(rows)
        for m in meshes(rows):
            for F in solid_loads(plane):
                if (m, F) in g:
                    us, uu, gain = g[(m, F)]
                    L.append(f"| {name} | {m[2:-3]} | {F:g} | {1e3 * us:.5f} | {1e3 * uu:.5f} | {pct(gain)} |")
    return L


def convergence_table(plane: list, clamped: list) -> list:
    """Markdown lines, per roots and load: the gain on each mesh, its change between the two finest
    (points), and each law's soleus elongation change between them ((u_fine − u_coarse)/u_fine)."""
    L = []
    for name, rows in (("plane", plane), ("clamped", clamped)):
        g, ms = gains(rows), meshes(rows)
        if not L:
            L = ["| roots | load [N] | " + " | ".join(f"gain {m}" for m in ms) + " | change [points] | "
                 "sliding u_x change | unilateral u_x change |", "|---|---:|" + "---:|" * (len(ms) + 3)]
        for F in solid_loads(plane):
            (sc, uc, gc), (sf, uf, gf) = g[(ms[-2], F)], g[(ms[-1], F)]
            L.append(f"| {name} | {F:g} | " + " | ".join(pct(g[(m, F)][2]) for m in ms)
                     + f" | {points(gf - gc)} | {pct((sf - sc) / sf, 3)} | {pct((uf - uc) / uf, 3)} |")
    return L


def roots_table(plane: list, clamped: list) -> list:
    """Markdown lines, per load on the finest common mesh: what the plane roots change in each law's
    soleus elongation ((u_plane − u_clamped)/u_clamped) and in the gain (points)."""
    fine = [m for m in meshes(plane) if m in meshes(clamped)][-1]
    gp, gc = gains(plane), gains(clamped)
    L = [f"| load [N] | sliding: plane against clamped | unilateral: plane against clamped | gain clamped | "
         f"gain plane | plane − clamped [points] |", "|---:|---:|---:|---:|---:|---:|"]
    for F in solid_loads(plane):
        (sc, uc, g0), (sp, up, g1) = gc[(fine, F)], gp[(fine, F)]
        L.append(f"| {F:g} | {pct((sp - sc) / sc, 3)} | {pct((up - uc) / uc, 3)} | {pct(g0)} | {pct(g1)} | "
                 f"{points(g1 - g0)} |")
    return L


def beams_table(plane: list) -> list:
    """Markdown lines: the beams (plane roots) per element count and load: their elongations and
    gain, the gain's difference to the solid reference's (points) and each law's error against it."""
    g = gains(plane)
    errs = {(k[1], k[2]): e for k, e in ancf_errors(plane).items() if num(k[0]) == 45.0}
    L = ["| elements | load [N] | sliding [mm] | unilateral [mm] | gain | gain − solid's [points] | "
         "error sliding | error unilateral |", "|---:|---:|---:|---:|---:|---:|---:|---:|"]
    els = sorted({k[1] for k in errs})
    for ne in els:
        for F in solid_loads(plane):
            if (f"{ne} el.", F) not in g:
                continue
            us, uu, gain = g[(f"{ne} el.", F)]
            es, eu = (errs.get((law, ne), {}).get(F, np.nan) for law in ("sliding", "unilateral"))
            L.append(f"| {ne} | {F:g} | {1e3 * us:.5f} | {1e3 * uu:.5f} | {pct(gain)} | "
                     f"{points(gain - g[('reference', F)][2])} | {pct(es, 3)} | {pct(eu, 3)} |")
    return L


def penalty_table(plane: list, psi: float = 45.0) -> list:
    """Markdown lines: the solid with a pure penalty ε = κ μ/h instead of exact multipliers (rows of
    model PENALTY, one mesh), per κ (stiff to soft) and load: each law's soleus elongation, the
    gain and its difference to the exact multipliers' (same mesh), and each law against them; a
    failed run shows —."""
    pen = [r for r in plane if r["model"] == PENALTY and num(r["psi_deg"]) == psi]
    runs = sorted({r["resolution"] for r in pen}, key=lambda m: -float(m.split("eps = ")[1].split()[0]))
    L = ["| κ | load [N] | sliding [mm] | unilateral [mm] | gain | gain − exact [points] | "
         "sliding against exact | unilateral against exact |", "|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for res in runs:
        mesh = res.split(",")[0]
        u = {(r["law"], num(r["load_N"])): num(r["soleus_ux_m"]) for r in pen
             if r["resolution"] == res and r["load_N"] not in ("", None)}
        exact = {law: elongations(plane, law, psi) for law in ("sliding", "unilateral")}
        for F in solid_loads(plane, psi):
            us, uu = u.get(("sliding", F), np.nan), u.get(("unilateral", F), np.nan)
            es, eu = exact["sliding"][(mesh, F)], exact["unilateral"][(mesh, F)]
            mm = lambda x: "—" if not np.isfinite(x) else f"{1e3 * x:.5f}"
            gain = (uu - us) / us
            L.append(f"| {res.split('eps = ')[1].split()[0]} | {F:g} | {mm(us)} | {mm(uu)} | {pct(gain)} | "
                     f"{points(gain - (eu - es) / es)} | {pct((us - es) / es, 3)} | {pct((uu - eu) / eu, 3)} |")
    return L


def section_tables(plane: list, clamped: list) -> list:
    """The section's five tables (lists of markdown lines), in the page's order."""
    return [solid_table(plane, clamped), convergence_table(plane, clamped), roots_table(plane, clamped),
            penalty_table(plane), beams_table(plane)]


def stated(text: str) -> list:
    """The numbers a paragraph states, as (value as a fraction, half a unit of its last digit,
    signed): percentages "+2.02 %" and point differences "+0.61 points"; an unsigned number is a
    magnitude ("by 0.20 points")."""
    out = []
    for m in re.finditer(r"(?<![\w.])([+−-]?\d+(?:\.\d+)?)\s*(%|points?\b)", text):
        s = m.group(1).replace("−", "-")
        digits = len(s.split(".")[1]) if "." in s else 0
        out.append((float(s) / 100, 0.5 * 10.0 ** -digits / 100, s[0] in "+-"))
    return out


def table_values(lines: list) -> list:
    """Every percentage or point number in table lines, as fractions."""
    vals = []
    for ln in lines[2:]:
        for cell in ln.strip("|").split("|"):
            c = cell.strip().replace(" %", "")
            if re.fullmatch(r"[+-]\d+\.\d+", c):
                vals.append(float(c) / 100)
    return vals
