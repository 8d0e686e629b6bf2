"""Contact-space variants of the beams against the contact solid's reference."""
from __future__ import annotations

import os

from ancf_verify.contact.rows import REF, num
from ancf_verify.contact.tendon import NAMES, SOURCE, tendon_config


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
    from ancf_petsc.solving.run import run_model
    keys, coarse, mode = VARIANTS[variant]
    if coarse is not None and (elements <= coarse or elements % coarse):
        return None
    beams = NAMES if mode else NAMES[:1]
    raw = tendon_config(psi, elements, mode, os.path.join(tmp, f"{variant}_{psi:g}_{elements}"), beams)
    if mode:
        raw["contact"].update(keys)
    spec = parse_config(raw, base_dir=SOURCE.configs)
    if coarse is not None:
        spec.contact.group = elements // coarse
    res = run_model(spec, log=lambda *_: None)
    if res.status != "completed":
        return None
    return {float(st["load_factor"]): float(st["probes"]["soleus"]["displacement"][0])
            for st in res.summary["steps"]}


def reference(rows: list, law: str) -> dict:
    """{(ψ, load): soleus elongation} of the solid reference for ``law`` ('sliding' | 'free')."""
    return {(num(r["psi_deg"]), num(r["load_N"])): num(r["soleus_ux_m"])
            for r in rows if r["model"] == REF and r["law"] == law and r["load_N"] not in ("", None)}
