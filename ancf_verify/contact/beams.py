"""The tendon as ANCF beams in-process (one column of the comparison)."""
from __future__ import annotations

import os
import time

import numpy as np

from ancf_verify.contact.tendon import NAMES, SHORT, SOURCE, tendon_config


# ============================================================================================
# ANCF runs
# ============================================================================================
def run_ancf(psi: float, mode: str | None, elements: int, tmp: str, root: str = "clamped") -> dict:
    """One ANCF column in-process (roots: the preset ``root``); per load the x-displacement of r
    at each last node."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    beams = NAMES if mode else NAMES[:1]
    out = os.path.join(tmp, f"ancf_{psi:g}_{mode or 'free'}_{elements}_{root}")
    t0 = time.perf_counter()
    try:
        spec = parse_config(tendon_config(psi, elements, mode, out, beams, root), base_dir=SOURCE.configs)
        res = run_model(spec, log=lambda *_: None)
        status, message, s = res.status, res.message, res.summary
    except Exception as exc:   # record and go on
        status, message, s = "failed", f"{type(exc).__name__}: {exc}", None
    wall = time.perf_counter() - t0
    rec = {"psi": psi, "law": mode or "free", "elements": elements, "ok": status == "completed",
           "msg": "" if status == "completed" else str(message), "wall": wall, "levels": [],
           "dofs": int(s["dofs"]) if s else 0}
    if s:
        for st in s["steps"]:
            rec["levels"].append({"load": float(st.get("load_factor", st.get("level", float("nan")))),
                                  "its": int(st["iterations"]),
                                  "u": {SHORT[NAMES.index(n)]: np.array(st["probes"][n]["displacement"])
                                        for n in beams}})
    return rec
