#!/usr/bin/env python3
"""The pressure functions at clamped ends kept or folded (``contact.projection.supported_ends``),
against the 3D solid of docs/solid_friction*.csv (read from the CSVs: nothing solid is solved).

    python scripts/supported_ends_study.py pressure     # normal force near the clamp, μ = 0
    python scripts/supported_ends_study.py friction     # Coulomb μ = 0.3 columns against the solid

``pressure``: per interface, the compressive and tensile normal force Q± = ∫ p± dA within 10 mm
of the clamped roots and beyond, of the frictionless ANCF columns (4/8/16 elements, ψ = 45°, 10
and 100 N) with the ends kept and folded, and of the solid (docs/solid_friction_profiles.csv).
``friction``: the columns of scripts/verify_solid_friction.py (``contact.tangential: {law:
coulomb, friction: 0.3}``) with the ends kept and folded: levels reached, Newton iterations and
the worst errors against the solid reference (soleus relative; gastrocnemii against the soleus
elongation).  Markdown tables on stdout (docs/contact.md, "Supported ends").
"""
from __future__ import annotations

import argparse
import contextlib
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import verify_solid_contact as vsc  # noqa: E402
import solid_friction_report as rep  # noqa: E402

ZONE = 0.010          # the clamp zone [m]
RULES = ("keep", "merge")


@contextlib.contextmanager
def supported_ends(rule: str):
    """verify_solid_contact.tendon_config with ``contact.projection.supported_ends: rule``."""
    original = vsc.tendon_config

    def config(*args, **kwargs):
        raw = original(*args, **kwargs)
        if "contact" in raw:
            raw["contact"]["projection"] = {"supported_ends": rule}
        return raw
    vsc.tendon_config = config
    try:
        yield
    finally:
        vsc.tendon_config = original


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
    from solid_friction_profiles import ancf_profile, read
    solid = [r for r in read(os.path.join(vsc.ROOT, "docs", "solid_friction_profiles.csv"))
             if r["model"] == rep.SOLID and r["variant"] == "mu 0" and r["resolution"] == "h 2.00 mm"]
    print("| model | ends | load [N] | " + " | ".join(f"{i}: Q⁺ / Q⁻ [N], x < 10 mm · beyond" for i in rep.IFACES) + " |")
    print("|---|---|---:|" + "---:|" * len(rep.IFACES))
    for F in loads:
        q = zone_forces([r for r in solid if float(r["load_N"]) == F])
        print(f"| solid P2 tet h 2.00 mm | | {F:g} | " + " | ".join(cell(q[i]) for i in rep.IFACES) + " |")
    with tempfile.TemporaryDirectory(prefix="supported_ends_") as tmp:
        for e in elements:
            for rule in RULES:
                for F in loads:
                    with supported_ends(rule):
                        rows = ancf_profile(45.0, e, 0.0, F, None, os.path.join(tmp, rule))
                    q = zone_forces(rows)
                    cells = [cell(q[i]) if i in q else "failed" for i in rep.IFACES]
                    print(f"| ANCF {e} el. | {rule} | {F:g} | " + " | ".join(cells) + " |", flush=True)


def friction(elements: list, augs: list) -> None:
    from verify_solid_friction import run_ancf
    ref = {F: v["row"] for F, v in rep.reference(rep.read_csv(os.path.join(vsc.ROOT, "docs", "solid_friction.csv")),
                                                   45.0).items()}
    print("| ends | augmentation c | elements | levels reached | Newton its | soleus, relative | medial / u_soleus "
          "| lateral / u_soleus | friction on the gastrocnemii from the soleus at 100 N [N] (solid "
          f"{sum(rep.num(ref[100.0][f'fx_{i}_N']) for i in ('mg_sol', 'lg_sol')):.1f}) |")
    print("|---|---|---:|---|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory(prefix="supported_ends_") as tmp:
        for e in elements:
            for aug in augs:
                for rule in RULES:
                    with supported_ends(rule):
                        run = run_ancf(45.0, e, 0.3, aug, os.path.join(tmp, rule))
                    lv = run["levels"]
                    worst = {}
                    for L in lv:
                        r = ref.get(L["load"])
                        if r is None:
                            continue
                        us = rep.num(r["soleus_ux_m"])
                        errs = {"soleus": (L["u"]["soleus"] - us) / us}
                        for b in ("medial", "lateral"):
                            errs[b] = (L["u"][b] - rep.num(r[f"{b}_ux_m"])) / us
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("part", choices=("pressure", "friction"))
    ap.add_argument("--elements", default="4,8,16")
    ap.add_argument("--loads", default="10,100", help="pressure: load levels [N]")
    ap.add_argument("--augmentations", default="default,0.1", help="friction: the Coulomb law's augmentation c")
    args = ap.parse_args(argv)
    elements = [int(e) for e in args.elements.split(",")]
    if args.part == "pressure":
        pressure(elements, [float(F) for F in args.loads.split(",")])
    else:
        friction(elements, [None if s == "default" else float(s) for s in args.augmentations.split(",")])
    return 0


if __name__ == "__main__":
    sys.exit(main())
