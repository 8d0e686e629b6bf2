"""The tendon as ANCF beams with Coulomb friction (one column of the friction comparison)."""
from __future__ import annotations

import os
import time

import numpy as np

from ancf_verify.contact.tendon import INTERFACES, NAMES, SHORT, SOURCE, tendon_config
from ancf_verify.friction.rows import SPACES, ZONE


IFACES = [n for n, _, _ in INTERFACES]


#: the beam model's config key of the Coulomb law's augmentation factor c (contact.tangential.<key>)
AUG_KEY = "augmentation"


def zone_label(variant: str, zone: float) -> str:
    """The variant of a free-zone diagnostic run (rep.ZONE marks it)."""
    return f"{variant}{ZONE}{zone * 1e3:g} mm" if zone else variant


#: friction's held root functions as docs/solid_friction.csv was measured: kept (the default until
#: 2026-11-26; the default merge moves the beams' soleus by +0.19 / +0.08 / +0.02 % at 4 / 8 / 16
#: elements, docs/interface.md "Verdict and why")
SUPPORTED_ENDS = "keep"


def ancf_config(psi: float, elements: int, mu: float, aug: float | None, out: str, space: str | None = None,
                contact: dict | None = None, element: str | None = None) -> dict:
    """verify_solid_contact's frictionless comparison config with Coulomb friction added (and the
    contact keys of the pressure space ``space``, a rows.SPACES name; None: the default; then the
    keys of ``contact``, e.g. ``{"projection": {"supported_ends": "merge"}}``; ``element``: every
    beam's ``element`` key, e.g. "33103"; None: the key unset, the config's default 3363)."""
    raw = tendon_config(psi, elements, "sliding", out)
    if element:
        for b in raw["beams"]:
            b["element"] = str(element)
    raw["contact"]["tangential"] = {"law": "coulomb", "friction": mu, "supported_ends": SUPPORTED_ENDS}
    if aug is not None:
        raw["contact"]["tangential"][AUG_KEY] = aug
    if space:
        raw["contact"].update(SPACES[space])
    raw["contact"].update(contact or {})
    return raw


def run_ancf(psi: float, elements: int, mu: float, aug: float | None, tmp: str, zone: float = 0.0,
             space: str | None = None, contact: dict | None = None, element: str | None = None) -> dict:
    """One ANCF column in-process: per level the probes' u_x, iterations and shear forces
    (``zone`` > 0, a diagnostic: no friction on the functions centred below x = zone [m],
    ``TangentialSpec.free_zone``; ``space``: the pressure space, a rows.SPACES name, None the default;
    ``element``: every beam's element, None the config's default)."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    out = os.path.join(tmp, (f"ancf_{psi:g}_{elements}_{aug}_{zone:g}_{space}"
                                + (f"_{element}" if element else "")).replace(" ", "_"))
    t0 = time.perf_counter()
    try:
        spec = parse_config(ancf_config(psi, elements, mu, aug, out, space, contact, element), base_dir=SOURCE.configs)
        spec.contact.tangential.free_zone = zone
        res = run_model(spec, log=lambda *_: None)
        status, message, s = res.status, str(res.message), res.summary
    except Exception as exc:   # record and go on
        status, message, s = "failed", f"{type(exc).__name__}: {exc}", None
    rec = {"psi": psi, "elements": elements, "augmentation": aug, "zone": zone, "space": space, "element": element,
           "ok": status == "completed",
           "msg": "" if status == "completed" else message, "wall": time.perf_counter() - t0,
           "levels": [], "dofs": int(s["dofs"]) if s else 0,
           "k": None}
    for st in (s or {}).get("steps", []):
        forces = {}
        for key, c in st.get("contact", {}).items():
            name = key.split()[0]
            forces[name] = c.get("shear_force", [np.nan])[0]
            forces[name + "_pmax"] = c.get("max_pressure", np.nan)
            forces[name + "_stick"] = c.get("stick_share", np.nan)
        rec["levels"].append({"load": float(st["load_factor"]), "its": int(st["iterations"]),
                              "u": {SHORT[i]: st["probes"][n]["displacement"][0]
                                    for i, n in enumerate(NAMES)}, "friction": forces})
    return rec
