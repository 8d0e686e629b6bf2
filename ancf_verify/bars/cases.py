"""The bars compared with the solid (tension, bending, twist; neo-Hookean) and their ANCF configs and runs."""
from __future__ import annotations

from dataclasses import dataclass, field
import copy
import math
import os
import tempfile
import time

import numpy as np

from ancf_verify.paths import CONFIGS
from ancf_verify.stack import SolidError


# --------------------------------------------------------------------------------------------
# Cases
# --------------------------------------------------------------------------------------------
@dataclass
class Case:
    """One bar: ANCF section spec (also meshed for the solid), material, end force, meshes."""
    key: str
    title: str
    section: dict
    material: dict
    force: tuple
    h: tuple                     # solid mesh sizes [m], coarse to fine
    h_quick: tuple
    length: float = 0.1
    twist_deg: float = 0.0
    twist_axis: tuple = (0.0, 0.0)
    steps: tuple = (0.25, 0.5, 0.75, 1.0)
    notes: list = field(default_factory=list)
    root: str = "clamped"        # the root's support, solid and beam alike (ancf_verify.roots)
    element: str = "3363"        # the beam's element (physics/elements; issue 42's section orders)


def geometric(h0: float, n: int, r: float = math.sqrt(2.0)) -> tuple:
    """n mesh sizes h0, h0/r, h0/r^2, ..."""
    return tuple(h0 / r ** k for k in range(n))

NH_BAR = {"mu": 1.0e6, "bulk_modulus": 5.0e7}

NH_SOLEUS = {"mu": 103.1e6, "bulk_modulus": 0.86e9}

ELLIPSE = {"shape": "ellipse", "semi_axes": [0.006, 0.004], "cubature_degree": 6}

CASES = [
    Case("tension", "straight bar, tension 45 N (~25 % strain), clamped root", ELLIPSE, NH_BAR,
         (45.0, 0.0, 0.0), h=geometric(8e-3, 6), h_quick=geometric(8e-3, 3, 2.0)),
    Case("bending", "straight cantilever, transverse end force 0.04 N (tip deflection ~14 % of L)",
         ELLIPSE, NH_BAR, (0.0, 0.0, 0.04), h=geometric(8e-3, 6), h_quick=geometric(8e-3, 3, 2.0)),
    Case("pretwisted", "pretwisted bar psi = 60 deg, section off the twist axis, 4 N, clamped root",
         {"shape": "ellipse", "semi_axes": [0.005, 0.0025], "center": [0.004, 0.0],
          "cubature_degree": 6}, NH_BAR, (4.0, 0.0, 0.0), twist_deg=60.0,
         h=geometric(5e-3, 5), h_quick=geometric(5e-3, 3, 2.0)),
    Case("soleus", "Achilles soleus subtendon, psi = 45 deg, no contact, 100 N, clamped root",
         {"shape": "outline", "file": "data/achilles_type3_sections.yaml", "loop": "soleus",
          "spline_degree": 3, "cubature_degree": 6}, NH_SOLEUS, (100.0, 0.0, 0.0), length=0.07,
         twist_deg=45.0, twist_axis=(0.005896, -0.0029837333333333335),
         h=geometric(6e-3, 7), h_quick=geometric(3e-3, 3, 2.0)),
]


def ancf_config(case: Case, elements: int, axial_points: int, out_dir: str) -> dict:
    """The raw ANCF config of ``case`` (one beam, its root's preset at the first node, end
    traction, tip probe)."""
    return {"name": f"{case.key}_e{elements}_a{axial_points}",
            "geometry": {"length": case.length, "twist_deg": case.twist_deg,
                         "twist_axis": list(case.twist_axis)},
            "beams": [{"name": "bar", "section": copy.deepcopy(case.section),
                       "material": {"model": "neo-hookean", **case.material},
                       "elements": elements, "axial_points": axial_points,
                       **({"element": case.element} if case.element != "3363" else {})}],
            "boundary_conditions": [{"beam": "bar", "node": "first", "fix": case.root}],
            "loads": [{"beam": "bar", "node": "last", "traction_force": list(case.force)}],
            "steps": list(case.steps),
            "probes": [{"name": "tip", "beam": "bar", "node": "last"}],
            "output": {"dir": out_dir, "vtk": False}}


def ancf_section(case: Case):
    """The ANCF Section object of ``case`` (outline, centroid and area for the solid)."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    spec = parse_config(ancf_config(case, 1, 3, tempfile.mkdtemp()), base_dir=CONFIGS)
    return build_model(spec).beams[0].section


# --------------------------------------------------------------------------------------------
# ANCF runs
# --------------------------------------------------------------------------------------------
def run_ancf(case: Case, elements: int, axial_points: int, repeats: int, tmp: str) -> dict:
    """Best-of-``repeats`` wall time of parse + build + solve; tip displacement and DOFs."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    best, out = math.inf, None
    for k in range(repeats):
        raw = ancf_config(case, elements, axial_points, os.path.join(tmp, f"{case.key}_{elements}_{axial_points}_{k}"))
        t0 = time.perf_counter()
        spec = parse_config(raw, base_dir=CONFIGS)
        res = run_model(spec, log=lambda *_: None)
        wall = time.perf_counter() - t0
        if res.status != "completed":
            raise SolidError(f"ANCF {case.key} {elements} el./{axial_points} pts failed: {res.message}")
        best = min(best, wall)
        s = res.summary
        out = {"u": np.array(s["steps"][-1]["probes"]["tip"]["displacement"]), "dofs": int(s["dofs"]),
               "its": int(sum(st["iterations"] for st in s["steps"]))}
    out.update(model=f"ANCF {axial_points}pt", res=f"{elements} el.", size=elements, wall=best,
               mesh=float("nan"))
    return out
