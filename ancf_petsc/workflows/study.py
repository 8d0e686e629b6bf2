"""Speed–accuracy study: one scene solved with many discretisations, wall time against error.

A study file (YAML)::

    kind: pareto                              # (the default; ``kind: stability`` is stability.py)
    name: bending                             # default: the file's stem
    base: ../bending_neohookean.yaml          # the scene, relative to the study file (a bundle too;
                                              #   not a load history: its steps are solved)
    probe: tip                                # quantity of interest: a probe of the base config,
    component: z                              #   x | y | z | norm of its displacement,
    level: 1.0                                #   at this load factor (default: the last step)
    grid:                                     # Cartesian product of these (each optional)
      elements: [2, 4, 8, 16, 32]
      axial_points: [2, 3]
      cubature_degree: [4, 6]
      element: ["3363", "3333"]
    reference: {elements: 128, axial_points: 3, richardson: true}
    repeats: 1                                # timing: best of this many solves
    output: ../../studies/bending             # relative to the study file

Every discretisation (``refinement.Discretisation``) is solved in this process, serially, over
the base config's load levels up to ``level``, without ParaView output; its wall time is the
run's own (``summary.json`` timings: set-up + load stepping + output, no interpreter start-up).
The error is |q − q_ref| / |q_ref| against the reference discretisation, or against the
Richardson limit of the reference and its two coarser halvings (``richardson: true``).
Results: ``<output>/study.csv`` and the chart ``<output>/pareto.png`` (error against wall time,
log–log, with the Pareto front: the discretisations no other one beats in both).
"""
from __future__ import annotations

import copy
import csv
import itertools
import math
import os
import time
from dataclasses import asdict, dataclass, replace
from typing import Any, Callable

import yaml

from ..io.files import prepare_output_dir
from .. import yamlio
from ..config.bundle import expand_bundle
from ..config.specs import DEFAULT_AXIAL_POINTS, SectionSpec
from ..physics.elements import DEFAULT_ELEMENT, ELEMENTS
from ..errors import InputError
from ..status import CONFIG_ERROR, EXIT_INPUT
from ..io.levels import gap_note, reported_at
from .refinement import COMPONENTS, Discretisation, apply, level_step, quantity, richardson

GRID_KEYS = ("elements", "axial_points", "cubature_degree", "element")
STUDY_KEYS = ("kind", "name", "base", "probe", "component", "level", "grid", "reference",
              "repeats", "output")


class StudyError(InputError):
    """A study-file problem: ``path`` is the key path in the study file."""


def read_yaml(path: str, key: str = "") -> Any:
    """A YAML file's document; every problem (missing, a directory, binary, bad or repeated
    keys) is one StudyError naming ``key`` and, for a file a key names, the file (the
    study file itself is named by the caller)."""
    where = f"{path}: " if key else ""
    if os.path.isdir(path):
        raise StudyError(key, f"{where}is a directory, not a YAML file")
    if not os.path.isfile(path):
        raise StudyError(key, f"{where}no such file")
    try:
        return yamlio.load(yamlio.read_text(path))
    except UnicodeDecodeError:
        raise StudyError(key, f"{where}not a text (UTF-8) YAML file") from None
    except OSError as exc:
        raise StudyError(key, f"{where}cannot read: {exc.strerror}") from None
    except yaml.YAMLError as exc:
        raise StudyError(key, f"{where}{yamlio.syntax_error(exc)}") from None


@dataclass
class Scene:
    """A base config to vary, and the quantity of interest read from its runs."""
    raw: dict                       # the base config (parsed YAML)
    base_dir: str                   # its directory (relative paths inside it)
    probe: str
    component: str = "norm"
    level: float | None = None      # load factor of the quantity (None: the last step)

    def levels(self) -> list[float]:
        """The base config's load levels up to ``level``."""
        steps = [float(s) for s in self.raw["steps"]]
        if self.level is None:
            return steps
        return [s for s in steps if s <= self.level * (1.0 + 1e-12)]


@dataclass
class StudySpec:
    name: str
    scene: Scene
    grid: dict[str, list]
    reference: Discretisation
    richardson: bool
    repeats: int
    output: str


@dataclass
class Row:
    """One solved discretisation."""
    label: str
    element: str
    elements: int
    axial_points: int
    cubature_degree: int | None
    dofs: int
    gauss_points: int
    status: str
    value: float
    wall_time: float
    newton_iterations: int
    message: str = ""
    rel_error: float = math.nan
    pareto: bool = False


# ------------------------------------------------------------------------------ solving
def solve_raw(raw: dict, base_dir: str, out_dir: str, comm=None) -> tuple[Any, dict | None]:
    """Solve a raw config in this process (quietly); returns (RunResult, summary or None).

    Config errors are returned as a failed result (message = the config error), not raised.
    """
    from ..config.parse import parse_config
    from ..config.values import ConfigError
    from ..linalg.database import own_prefix
    from ..solving.run import RunResult, run_model, serial_comm
    raw = copy.deepcopy(raw)
    raw["output"] = {"dir": out_dir, "vtk": False}
    # studies measure accuracy, cost and convergence; the stability of every level stays in the
    # summary (negative_eigenvalues) instead of turning the run's status to 'unstable'
    raw.setdefault("solver", {}).setdefault("allow_unstable", True)
    comm = serial_comm() if comm is None else comm
    try:
        spec = parse_config(raw, base_dir=base_dir)
        with own_prefix(spec.solver, "study"):          # this solve's PETSc options apart
            res = run_model(spec, comm, log=lambda *_: None)
    except ConfigError as exc:
        return RunResult("config_error", str(exc), None, [], reason_code=CONFIG_ERROR, exit_code=EXIT_INPUT), None
    return res, res.summary


def _discretisation_of(raw: dict) -> tuple[str, int, int, int | None]:
    """(element, elements, axial points, cubature degree) of the first beam of a raw config; the
    degree the run integrates with (33103, 33153 raise it to ``Element.section_degree``: a grid's
    degree 2 and 4 of 33103 were two rows 'deg 2', 'deg 4' of one degree-6 run)."""
    b = raw["beams"][0]
    element = str(b.get("element", DEFAULT_ELEMENT))
    deg, least = b["section"].get("cubature_degree"), ELEMENTS[element].section_degree if element in ELEMENTS else 0
    if least and (deg is None or deg < least):
        deg = max(least, SectionSpec.cubature_degree if deg is None else deg)
    return element, int(b["elements"]), int(b.get("axial_points", DEFAULT_AXIAL_POINTS)), deg


def measure(scene: Scene, disc: Discretisation, out_dir: str, repeats: int = 1) -> Row:
    """Solve the scene with one discretisation; best wall time of ``repeats`` solves."""
    raw = apply(scene.raw, disc)
    raw["steps"] = scene.levels()
    best, summary, res = math.inf, None, None
    for _ in range(max(1, repeats)):
        res, summary = solve_raw(raw, scene.base_dir, out_dir)
        if summary is None:
            break
        best = min(best, float(summary["timings"]["total"]))
        if res.status != "completed":
            break
    element, n, ax, deg = _discretisation_of(raw)
    if disc.cubature_degree is not None and deg != disc.cubature_degree:
        disc = replace(disc, cubature_degree=deg)               # the label says the degree integrated
    ok = res.status == "completed"
    value = quantity(summary, scene.probe, scene.component, scene.level) if ok else math.nan
    dofs = int(summary["dofs"]) if summary else 0
    points = sum(int(v["points"]) for v in summary["sections"].values()) * ax * n if summary else 0
    return Row(label=disc.label() or "base", element=element, elements=n, axial_points=ax,
               cubature_degree=deg, dofs=dofs, gauss_points=points, status=res.status,
               value=value, wall_time=best if summary else math.nan,
               newton_iterations=int(summary.get("newton_iterations", 0)) if summary else 0,
               message=gap_note(reported_at(level_step(summary, scene.level)), "") if ok else res.message)


def reference_value(scene: Scene, ref: Discretisation, extrapolate: bool, out_dir: str,
                    log: Callable[[str], None] = print) -> tuple[float, list[Row], str]:
    """The reference quantity: the reference discretisation's value, or the Richardson limit
    of it and its two halvings in element count.  Returns (value, rows, description)."""
    n = ref.elements or _discretisation_of(scene.raw)[1]
    counts = halvings(n) if extrapolate else [n]
    rows = []
    for k in counts:
        d = Discretisation(elements=k, axial_points=ref.axial_points,
                           cubature_degree=ref.cubature_degree, element=ref.element)
        row = measure(scene, d, os.path.join(out_dir, f"reference_{k}"))
        log(f"[study] reference {row.label}: {scene.probe} = {row.value:.10g} ({row.status}, "
            f"{row.wall_time:.2f} s)")
        if row.status != "completed":
            raise StudyError("reference", f"the reference run ({row.label}) did not complete: "
                                          f"{row.message}")
        rows.append(row)
    if not extrapolate:
        return rows[-1].value, rows, f"{rows[-1].label}"
    ex = richardson(*(r.value for r in rows))
    if not ex.reliable:
        log(f"[study] Richardson extrapolation unreliable (no monotone convergence); using {rows[-1].label}")
        return rows[-1].value, rows, f"{rows[-1].label} (extrapolation unreliable)"
    return ex.limit, rows, (f"Richardson limit of {', '.join(str(r.elements) for r in rows)} "
                            f"elements (observed order {ex.order:.2f})")


def halvings(n: int) -> list[int]:
    """n/4, n/2, n elements: ``richardson``'s meshes, each refined by 2 (10 gave 2, 5, 10)."""
    expect(n >= 4 and n % 4 == 0, "reference.elements", "Richardson extrapolates from n/4, n/2 and n "
           f"elements, each twice the last: give a multiple of 4, e.g. {max(4, n - n % 4)}; got {n}")
    return [n // 4, n // 2, n]


def check_reference(scene: Scene, ref: float) -> float:
    """The reference value, refused when it is 0: the errors are relative to it."""
    expect(ref != 0.0, "component", f"the reference's {scene.probe} {scene.component} is 0 (a held or "
                                    "symmetric component): errors relative to it are undefined; study "
                                    f"another component or probe; got {scene.component}")
    return ref


def pareto_front(rows: list[Row]) -> list[int]:
    """Indices of the completed rows that no other completed row beats in both time and error."""
    ok = [i for i, r in enumerate(rows) if r.status == "completed" and math.isfinite(r.rel_error)]
    front = []
    for i in ok:
        ti, ei = rows[i].wall_time, rows[i].rel_error
        if not any(rows[j].wall_time <= ti and rows[j].rel_error <= ei
                   and (rows[j].wall_time < ti or rows[j].rel_error < ei) for j in ok if j != i):
            front.append(i)
    return sorted(front, key=lambda i: rows[i].wall_time)


def grid_points(grid: dict[str, list]) -> list[Discretisation]:
    """The Cartesian product of the grid's axes as discretisations."""
    keys = [k for k in GRID_KEYS if k in grid]
    return [Discretisation(**dict(zip(keys, combo)))
            for combo in itertools.product(*(grid[k] for k in keys))]


CSV_FIELDS = ("label", "element", "elements", "axial_points", "cubature_degree", "dofs",
              "gauss_points", "status", "value", "rel_error", "wall_time", "newton_iterations",
              "pareto", "message")


def write_csv(rows: list[Row], path: str) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=CSV_FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in asdict(r).items()})


def run_study(spec: StudySpec, log: Callable[[str], None] = print) -> dict:
    """Solve the reference and every grid point; write study.csv and pareto.png."""
    from ..viz.charts import pareto_chart
    prepare_output_dir(spec.output, "output / --out")   # OutputError naming the path and keys
    t0 = time.perf_counter()
    ref, ref_rows, ref_text = reference_value(spec.scene, spec.reference, spec.richardson,
                                              spec.output, log)
    check_reference(spec.scene, ref)
    points = grid_points(spec.grid)
    rows = []
    for k, d in enumerate(points):
        row = measure(spec.scene, d, os.path.join(spec.output, f"run_{k:03d}"), spec.repeats)
        row.rel_error = abs(row.value - ref) / abs(ref) if row.status == "completed" else math.nan
        rows.append(row)
        log(f"[study] {k + 1}/{len(points)} {row.label:28s} {row.status:9s} {row.wall_time:7.2f} s  "
            f"error {row.rel_error:.2e}  ({row.dofs} DOFs, {row.newton_iterations} Newton its)")
    for i in pareto_front(rows):
        rows[i].pareto = True
    csv_path = os.path.join(spec.output, "study.csv")
    write_csv(rows, csv_path)
    comp = spec.scene.component
    what = "displacement magnitude" if comp == "norm" else f"{comp}-displacement"
    title = (f"{spec.name.replace('_', ' ')}: {what} of probe '{spec.scene.probe}' at load factor "
             f"{spec.scene.levels()[-1]:g}")
    png = pareto_chart(rows, os.path.join(spec.output, "pareto.png"), title, ref_text)
    log(f"[study] reference: {ref_text} = {ref:.10g}")
    log("[study] Pareto front: " + "; ".join(f"{r.label} ({r.wall_time:.2f} s, {r.rel_error:.1e})"
                                             for r in rows if r.pareto))
    log(f"[study] {len(rows)} runs in {time.perf_counter() - t0:.1f} s; {csv_path}, {png}")
    return {"reference": ref, "reference_text": ref_text, "reference_rows": ref_rows, "rows": rows,
            "csv": csv_path, "png": png}


# ------------------------------------------------------------------------------ study files
def expect(cond: bool, path: str, message: str) -> None:
    if not cond:
        raise StudyError(path, message)


def load_base(path: str, key: str = "base") -> tuple[dict, str]:
    """The base config of a study file: (raw YAML, its directory)."""
    expect(os.path.isfile(path), key, f"file not found: {path} (relative to the study file)")
    raw = read_yaml(path, key)
    if isinstance(raw, dict) and "bundle" in raw:    # its beams, loads and probes, as ancf-solve makes them
        try:
            raw = expand_bundle(raw)
        except InputError as exc:
            raise StudyError(key, f"{path}: {exc}") from None
    expect(isinstance(raw, dict) and ("beams" in raw or "history" in raw), key,
            f"{path} is not a model config (no beams or bundle)")
    expect("steps" in raw, key, f"{path} follows a load history: a study solves a config's steps; "
                                "give steps instead of history")
    return raw, os.path.dirname(os.path.abspath(path))


def parse_scene(doc: dict, here: str) -> Scene:
    """The ``base``, ``probe``, ``component`` and ``level`` keys of a study file."""
    expect("base" in doc, "base", "missing value (required): the model config to study")
    raw, base_dir = load_base(os.path.join(here, str(doc["base"])))
    probes = [p.get("name") for p in raw.get("probes", []) if isinstance(p, dict)]
    probe = doc.get("probe")
    expect(probe in probes, "probe", f"no probe {probe!r} in the base config (have: "
                                      f"{', '.join(map(str, probes)) or 'none'})")
    component = doc.get("component", "norm")
    expect(component in COMPONENTS, "component", f"must be one of {', '.join(COMPONENTS)}; "
                                                  f"got {component!r}")
    level = doc.get("level")
    if level is not None:
        steps = [float(s) for s in raw["steps"]]
        expect(isinstance(level, (int, float)) and any(math.isclose(level, s, rel_tol=1e-12)
                                                        for s in steps),
                "level", f"must be one of the base config's steps ({', '.join(f'{s:g}' for s in steps)})")
        level = float(level)
    return Scene(raw, base_dir, probe, component, level)


def _int_list(value: Any, path: str, lo: int = 1) -> list[int]:
    expect(isinstance(value, list) and value and all(isinstance(v, int) and not isinstance(v, bool)
                                                      and v >= lo for v in value),
            path, f"expected a non-empty list of integers >= {lo}; got {value!r}")
    return list(value)


def parse_discretisation(value: Any, path: str, extra: tuple = ()) -> dict:
    """A mapping of single discretisation values (``reference:``)."""
    expect(isinstance(value, dict), path, f"expected a mapping with keys {', '.join(GRID_KEYS + extra)}")
    for key in value:
        expect(key in GRID_KEYS + extra, f"{path}.{key}",
                f"unknown key; allowed here: {', '.join(GRID_KEYS + extra)}")
    out = {}
    for key in GRID_KEYS:
        if key in value:
            out[key] = parse_grid({key: [value[key]]}, path)[key][0]
    return out


def parse_grid(value: Any, path: str = "grid") -> dict[str, list]:
    from ..physics.elements import element_names
    expect(isinstance(value, dict) and value, path,
            f"expected a mapping of lists over {', '.join(GRID_KEYS)}")
    out = {}
    for key, vals in value.items():
        kp = f"{path}.{key}"
        expect(key in GRID_KEYS, kp, f"unknown key; allowed here: {', '.join(GRID_KEYS)}")
        if key == "element":
            vals = [str(v) for v in vals] if isinstance(vals, list) else vals
            expect(isinstance(vals, list) and vals and all(v in element_names() for v in vals), kp,
                    f"expected a list of element types from {', '.join(element_names())}; got {vals!r}")
            out[key] = vals
        else:
            out[key] = _int_list(vals, kp)
    return out


def load_study(path: str) -> StudySpec:
    """Read and check a study file (``kind: pareto``)."""
    doc = read_yaml(path)
    expect(isinstance(doc, dict), "", yamlio.not_a_mapping(doc, STUDY_KEYS))
    for key in doc:
        expect(key in STUDY_KEYS, key, f"unknown key; allowed: {', '.join(STUDY_KEYS)}")
    here = os.path.dirname(os.path.abspath(path))
    scene = parse_scene(doc, here)
    expect("grid" in doc, "grid", "missing value (required): lists of elements, axial_points, "
                                   "cubature_degree and/or element to try")
    grid = parse_grid(doc["grid"])
    ref = parse_discretisation(doc.get("reference", {}), "reference", ("richardson",))
    extrapolate = doc.get("reference", {}).get("richardson", False)
    expect(isinstance(extrapolate, bool), "reference.richardson", "expected true or false")
    if extrapolate:
        halvings(ref.get("elements") or _discretisation_of(scene.raw)[1])
    repeats = doc.get("repeats", 1)
    expect(isinstance(repeats, int) and repeats >= 1, "repeats", "expected an integer >= 1")
    name = doc.get("name", os.path.splitext(os.path.basename(path))[0])
    output = os.path.normpath(os.path.join(here, str(doc.get("output", os.path.join("studies", name)))))
    return StudySpec(name=str(name), scene=scene, grid=grid, reference=Discretisation(**ref),
                     richardson=extrapolate, repeats=repeats, output=output)
