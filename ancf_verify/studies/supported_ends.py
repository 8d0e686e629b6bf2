"""The supported-ends rule (merge or keep) against the solid: pressure and friction near the roots."""
from __future__ import annotations

import os
import tempfile

from ancf_verify.friction.rows import IFACES, SOLID, num, read_csv, reference
from ancf_verify.paths import ROOT


ZONE = 0.010          # the clamp zone [m]

RULES = ("keep", "merge")


def ends(rule: str) -> dict:
    """The beams' contact keys of a supported-ends rule (contact.projection.supported_ends)."""
    return {"projection": {"supported_ends": rule}}


def zone_forces(rows: list) -> dict:
    """{interface: (Q⁺ near, Q⁻ near, Q⁺ beyond, Q⁻ beyond)} [N] from profile rows (per length)."""
    out = {}
    for r in rows:
        q = out.setdefault(r["interface"], [0.0] * 4)
        dx = float(r["x_hi_m"]) - float(r["x_lo_m"])
        far = 2 * (float(r["x_lo_m"]) >= ZONE - 1e-12)
        q[far] += float(r["q_plus_N_per_m"]) * dx
        q[far + 1] += float(r["q_minus_N_per_m"]) * dx
    return out


def cell(q) -> str:
    return f"{q[0]:.0f} / {q[1]:.0f} · {q[2]:.0f} / {q[3]:.0f}"


def pressure(elements: list, loads: list) -> None:
    from ancf_verify.friction.profiles import ancf_profile, read
    solid = [r for r in read(os.path.join(ROOT, "docs", "solid_friction_profiles.csv"))
             if r["model"] == SOLID and r["variant"] == "mu 0" and r["resolution"] == "h 2.00 mm"]
    print("| model | ends | load [N] | " + " | ".join(f"{i}: Q⁺ / Q⁻ [N], x < 10 mm · beyond" for i in IFACES) + " |")
    print("|---|---|---:|" + "---:|" * len(IFACES))
    for F in loads:
        q = zone_forces([r for r in solid if float(r["load_N"]) == F])
        print(f"| solid P2 tet h 2.00 mm | | {F:g} | " + " | ".join(cell(q[i]) for i in IFACES) + " |")
    with tempfile.TemporaryDirectory(prefix="supported_ends_") as tmp:
        for e in elements:
            for rule in RULES:
                for F in loads:
                    rows = ancf_profile(45.0, e, 0.0, F, None, os.path.join(tmp, rule), contact=ends(rule))
                    q = zone_forces(rows)
                    cells = [cell(q[i]) if i in q else "failed" for i in IFACES]
                    print(f"| ANCF {e} el. | {rule} | {F:g} | " + " | ".join(cells) + " |", flush=True)


def friction(elements: list, augs: list) -> None:
    from ancf_verify.friction.beams import run_ancf
    ref = {F: v["row"] for F, v in reference(read_csv(os.path.join(ROOT, "docs", "solid_friction.csv")),
                                                   45.0).items()}
    print("| ends | augmentation c | elements | levels reached | Newton its | soleus, relative | medial / u_soleus "
          "| lateral / u_soleus | friction on the gastrocnemii from the soleus at 100 N [N] (solid "
          f"{sum(num(ref[100.0][f'fx_{i}_N']) for i in ('mg_sol', 'lg_sol')):.1f}) |")
    print("|---|---|---:|---|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory(prefix="supported_ends_") as tmp:
        for e in elements:
            for aug in augs:
                for rule in RULES:
                    run = run_ancf(45.0, e, 0.3, aug, os.path.join(tmp, rule), contact=ends(rule))
                    lv = run["levels"]
                    worst = {}
                    for L in lv:
                        r = ref.get(L["load"])
                        if r is None:
                            continue
                        us = num(r["soleus_ux_m"])
                        errs = {"soleus": (L["u"]["soleus"] - us) / us}
                        for b in ("medial", "lateral"):
                            errs[b] = (L["u"][b] - num(r[f"{b}_ux_m"])) / us
                        for k, v in errs.items():
                            worst[k] = max(worst.get(k, 0.0), v, key=abs)
                    at100 = [L for L in lv if L["load"] == 100.0]
                    # the beams' shear force is on A (the gastrocnemius): the solid's sign is −
                    f100 = (f"{-sum(at100[0]['friction'].get(i, 0.0) for i in ('mg_sol', 'lg_sol')):.1f}"
                            if at100 else "—")
                    reached = ("all 13" if run["ok"] else
                               f"to {lv[-1]['load']:g} N" if lv else "none") + ("" if run["ok"] else f" ({run['msg'][:40]})")
                    its = sum(L["its"] for L in lv)
                    w = [f"{100 * worst[k]:+.2f} %" if k in worst else "—" for k in ("soleus", "medial", "lateral")]
                    print(f"| {rule} | {'default' if aug is None else f'{aug:g}'} | {e} | {reached} | {its} | "
                          + " | ".join(w) + f" | {f100} |", flush=True)
