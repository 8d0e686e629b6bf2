"""The gait envelope: the paper's three subtendons over twist × muscle bias × load × material × law.

Tendon researchers run the Achilles model far from the paper's scene (one 400 N pull on the soleus
of a 45°-twisted tendon): helical twists of 0–180°, each muscle with its own share of the load
(gastrocnemius-biased 20/40/40 %, uniform, soleus-biased 60/20/20 % over soleus / medial / lateral,
the loading biases of Blank et al. 2024's FEBio study), total loads to 3 kN (walking 2.6 kN,
running 3.1–4.6 kN), soft-matrix GOH materials and friction.  ``EnvelopeCell`` is one such model
built from a shipped config: its twist, the end tractions split by the bias, root sections on a
frictionless plane (u_x = 0 over the root face, the section free in its plane), 2 axial points and
the requested levels (or a walking stride).  ``run_cell`` solves it with a given ``ancf-solve``
(this tree's or an older commit's, for before/after tables) in a child process, so that a crash is
recorded, not raised; ``grid`` names the grids of scripts/bench_envelope.py, and
envelope_summary.py states them against the targets.
"""
from __future__ import annotations

import copy
import json
import os
import subprocess
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np
import yaml

from ..contact.laws import LAWS

#: share of the total load per subtendon (soleus, medial, lateral gastrocnemius)
BIASES = {"gastrocnemius": (0.2, 0.4, 0.4), "uniform": (1 / 3, 1 / 3, 1 / 3), "soleus": (0.6, 0.2, 0.2)}
#: total end loads [N] of a monotonic column: the issue's levels to 1.2 kN, then on to 3 kN
LEVELS = (30.0, 100.0, 200.0, 400.0, 600.0, 800.0, 1000.0, 1200.0, 1600.0, 2000.0, 2500.0, 3000.0)
#: the root on a frictionless plane: u_x = 0 over the face, the section free in its plane
PLANE_ROOT = {"r": "xyz", "r_y": "xz", "r_z": "x", "r_yy": "x", "r_zz": "x", "r_yz": "x"}
BEAMS = ("soleus", "medial_gastrocnemius", "lateral_gastrocnemius")
STRIDE_COLUMNS = ("soleus_r", "gasmed_r", "gaslat_r")     # the stride files' (OpenSim's) names, BEAMS' order
CONFIGS = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "configs")
DATA = os.path.join(CONFIGS, "data")
NEO = os.path.join(CONFIGS, "achilles_type3_psi45.yaml")
GOH = tuple(os.path.join(CONFIGS, f"achilles_type3_psi45_goh{s}.yaml")
            for s in ("", "_alex", "_amir", "_optimized_see", "_solver_default", "_tendon_model"))
#: a second subject: the outlines traced from a label image (docs/geometry.md)
SUBJECT2 = os.path.join(CONFIGS, "geometry_mask_demo.yaml")
TWISTS = tuple(range(0, 181, 15))


@dataclass(frozen=True)
class EnvelopeCell:
    """One model of the envelope: the base config (its material and geometry), its twist [deg],
    bias, contact law (sliding | unilateral | the base's own: None), Coulomb friction μ (0: none),
    elements per beam, and either monotonic load levels [N] or (``stride``) the synthetic walking
    stride of the bias (configs/data/stride_walking_<bias>.csv, 100 frames, 2.63 kN peak)."""
    base: str
    twist: float
    bias: str
    law: str | None = None
    friction: float = 0.0
    elements: int = 4
    levels: tuple[float, ...] = LEVELS
    stride: bool = False
    predictor: str | None = None          # solver.predictor (None: the config's default)
    tangent: str | None = None            # solver.tangent (None: the config's default)
    augmentation: float | None = None     # contact.tangential.augmentation (None: the default)
    band_step: float | None = None        # solver.band_step (None: the default)
    section_update: str | None = None     # solver.section_update (None: the default)
    pressure_axial: int | None = None     # contact.projection.axial (None: the default)

    @property
    def name(self) -> str:
        law = self.law or "own"
        mu = f"_mu{self.friction:g}" if self.friction else ""
        stem = os.path.splitext(os.path.basename(self.base))[0]
        kind = "_stride" if self.stride else ""
        pred = (f"_{self.predictor}" if self.predictor else "") + (f"_{self.tangent}" if self.tangent else "")
        pred += f"_c{self.augmentation:g}" if self.augmentation is not None and self.friction else ""
        pred += f"_band{self.band_step:g}" if self.band_step is not None else ""
        pred += (f"_{self.section_update}" if self.section_update else "") + (
            f"_p{self.pressure_axial}" if self.pressure_axial is not None else "")
        return f"{stem}{kind}_{law}{mu}_tw{self.twist:g}_{self.bias}_e{self.elements}{pred}"


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
    if cell.stride:
        cfg["history"] = {"file": os.path.join(DATA, f"stride_walking_{cell.bias}.csv")}
        cfg["loads"] = [{"beam": n, "node": "last", "traction_force": [1.0, 0.0, 0.0], "column": c}
                        for n, c in zip(BEAMS, STRIDE_COLUMNS) if n in names]
        cfg.pop("steps", None)
    else:
        shares = BIASES[cell.bias]
        cfg["loads"] = [{"beam": n, "node": "last", "traction_force": [s, 0.0, 0.0]}
                        for n, s in zip(BEAMS, shares) if n in names]
        cfg["steps"] = [float(x) for x in cell.levels]
    cfg["probes"] = [{"name": n, "beam": n, "node": "last"} for n in names]
    contact = cfg.setdefault("contact", {})
    if cell.law is not None:
        contact["mode"] = cell.law
    if cell.pressure_axial is not None:
        contact.setdefault("projection", {})["axial"] = cell.pressure_axial
    if cell.friction:
        contact["tangential"] = {"law": "coulomb", "friction": float(cell.friction)}
        if cell.augmentation is not None:
            contact["tangential"]["augmentation"] = float(cell.augmentation)
    cfg["output"] = {"vtk": False}
    for key in ("predictor", "tangent", "band_step", "section_update"):          # the solver's, where the cell sets them
        if getattr(cell, key) is not None:
            cfg.setdefault("solver", {})[key] = getattr(cell, key)
    return cfg


@dataclass
class CellResult:
    """How a cell ended: status (completed | failed | unstable | interrupted | crashed | timeout),
    the last converged load [N], Newton iterations (all, and up to 1.2 kN), cut-backs, wall time
    [s], the run's message, where it went on with pointwise fade forces (``contact.fade_forces:
    auto``, solving/fade_switch.py; None: it did not), where it snapped past a critical point
    (solving/critical_point.py: the critical states' load levels) and where its contact search
    windows became the whole partner beam (solving/window_widening.py; None: they did not)."""
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
    solve_time: float = 0.0         # summary.json's timings.solve [s]
    pointwise_from: float | None = None   # summary.json's fade_forces_pointwise_from
    snaps: tuple = ()                     # summary.json's steps[].branch_switches[].critical_load_factor
    windows_from: float | None = None     # summary.json's search_window_whole_from
    cause: str = ""                       # summary.json's failure_cause (solving/failure_cause.py)
    passed_over: tuple = ()               # (level, reported at) past a gap of the load path (step_over.py)

    @property
    def frames(self) -> int:
        return len(self.per_level)

    @property
    def median_iterations(self) -> float:
        """Median Newton iterations per level (per frame of a stride)."""
        return float(np.median([its for _, its, _ in self.per_level])) if self.per_level else 0.0

    @property
    def cutback_levels(self) -> int:
        """Levels (frames) that took a cut-back."""
        return sum(1 for _, _, cb in self.per_level if cb)

    def row(self) -> dict:
        c = self.cell
        return {"base": os.path.basename(c.base), "law": c.law or "own", "friction": c.friction,
                "twist": c.twist, "bias": c.bias, "elements": c.elements, "stride": c.stride,
                "status": self.status, "last_level": self.last_level, "iterations": self.iterations,
                "iterations_to_1200": self.iterations_to_1200, "cutbacks": self.cutbacks,
                "cutbacks_to_1200": self.cutbacks_to_1200, "levels": self.frames,
                "median_iterations": self.median_iterations, "cutback_levels": self.cutback_levels,
                "solve_time": round(self.solve_time, 3), "wall_time": round(self.wall_time, 2),
                "message": self.message,
                "fade_forces_pointwise_from": "" if self.pointwise_from is None else self.pointwise_from,
                "snaps": ";".join(f"{x:.6g}" for x in self.snaps),
                "search_window_whole_from": "" if self.windows_from is None else self.windows_from, "cause": self.cause,
                "passed_over": ";".join(f"{lv:.6g}@{at:.6g}" for lv, at in self.passed_over)}


def solve_config(solver: list[str], cfg: dict, out: str, timeout: float | None = None):
    """Write ``cfg`` to ``out``/config.yaml and run the command ``solver`` (an ancf-solve) on it
    with its output in ``out``/run: (the finished process, or None after ``timeout`` seconds;
    the wall time; summary.json's content, or None when it wrote none)."""
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "config.yaml")
    with open(path, "w") as fh:
        yaml.safe_dump(cfg, fh, sort_keys=False)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(solver + [path, "--output-dir", os.path.join(out, "run"), "--quiet"],
                              capture_output=True, text=True, timeout=timeout,
                              env=dict(os.environ, OMPI_MCA_rmaps_base_oversubscribe="1"))
    except subprocess.TimeoutExpired:
        return None, time.perf_counter() - t0, None
    wall, summary = time.perf_counter() - t0, os.path.join(out, "run", "summary.json")
    if not os.path.isfile(summary):
        return proc, wall, None
    with open(summary) as fh:
        return proc, wall, json.load(fh)


def run_cell(cell: EnvelopeCell, solver: list[str], workdir: str, timeout: float = 900.0) -> CellResult:
    """Solve ``cell`` with the command ``solver`` (an ancf-solve) in ``workdir``/<name>: its
    outcome from summary.json, and from the exit code and stderr where there is none (a crash)."""
    proc, wall, data = solve_config(solver, cell_config(cell), os.path.join(workdir, cell.name), timeout)
    if proc is None:
        return CellResult(cell, "timeout", wall_time=wall, message=f"no answer in {timeout:g} s")
    if data is None or proc.returncode == 1:
        tail = (proc.stderr.strip().splitlines() or ["(no output)"])[-1]
        return CellResult(cell, "crashed", wall_time=wall, message=f"exit {proc.returncode}: {tail[:200]}")
    steps = data.get("steps", [])
    early = steps if cell.stride else steps[:sum(lv <= 1200.0 * (1 + 1e-12) for lv in cell.levels)]  # a step a level
    status = data.get("status", "unknown")
    return CellResult(cell, status, last_level=steps[-1]["load_factor"] if steps else 0.0,
                      iterations=int(data.get("newton_iterations", sum(s["iterations"] for s in steps))),
                      iterations_to_1200=sum(s["iterations"] for s in early),
                      cutbacks=sum(s["cutbacks"] for s in steps),
                      cutbacks_to_1200=sum(s["cutbacks"] for s in early), wall_time=wall,
                      message="" if status == "completed" else str(data.get("message", ""))[:300],
                      cause=str(data.get("failure_cause", "")),
                      per_level=[(s["load_factor"], s["iterations"], s["cutbacks"]) for s in steps],
                      solve_time=float(data.get("timings", {}).get("solve", 0.0)),
                      pointwise_from=data.get("fade_forces_pointwise_from"),
                      windows_from=data.get("search_window_whole_from"),
                      snaps=tuple(sw["critical_load_factor"] for s in steps for sw in s.get("branch_switches", [])
                                  if "critical_load_factor" in sw),
                      passed_over=tuple((s["passed_over"]["level"], s["passed_over"]["reported_at"])
                                        for s in steps if "passed_over" in s))


def _columns(base: str, laws, frictions=(0.0,), stride: bool = False):
    """A grid builder: cells of ``base`` for every law, friction, twist and bias."""
    return lambda twists, biases, elements: [
        EnvelopeCell(base, t, b, law, mu, elements=elements, stride=stride)
        for law in laws for mu in frictions for t in twists for b in biases]


SLIDING, UNILATERAL = LAWS                    # contact/laws.py, in its order
_FRICTION_STRIDES = _columns(NEO, (SLIDING,), (0.3,), stride=True)


def _strides(base: str):
    """A grid builder: the walking stride of ``base`` sliding and unilateral, then with μ = 0.3."""
    frictionless, friction = _columns(base, (SLIDING, UNILATERAL), stride=True), _columns(
        base, (SLIDING,), (0.3,), stride=True)
    return lambda twists, biases, elements: frictionless(twists, biases, elements) + friction(twists, biases, elements)


#: the named grids of scripts/bench_envelope.py: neo-Hookean columns (sliding and unilateral),
#: Coulomb μ 0.1 / 0.3 / 0.5, every shipped GOH config with its own law, strides (sliding,
#: unilateral, μ 0.3; and the μ 0.3 ones alone), the traced second subject (columns, and the
#: walking stride sliding, unilateral and with μ 0.3), and the walking stride on every shipped GOH
#: config with its own law
GRIDS = {
    "core": _columns(NEO, (SLIDING, UNILATERAL)),
    "friction": _columns(NEO, (SLIDING,), (0.1, 0.3, 0.5)),
    "fibres": lambda twists, biases, elements: [c for base in GOH for c in _columns(base, (None,))(
        twists, biases, elements)],
    "strides": _strides(NEO),
    "friction_strides": _FRICTION_STRIDES,
    "subject2": _columns(SUBJECT2, (SLIDING, UNILATERAL)),
    "subject2_strides": _strides(SUBJECT2),
    "fibre_strides": lambda twists, biases, elements: [c for base in GOH for c in _columns(
        base, (None,), stride=True)(twists, biases, elements)],
}


def grid(name: str, twists, biases, elements: int = 4, **settings) -> list[EnvelopeCell]:
    """The cells of a named grid (``GRIDS``), with the ``EnvelopeCell`` settings given (predictor,
    tangent, band_step, section_update: the solver's; pressure_axial: contact.projection.axial;
    augmentation: friction cells' contact.tangential)."""
    if name not in GRIDS:
        raise ValueError(f"unknown grid {name!r}; grids: {', '.join(GRIDS)}")
    return [replace(c, **settings) for c in GRIDS[name](twists, biases, elements)]


def run_cells(cells: list[EnvelopeCell], solvers: dict[str, list[str]], workdir: str, jobs: int,
              report=print) -> list[dict]:
    """Every cell with every solver (tag → command), ``jobs`` child processes at a time; a line
    per cell to ``report``; the rows (``CellResult.row`` and the solver's tag)."""
    work = [(tag, cmd, c) for c in cells for tag, cmd in solvers.items()]

    def one(job):
        tag, cmd, cell = job
        res = run_cell(cell, cmd, os.path.join(workdir, tag))
        report(f"{tag:6s} {cell.name:64s} {res.status:10s} last {res.last_level:6g}  Newton "
               f"{res.iterations:4d} (to 1.2 kN {res.iterations_to_1200:4d}, median {res.median_iterations:g})  "
               f"cut-backs {res.cutbacks:2d} ({res.cutback_levels} levels)  {res.wall_time:6.1f} s  "
               + ("" if res.pointwise_from is None else f"pointwise fade forces from {res.pointwise_from:g}  ")
               + f"{res.message[:100]}")
        return dict(res.row(), solver=tag)

    with ThreadPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(one, work))


def _cell_text(r: dict | None, key: str) -> str:
    """A row in a table cell, with where it switched to pointwise fade forces (fade_switch.py),
    widened its contact search windows (window_widening.py), snapped past a critical point
    (critical_point.py) and reported a level past a gap of the load path (step_over.py)."""
    if r is None:
        return "–"
    if r["status"] == "crashed":
        return "**traceback**"
    stride = str(r.get("stride", "")).lower() in ("true", "1")
    text, at = _outcome_text(r, key, stride), r.get("fade_forces_pointwise_from") or ""
    unit, where = ("frame ", "") if stride else ("", " N")
    if r.get("search_window_whole_from"):
        text += f", whole windows from {unit}{float(r['search_window_whole_from']):.4g}{where}"
    if at:
        text += f", pointwise from {unit}{float(at):.4g}{where}"
    for snap in filter(None, (r.get("snaps") or "").split(";")):
        text += f", snap at {unit}{float(snap):.4g}{where}"
    for gap in filter(None, (r.get("passed_over") or "").split(";")):
        level, at = (float(x) for x in gap.split("@"))
        text += f", {unit}{level:g}{where} past a gap at {unit}{at:.6g}{where}"
    return text


def _outcome_text(r: dict, key: str, stride: bool) -> str:
    if r["status"] != "completed":
        last = float(r["last_level"] or 0.0)
        where = (f"at frame {last:g}" if stride else f"after {last:g} N" if last > 0
                 else "in the first level")
        return f"**{r['status']}** {where}"
    if stride:                     # the frames with a cut-back, how many, and the stride's total
        cb = int(float(r.get("cutback_levels") or 0))
        if not cb:
            return f"{float(r[key]):g}"
        n = int(float(r.get("cutbacks") or cb))
        its = int(float(r.get("iterations") or 0))
        return (f"{float(r[key]):g} ({n} cut-back{'s' if n > 1 else ''} in {cb} frame{'s' if cb > 1 else ''}"
                + (f"; {its} in all)" if its else ")"))
    cb = int(float(r.get("cutbacks_to_1200", r["cutbacks"]) or 0))
    return f"{int(float(r[key]))}" + (f" ({cb} cut-back{'s' if cb > 1 else ''})" if cb else "")


def markdown_table(after: list[dict], before: list[dict] | None = None, law: str | None = None,
                   key: str = "iterations_to_1200") -> str:
    """Twist × bias of a grid's rows (CSV rows of ``run_cells``; one law): Newton iterations to
    1.2 kN (or the median per frame of strides: ``key``) and cut-backs, ``before → after``."""
    def pick(rows):
        return {(float(r["twist"]), r["bias"]): r for r in rows or [] if law is None or r["law"] == law}
    a, b = pick(after), pick(before)
    biases = [x for x in BIASES if any(k[1] == x for k in a)]
    lines = ["| twist [deg] | " + " | ".join(biases) + " |", "|---:|" + "---|" * len(biases)]
    for t in sorted({k[0] for k in a}):
        cells = []
        for bias in biases:
            now = _cell_text(a.get((t, bias)), key)
            cells.append(now if before is None else f"{_cell_text(b.get((t, bias)), key)} → {now}")
        lines.append(f"| {t:g} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _read_rows(path: str) -> list[dict] | None:
    import csv
    if not os.path.isfile(path):
        return None
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _matches(row: dict, filters: dict[str, str]) -> bool:
    """``row`` has every ``filters`` value (numbers compared as numbers, 'friction=0.3')."""
    def same(a: str, b: str) -> bool:
        try:
            return float(a) == float(b)
        except ValueError:
            return a == b
    return all(same(str(row.get(k, "")), v) for k, v in filters.items())


def render_docs(text: str, csv_dir: str) -> str:
    """``text`` (docs/gait.md) with every block ``<!-- envelope:GRID:LAW[:KEY=VALUE,…] -->`` …
    ``<!-- /envelope -->`` rendered from ``csv_dir``/gait_envelope_GRID.csv (and
    ``…_before.csv``, 38a07d3's, when it is there) by ``markdown_table``; LAW ``strides-…`` tables
    the median Newton iterations per frame, LAW ``own`` every law; the filters pick rows by their
    CSV columns (``friction=0.3``, ``base=achilles_type3_psi45_goh_amir.yaml``)."""
    import re
    pattern = re.compile(r"(<!-- envelope:(\w+):([\w-]+)(?::([^ ]+))? -->\n)(.*?)(<!-- /envelope -->)", re.S)

    def block(m):
        grid_name, law = m.group(2), m.group(3)
        filters = dict(item.split("=", 1) for item in m.group(4).split(",")) if m.group(4) else {}
        after = _read_rows(os.path.join(csv_dir, f"gait_envelope_{grid_name}.csv")) or []
        before = _read_rows(os.path.join(csv_dir, f"gait_envelope_{grid_name}_before.csv"))
        key = "iterations_to_1200"
        if law.startswith("strides-"):
            law, key = law[len("strides-"):], "median_iterations"
        if filters:
            after = [r for r in after if _matches(r, filters)]
            before = None if before is None else [r for r in before if _matches(r, filters)]
        return m.group(1) + markdown_table(after, before, None if law == "own" else law, key) + "\n" + m.group(6)

    return pattern.sub(block, text)
