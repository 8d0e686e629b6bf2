"""The three-subtendon Achilles tendon of the contact comparison: names, material, loads, beam config."""
from __future__ import annotations

import os
import sys
import tempfile
from dataclasses import dataclass

from ancf_verify.paths import CONFIGS
from ancf_verify.stack import SolidError


NAMES = ("soleus", "medial_gastrocnemius", "lateral_gastrocnemius")

SHORT = ("soleus", "medial", "lateral")

MU = (103.1e6, 143.2e6, 226.7e6)

KBULK = 0.86e9

LENGTH = 0.07

AXIS = (0.005896, -0.0029837333333333335)

LOADS = (10, 20, 30, 40, 45, 60, 80, 90, 100, 150, 200, 300, 400)


# (shared curve, slave body, master body): the gastrocnemii slide on the soleus (which moves
# past their ends at x = L, so they stay covered by it); medial on the stiffer lateral
INTERFACES = (("mg_sol", 1, 0), ("lg_sol", 2, 0), ("lg_mg", 1, 2))

SECTIONS_FILE = "data/achilles_type3_sections.yaml"


@dataclass
class AncfSource:
    """Where ancf_petsc and its configs/ come from (``--ancf-src``: an export of another commit,
    set before ancf_petsc is first imported) and what the CSV calls it."""
    configs: str = CONFIGS
    label: str = "the working tree"


#: the source of the ANCF columns of this process (``use_source`` changes it)
SOURCE = AncfSource()


class ContactError(SolidError):
    """A failed solve or a broken setup (one line, exit status 1)."""


def use_source(src: str, label: str) -> None:
    """Import ancf_petsc (and read configs/) from the directory ``src`` ('' : this checkout),
    recorded in the CSV as ``label``; before ancf_petsc is first imported."""
    SOURCE.label = label
    if src:
        if "ancf_petsc" in sys.modules:
            raise ContactError("--ancf-src: ancf_petsc is imported already")
        if not os.path.isfile(os.path.join(src, "ancf_petsc", "__init__.py")):
            raise ContactError(f"--ancf-src: no ancf_petsc package in {src!r} (this checkout's would be "
                               "solved under its label); give the directory of an export of a commit")
        sys.path.insert(0, os.path.abspath(src))
        SOURCE.configs = os.path.join(os.path.abspath(src), "configs")


# ============================================================================================
# Geometry and meshes
# ============================================================================================
def tendon_config(psi: float, elements: int, mode: str | None, out_dir: str, beams=NAMES,
                  root: str = "clamped") -> dict:
    """The raw ANCF config: first nodes fixed by the preset ``root`` (clamped or plane, as the
    solid's roots: ancf_verify.roots), traction_force 1 N (load factors = newtons) at the soleus'
    last node, 2 axial points, contact ``mode`` (None: none), probes at the last nodes."""
    raw = {"name": f"type3_psi{psi:g}_e{elements}_{mode or 'free'}",
           "geometry": {"length": LENGTH, "twist_deg": float(psi), "twist_axis": list(AXIS)},
           "beams": [{"name": n, "section": {"shape": "outline", "file": SECTIONS_FILE, "loop": n,
                                             "spline_degree": 3, "cubature_degree": 6},
                      "material": {"model": "neo-hookean", "mu": MU[NAMES.index(n)],
                                   "bulk_modulus": KBULK},
                      "elements": elements, "axial_points": 2} for n in beams],
           "boundary_conditions": [{"beam": n, "node": "first", "fix": root} for n in beams],
           "loads": [{"beam": "soleus", "node": "last", "traction_force": [1.0, 0.0, 0.0]}],
           "steps": [float(f) for f in LOADS],
           "probes": [{"name": n, "beam": n, "node": "last"} for n in beams],
           "output": {"dir": out_dir, "vtk": False}}
    if mode:
        raw["contact"] = {"mode": mode}
    return raw


def tendon_sections() -> list:
    """The three ANCF Section objects (outline loops, centroids, areas)."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    spec = parse_config(tendon_config(0.0, 1, "sliding", tempfile.mkdtemp()), base_dir=SOURCE.configs)
    return [b.section for b in build_model(spec).beams]


def curve_names(sec) -> list:
    return [cv.name for cv, _ in sec.loop]
