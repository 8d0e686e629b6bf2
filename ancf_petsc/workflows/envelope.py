"""The gait envelope: the paper's three subtendons over twist × muscle bias × load × material × law.

Tendon researchers run the Achilles model far from the paper's scene (one 400 N pull on the soleus
of a 45°-twisted tendon): helical twists of 0–180°, each muscle with its own share of the load
(gastrocnemius-biased 20/40/40 %, uniform, soleus-biased 60/20/20 % over soleus / medial / lateral,
the loading biases of Blank et al. 2024's FEBio study), total loads to 3 kN (walking 2.6 kN,
running 3.1–4.6 kN), soft-matrix GOH materials and friction.  ``EnvelopeCell`` is one such model
built from a shipped config: its twist, the end tractions split by the bias, root sections on a
frictionless plane (u_x = 0 over the root face, the section free in its plane), 2 axial points and
the requested levels.  ``run_cell`` solves it with a given ``ancf-solve`` (this tree's or an older
commit's, for before/after tables) in a child process, so that a crash is recorded, not raised.
"""
from __future__ import annotations

import copy
import json
import os
import subprocess
import time
from dataclasses import dataclass, field

import yaml

#: share of the total load per subtendon (soleus, medial, lateral gastrocnemius)
BIASES = {"gastrocnemius": (0.2, 0.4, 0.4), "uniform": (1 / 3, 1 / 3, 1 / 3), "soleus": (0.6, 0.2, 0.2)}
#: total end loads [N] of a monotonic column: the issue's levels to 1.2 kN, then on to 3 kN
LEVELS = (30.0, 100.0, 200.0, 400.0, 600.0, 800.0, 1000.0, 1200.0, 1600.0, 2000.0, 2500.0, 3000.0)
#: the root on a frictionless plane: u_x = 0 over the face, the section free in its plane
PLANE_ROOT = {"r": "xyz", "r_y": "xz", "r_z": "x", "r_yy": "x", "r_zz": "x", "r_yz": "x"}
BEAMS = ("soleus", "medial_gastrocnemius", "lateral_gastrocnemius")


@dataclass(frozen=True)
class EnvelopeCell:
    """One model of the envelope: the base config (its material and geometry), its twist [deg],
    bias, contact law (sliding | unilateral | the base's own: None), Coulomb friction μ (0: none),
    elements per beam and load levels [N]."""
    base: str
    twist: float
    bias: str
    law: str | None = None
    friction: float = 0.0
    elements: int = 4
    levels: tuple[float, ...] = LEVELS

    @property
    def name(self) -> str:
        law = self.law or "own"
        mu = f"_mu{self.friction:g}" if self.friction else ""
        stem = os.path.splitext(os.path.basename(self.base))[0]
        return f"{stem}_{law}{mu}_tw{self.twist:g}_{self.bias}_e{self.elements}"


def cell_config(cell: EnvelopeCell) -> dict:
    """The config of ``cell`` (a dict to write as YAML), from its base config."""
    with open(cell.base) as fh:
        cfg = yaml.safe_load(fh)
    cfg = copy.deepcopy(cfg)
    here = os.path.dirname(os.path.abspath(cell.base))
    cfg["name"] = cell.name
    cfg.setdefault("geometry", {})["twist_deg"] = float(cell.twist)
    geo_sections = cfg["geometry"].get("sections")
    if isinstance(geo_sections, dict) and "file" in geo_sections:
        geo_sections["file"] = os.path.join(here, geo_sections["file"])
    names = [b["name"] for b in cfg["beams"]]
    for b in cfg["beams"]:
        sec = b.get("section", {})
        if "file" in sec:
            sec["file"] = os.path.join(here, sec["file"])
        b["elements"] = cell.elements
        b["axial_points"] = 2
    cfg["boundary_conditions"] = [{"beam": n, "node": "first", "fix": dict(PLANE_ROOT)} for n in names]
    shares = BIASES[cell.bias]
    cfg["loads"] = [{"beam": n, "node": "last", "traction_force": [s, 0.0, 0.0]}
                    for n, s in zip(BEAMS, shares) if n in names]
    cfg["steps"] = [float(x) for x in cell.levels]
    cfg["probes"] = [{"name": n, "beam": n, "node": "last"} for n in names]
    contact = cfg.setdefault("contact", {})
    if cell.law is not None:
        contact["mode"] = cell.law
    if cell.friction:
        contact["tangential"] = {"law": "coulomb", "friction": float(cell.friction)}
    cfg["output"] = {"vtk": False}
    return cfg


@dataclass
class CellResult:
    """How a cell ended: status (completed | failed | unstable | interrupted | crashed | timeout),
    the last converged load [N], Newton iterations (all, and up to 1.2 kN), cut-backs, wall time
    [s] and the run's message."""
    cell: EnvelopeCell
    status: str
    last_level: float = 0.0
    iterations: int = 0
    iterations_to_1200: int = 0
    cutbacks: int = 0
    cutbacks_to_1200: int = 0
    wall_time: float = 0.0
    message: str = ""
    per_level: list = field(default_factory=list)

    def row(self) -> dict:
        c = self.cell
        return {"base": os.path.basename(c.base), "law": c.law or "own", "friction": c.friction,
                "twist": c.twist, "bias": c.bias, "elements": c.elements, "status": self.status,
                "last_level": self.last_level, "iterations": self.iterations,
                "iterations_to_1200": self.iterations_to_1200, "cutbacks": self.cutbacks,
                "cutbacks_to_1200": self.cutbacks_to_1200, "wall_time": round(self.wall_time, 2),
                "message": self.message}


def run_cell(cell: EnvelopeCell, solver: list[str], workdir: str, timeout: float = 900.0) -> CellResult:
    """Solve ``cell`` with the command ``solver`` (an ancf-solve) in ``workdir``/<name>: its
    outcome from summary.json, and from the exit code and stderr where there is none (a crash)."""
    out = os.path.join(workdir, cell.name)
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "config.yaml")
    with open(path, "w") as fh:
        yaml.safe_dump(cell_config(cell), fh, sort_keys=False)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(solver + [path, "--output-dir", os.path.join(out, "run"), "--quiet"],
                              capture_output=True, text=True, timeout=timeout,
                              env=dict(os.environ, OMPI_MCA_rmaps_base_oversubscribe="1"))
    except subprocess.TimeoutExpired:
        return CellResult(cell, "timeout", wall_time=time.perf_counter() - t0,
                          message=f"no answer in {timeout:g} s")
    wall = time.perf_counter() - t0
    summary = os.path.join(out, "run", "summary.json")
    data = None
    if os.path.isfile(summary):
        with open(summary) as fh:
            data = json.load(fh)
    if data is None or proc.returncode == 1:
        tail = (proc.stderr.strip().splitlines() or ["(no output)"])[-1]
        return CellResult(cell, "crashed", wall_time=wall, message=f"exit {proc.returncode}: {tail[:200]}")
    steps = data.get("steps", [])
    early = [s for s in steps if s["load_factor"] <= 1200.0 * (1 + 1e-12)]
    status = data.get("status", "unknown")
    return CellResult(cell, status, last_level=steps[-1]["load_factor"] if steps else 0.0,
                      iterations=int(data.get("newton_iterations", sum(s["iterations"] for s in steps))),
                      iterations_to_1200=sum(s["iterations"] for s in early),
                      cutbacks=sum(s["cutbacks"] for s in steps),
                      cutbacks_to_1200=sum(s["cutbacks"] for s in early), wall_time=wall,
                      message="" if status == "completed" else str(data.get("message", ""))[:300],
                      per_level=[(s["load_factor"], s["iterations"], s["cutbacks"]) for s in steps])
