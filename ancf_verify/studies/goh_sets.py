"""The GOH parameter sets of the paper's authors' public code (issue 26) and the ψ = 45° GOH column
(configs/achilles_type3_psi45_goh.yaml) built and solved with any of them."""
from __future__ import annotations

import copy
import os
import tempfile
import time

import yaml

from ancf_verify.paths import CONFIGS

LEVELS = [10, 20, 30, 40, 45, 60, 80, 90, 100, 150, 200, 300, 400]
NU49 = 49.67                                   # K/μ at small-strain ν = 0.49
#: (c10 [Pa], k1 [Pa], k2), κ = 0, one fibre family: Leonid1991/Tendon-model ProblemData.m (eb74128)
#: and LUT-CoSmart/ANCF-Beam-based-Solver Materials.m (ed5e49d), read with `fetch`
SETS = {"tendon_model_2023": (30.6e3, 3.7859e6, 7.8085), "solver_default_2025": (7.64e3, 996.6e3, 524.6),
        "alex": (53.6e3, 75.351e6, 23.926), "amir": (9.67e6, 135.5e6, 131.0),
        "optimized_SEE": (53.6e3, 8409291.05908193, 4.78018491589778)}
PUBLISHED = dict(mu=2 * 30.6e3, K=2.0e8, k1=3.7859e6, k2=7.8085)     # K: the source's 1e8 (J - 1)^2


def published_law(name: str) -> dict:
    """``column``'s material arguments of the set ``name``: its μ = 2 c10, k1, k2 and our K = 49.67 μ."""
    c10, k1, k2 = SETS[name]
    return dict(mu=2 * c10, K=NU49 * 2 * c10, k1=k1, k2=k2)


def column(mu: float, K: float, k1: float, k2: float, mode: str | None, elements: int = 4,
           axial_points: int = 3, steps=LEVELS) -> dict:
    """configs/achilles_type3_psi45_goh.yaml with this GOH law; ``mode`` None: the soleus alone."""
    with open(os.path.join(CONFIGS, "achilles_type3_psi45_goh.yaml")) as fh:
        raw = yaml.safe_load(fh)
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
        b["material"].update(mu=mu, bulk_modulus=K, k1=k1, k2=k2)
        b["elements"], b["axial_points"] = elements, axial_points
    if mode is None:
        raw["beams"] = raw["beams"][:1]
        raw["boundary_conditions"] = raw["boundary_conditions"][:1]
        raw["probes"] = raw["probes"][:1]
        raw.pop("contact")
    else:
        raw["contact"]["mode"] = mode
    raw["steps"] = list(steps)
    raw["output"] = {"dir": tempfile.mkdtemp(prefix="goh_sets_"), "vtk": False}
    return raw


def solve(raw: dict) -> dict:
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    t0 = time.perf_counter()
    res = run_model(parse_config(copy.deepcopy(raw), base_dir=CONFIGS), log=lambda *_: None)
    s = res.summary
    steps = s["steps"]
    return {"status": s["status"], "levels": len(steps), "wall": time.perf_counter() - t0,
            "last": steps[-1]["load_factor"] if steps else 0.0, "message": s.get("message", ""),
            "cutbacks": sum(st["cutbacks"] for st in steps), "newton": sum(st["iterations"] for st in steps),
            "soleus_mm": 1e3 * steps[-1]["probes"]["soleus"]["displacement"][0] if steps else float("nan"),
            "dir": raw["output"]["dir"]}
