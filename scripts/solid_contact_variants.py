#!/usr/bin/env python3
"""What limits the ANCF sliding columns against the 3D solid with contact (issue 24, point 3):
the soleus elongation of contact-discretisation variants against the solid reference of
docs/solid_contact.csv (read from the CSV: no dolfinx, nothing solid is solved).

    python scripts/solid_contact_variants.py                     # every variant, 4/8/16 el, ψ 0/15/45
    python scripts/solid_contact_variants.py --variants "default;free" --elements 4

Each ANCF column is the one of scripts/verify_solid_contact.py (``tendon_config``: clamped roots,
end traction on the soleus, 2 axial Gauss points), run in this process with the variant's
``contact:`` keys.  Variants: the pressure space (``projection``), the density of the contact
points (``axial_points``, ``curve_points``), the soleus alone (``free``: the beam's own error),
and a coarser mesh's pressure space on this mesh's displacements (``build_space(group=G)``: the
functions of the 4- or 8-element space on 8 or 16 elements, to tell the pressure space from the
displacements).  Prints, per variant, ψ and element count, the worst signed error over the
solid's loads and the error at 10 N, as a markdown table (docs/solid_contact.md, "What limits
4 elements").
"""
from __future__ import annotations

import argparse
import functools
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import verify_solid_contact as vsc  # noqa: E402

#: name → (contact keys, elements of the coarse pressure space or None, contact mode)
VARIANTS = {
    "default": ({}, None, "sliding"),
    "free": ({}, None, None),
    # the clamped roots' pressure functions kept (the default before 2026-11-26: they repeat the
    # supports; docs/contact.md, "Supported ends")
    "supported ends kept": ({"projection": {"supported_ends": "keep"}}, None, "sliding"),
    "projection 1,1": ({"projection": {"axial": 1, "curve": 1}}, None, "sliding"),
    "projection 2,0": ({"projection": {"axial": 2, "curve": 0}}, None, "sliding"),
    "projection 2,2": ({"curve_points": 3, "projection": {"axial": 2, "curve": 2}}, None, "sliding"),
    "projection 3,1": ({"axial_points": 4, "projection": {"axial": 3, "curve": 1}}, None, "sliding"),
    "4 axial points": ({"axial_points": 4, "projection": {"axial": 2, "curve": 1}}, None, "sliding"),
    "4 points per curve piece": ({"curve_points": 4}, None, "sliding"),
    "4-element pressure space": ({}, 4, "sliding"),
    "8-element pressure space": ({}, 8, "sliding"),
}


def run_column(psi: float, elements: int, variant: str, tmp: str) -> dict | None:
    """{load [N]: soleus elongation [m]} of one column, None when it failed or does not apply."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.contact import contact as contact_module
    from ancf_petsc.contact.multipliers import build_space
    from ancf_petsc.solving.run import run_model
    keys, coarse, mode = VARIANTS[variant]
    if coarse is not None and (elements <= coarse or elements % coarse):
        return None
    beams = vsc.NAMES if mode else vsc.NAMES[:1]
    raw = vsc.tendon_config(psi, elements, mode, os.path.join(tmp, f"{variant}_{psi:g}_{elements}"), beams)
    if mode:
        raw["contact"].update(keys)
    original = contact_module.build_space
    if coarse is not None:
        contact_module.build_space = functools.partial(build_space, group=elements // coarse)
    try:
        res = run_model(parse_config(raw, base_dir=vsc.CONFIGS), log=lambda *_: None)
    finally:
        contact_module.build_space = original
    if res.status != "completed":
        return None
    return {float(st["load_factor"]): float(st["probes"]["soleus"]["displacement"][0])
            for st in res.summary["steps"]}


def reference(rows: list, law: str) -> dict:
    """{(ψ, load): soleus elongation} of the solid reference for ``law`` ('sliding' | 'free')."""
    return {(vsc._num(r["psi_deg"]), vsc._num(r["load_N"])): vsc._num(r["soleus_ux_m"])
            for r in rows if r["model"] == vsc.REF and r["law"] == law and r["load_N"] not in ("", None)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--variants", default=";".join(VARIANTS), help="names separated by ;")
    ap.add_argument("--elements", default="4,8,16")
    ap.add_argument("--psi", default="0,15,45")
    args = ap.parse_args(argv)
    names = [v.strip() for v in args.variants.split(";") if v.strip()]
    unknown = [v for v in names if v not in VARIANTS]
    if unknown:
        print(f"solid_contact_variants: unknown variants {unknown}; known: {', '.join(VARIANTS)}",
              file=sys.stderr)
        return 2
    elements = [int(e) for e in args.elements.split(",")]
    psis = [float(p) for p in args.psi.split(",")]
    rows = vsc.read_csv(os.path.join(vsc.ROOT, "docs", "solid_contact.csv"))
    print("| variant | ψ | " + " | ".join(f"{e} el. worst (10 N)" for e in elements) + " |")
    print("|---|---:|" + "---:|" * len(elements))
    with tempfile.TemporaryDirectory(prefix="solid_variants_") as tmp:
        for name in names:
            ref = reference(rows, "free" if VARIANTS[name][2] is None else "sliding")
            for psi in psis:
                cells = []
                for e in elements:
                    u = run_column(psi, e, name, tmp)
                    errs = {F: (u[F] - ref[(psi, F)]) / ref[(psi, F)] for F in u or {} if (psi, F) in ref}
                    worst = max(errs.values(), key=abs) if errs else None
                    cells.append("—" if worst is None else
                                 f"{100 * worst:+.3f} % ({100 * errs.get(10.0, float('nan')):+.3f} %)")
                print(f"| {name} | {psi:g}° | " + " | ".join(cells) + " |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
