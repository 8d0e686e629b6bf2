"""The friction reference on locally refined meshes (issue 41, item 4): the solid runs refined
around one interface (contact.mesh.LocalSize; resolution "h 2.00 mm, 0.70 mm at mg_sol"), their
convergence and the beams against the finest, as tables of docs/interface.md."""
from __future__ import annotations

import numpy as np

from ancf_verify.friction.rows import BASE, BODIES, IFACES, LOCAL, SOLID, ancf_columns, num, solid_runs

#: the change between the two finest meshes the reference must stay within
TARGET = 0.02

SHOW = (10.0, 40.0, 100.0, 200.0, 400.0)

JUDGED = (10.0, 100.0, 400.0)          # the levels the beams are judged at

PLAUSIBLE = (0.5, 4.0)                 # observed orders whose Richardson value the tables show

QUANTITIES = [(f"fx_{i}_N", f"friction {i} [N]", 1.0, "{:+.3f}") for i in IFACES] + \
             [("soleus_ux_m", "soleus u_x [mm]", 1e3, "{:.5f}")]


def interface_size(resolution: str) -> float:
    """The local size [m] of a refined run's resolution ("h 2.00 mm, 0.70 mm at mg_sol"), NaN
    for a uniform mesh."""
    if LOCAL not in resolution:
        return float("nan")
    return 1e-3 * num(resolution.split(LOCAL)[0].split(",")[-1])


def refined_runs(rows: list, psi: float, variant: str = BASE) -> dict:
    """{interface size [m]: {load: row}} of the locally refined solid runs (one bulk size)."""
    out = {}
    for r in rows:
        if (r["model"] == SOLID and r["variant"] == variant and num(r["psi_deg"]) == psi and r["load_N"]
                and LOCAL in r["resolution"]):
            out.setdefault(interface_size(r["resolution"]), {})[num(r["load_N"])] = r
    return out


def meshes(rows: list, psi: float) -> list:
    """[(label, size at the interface [m], {load: row})], coarse to fine: the uniform meshes,
    then the locally refined ones."""
    uni = solid_runs(rows, psi)
    loc = refined_runs(rows, psi)
    out = [(f"h {1e3 * h:.2f} mm", h, uni[h]) for h in sorted(uni, reverse=True)]
    out += [(next(iter(loc[h].values()))["resolution"], h, loc[h]) for h in sorted(loc, reverse=True)]
    return out


def finest_two(rows: list, psi: float, load: float) -> list:
    """The two finest locally refined runs that reached ``load`` [(size, row)], coarse first."""
    loc = refined_runs(rows, psi)
    have = sorted((h for h in loc if load in loc[h]), reverse=True)
    return [(h, loc[h][load]) for h in have[-2:]]


def richardson(f: list, h: list) -> tuple:
    """Observed order p and the extrapolated value of three values f at sizes h (coarse to fine),
    f ≈ f∞ + C h^p; (NaN, NaN) unless the two changes have one sign and shrink."""
    d1, d2 = f[1] - f[0], f[2] - f[1]
    if d1 == 0 or d2 == 0 or d1 * d2 < 0 or abs(d2) >= abs(d1):
        return float("nan"), float("nan")
    ratio = d1 / d2

    def g(p):   # (h0^p - h1^p) / (h1^p - h2^p) - ratio, increasing in p for h0 > h1 > h2
        return (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p) - ratio
    lo, hi = 1e-3, 20.0
    if g(lo) > 0 or g(hi) < 0:
        return float("nan"), float("nan")
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if g(mid) < 0 else (lo, mid)
    p = 0.5 * (lo + hi)
    return p, f[2] + d2 * h[2] ** p / (h[1] ** p - h[2] ** p)


def convergence(rows: list, psi: float, column: str, load: float) -> dict:
    """The change of ``column`` between the two finest refined runs at ``load`` (relative; for
    the gastrocnemius ends against the soleus elongation) and, with three refined runs, the
    observed order and the Richardson value."""
    two = finest_two(rows, psi, load)
    out = {"pair": [h for h, _ in two], "change": float("nan"), "p": float("nan"), "limit": float("nan")}
    if len(two) < 2:
        return out
    (_, a), (_, b) = two
    scale = abs(num(b["soleus_ux_m"])) if column in ("medial_ux_m", "lateral_ux_m") else abs(num(b[column]))
    out["change"] = (num(b[column]) - num(a[column])) / scale
    loc = refined_runs(rows, psi)
    have = sorted((h for h in loc if load in loc[h]), reverse=True)
    if len(have) >= 3:
        hs = have[-3:]
        out["p"], out["limit"] = richardson([num(loc[h][load][column]) for h in hs], hs)
    return out


def mm(h: float) -> str:
    return f"{1e3 * h:.2f}"


def pct(x: float, digits: int = 1) -> str:
    return "—" if not np.isfinite(x) else f"{100 * x:+.{digits}f} %"


def meshes_md(rows: list, psi: float) -> list:
    L = ["| mesh | DOFs | levels | Newton iterations | wall [s] |", "|---|---:|---:|---:|---:|"]
    for label, _, lv in meshes(rows, psi):
        last = lv[max(lv)]
        L.append(f"| {label} | {int(num(last['dofs']))} | {len(lv)} (to {max(lv):g} N) | "
                 f"{sum(int(num(r['newton_its'])) for r in lv.values())} | {num(last['wall_s']):.0f} |")
    return L


def quantity_md(rows: list, psi: float, column: str, scale: float, fmt: str) -> list:
    """One row per shown level: the value on every mesh, the change between the two finest
    refined meshes, the 2 % check, the observed order and the Richardson value."""
    ms = meshes(rows, psi)
    L = ["| load [N] | " + " | ".join(label for label, _, _ in ms) + " | two finest | change | within 2 % "
         "| observed order | Richardson |", "|---:|" + "---:|" * len(ms) + "---|---:|---|---:|---:|"]
    for F in SHOW:
        if not any(F in lv for _, _, lv in ms):
            continue
        c = convergence(rows, psi, column, F)
        cells = [fmt.format(scale * num(lv[F][column])) if F in lv else "—" for _, _, lv in ms]
        ok = "—" if not np.isfinite(c["change"]) else ("yes" if abs(c["change"]) <= TARGET else "no")
        L.append(f"| {F:g} | " + " | ".join(cells) + f" | {' → '.join(mm(h) for h in c['pair'])} | "
                 f"{pct(c['change'])} | {ok} | " + ("—" if not np.isfinite(c["p"]) else f"{c['p']:.2f}")
                 + " | " + (fmt.format(scale * c["limit"]) if PLAUSIBLE[0] <= c["p"] <= PLAUSIBLE[1] else "—") + " |")
    return L


def ends_md(rows: list, psi: float) -> list:
    """The gastrocnemius ends: change between the two finest refined meshes against the soleus
    elongation, per shown level."""
    L = ["| load [N] | two finest | soleus | medial / u_soleus | lateral / u_soleus |", "|---:|---|---:|---:|---:|"]
    for F in SHOW:
        cs = {b: convergence(rows, psi, f"{b}_ux_m", F) for b in BODIES}
        if not np.isfinite(cs["soleus"]["change"]):
            continue
        L.append(f"| {F:g} | {' → '.join(mm(h) for h in cs['soleus']['pair'])} | "
                 + " | ".join(pct(cs[b]["change"], 2) for b in BODIES) + " |")
    return L


def beams_md(rows: list, psi: float, variant: str = "augmentation default") -> list:
    """The beams (default space and augmentation) against the finest refined solid that reached
    each judged level."""
    cols = ancf_columns(rows, psi)
    L = ["| elements | load [N] | solid mesh | soleus u_x solid / ANCF [mm] | soleus | medial / u_soleus "
         "| lateral / u_soleus | friction mg_sol solid / ANCF [N] | on the gastrocnemii from the soleus, "
         "solid / ANCF [N] |", "|---:|---:|---|---:|---:|---:|---:|---:|---:|"]
    for ne in sorted(ne for v, ne in cols if v == variant):
        lv = cols[(variant, ne)]["levels"]
        for F in JUDGED:
            two = finest_two(rows, psi, F)
            if not two or F not in lv:
                continue
            s, a = two[-1][1], lv[F]
            us = num(s["soleus_ux_m"])
            e = {b: (num(a[f"{b}_ux_m"]) - num(s[f"{b}_ux_m"])) / abs(us) for b in BODIES}
            fs, fa = (num(r["fx_mg_sol_N"]) + num(r["fx_lg_sol_N"]) for r in (s, a))
            L.append(f"| {ne} | {F:g} | {mm(two[-1][0])} mm at mg_sol | {1e3 * us:.5f} / "
                     f"{1e3 * num(a['soleus_ux_m']):.5f} | {pct(e['soleus'], 2)} | {pct(e['medial'], 2)} | "
                     f"{pct(e['lateral'], 2)} | {num(s['fx_mg_sol_N']):.2f} / {num(a['fx_mg_sol_N']):.2f} | "
                     f"{fs:.2f} / {fa:.2f} |")
    return L


def refined_md(rows: list, psi: float) -> list:
    """The tables of the locally refined reference (empty without refined runs)."""
    if not refined_runs(rows, psi):
        return []
    L = ["**Meshes** (the uniform ones of the tables above first; wall: the solid's cumulative solve time):", ""]
    L += meshes_md(rows, psi) + [""]
    for column, title, scale, fmt in QUANTITIES:
        L += [f"**{title}** per mesh; change between the two finest refined meshes (relative to the finer); "
              "observed order from the three finest refined meshes where the two changes have one sign and "
              f"shrink, and the Richardson value where that order is between {PLAUSIBLE[0]:g} and {PLAUSIBLE[1]:g}:", ""]
        L += quantity_md(rows, psi, column, scale, fmt) + [""]
    L += ["**End displacements**, change between the two finest refined meshes (soleus relative, the "
          "gastrocnemii against the soleus elongation):", ""] + ends_md(rows, psi) + [""]
    beams = beams_md(rows, psi)
    if len(beams) > 2:
        L += ["**The beams against the finest refined solid** (default pressure space and augmentation; errors "
              "against the solid's soleus elongation):", ""] + beams + [""]
    return L

