"""YAML config → validated ``ModelSpec`` (SI units).  Every error names its key path and the fix.

Nothing is computed here beyond checking; ``model.build_model`` turns the spec into arrays.
The keys are documented in README.md ("Config reference").
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any

import yaml

from ..physics.element3363 import ELEMENT_TYPES, VECTORS
from ..errors import InputError

LOCKING = ("none", "ecm")
SECTION_SHAPES = ("ellipse", "circle", "rectangle", "outline")
MATERIAL_MODELS = ("neo-hookean", "svk")
CONTACT_MODES = ("sliding", "unilateral")


#: a config problem: ``path`` is the key path (e.g. ``beams[0].material.mu``); see errors.py
ConfigError = InputError


# --------------------------------------------------------------------------------- primitives
def _join(path: str, key) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else str(key)


def _fmt(v) -> str:
    s = repr(v)
    return s if len(s) < 60 else s[:57] + "..."


def mapping(value, path: str, required: tuple = (), optional: tuple = ()) -> dict:
    """Check a mapping with exactly the given keys (required ones present, no unknown ones)."""
    if not isinstance(value, dict):
        raise ConfigError(path, f"expected a mapping with keys {', '.join(required + optional)}; "
                                f"got {type(value).__name__} {_fmt(value)}")
    allowed = set(required) | set(optional)
    for key in value:
        if key not in allowed:
            raise ConfigError(_join(path, key), "unknown key; allowed here: "
                              + ", ".join(sorted(allowed)))
    for key in required:
        if key not in value or value[key] is None:
            raise ConfigError(_join(path, key), "missing value (required)")
    return value


def number(value, path: str, *, positive=False, nonneg=False, lo=None, hi=None,
           hint: str = "") -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        if isinstance(value, str):
            try:
                value = float(value)
            except ValueError:
                raise ConfigError(path, f"expected a number{hint}; got {_fmt(value)}") from None
        else:
            raise ConfigError(path, f"expected a number{hint}; got {_fmt(value)}")
    value = float(value)
    if not math.isfinite(value):
        raise ConfigError(path, f"must be finite; got {value}")
    if positive and value <= 0:
        raise ConfigError(path, f"must be > 0{hint}; got {value:g}")
    if nonneg and value < 0:
        raise ConfigError(path, f"must be >= 0{hint}; got {value:g}")
    if lo is not None and value < lo:
        raise ConfigError(path, f"must be >= {lo:g}{hint}; got {value:g}")
    if hi is not None and value > hi:
        raise ConfigError(path, f"must be <= {hi:g}{hint}; got {value:g}")
    return value


def integer(value, path: str, *, lo: int | None = None, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(path, f"expected an integer; got {_fmt(value)}")
    if lo is not None and value < lo:
        raise ConfigError(path, f"must be >= {lo}; got {value}")
    if hi is not None and value > hi:
        raise ConfigError(path, f"must be <= {hi}; got {value}")
    return value


def string(value, path: str, choices: tuple | None = None) -> str:
    if not isinstance(value, str) or not value:
        raise ConfigError(path, f"expected a non-empty string; got {_fmt(value)}")
    if choices is not None and value not in choices:
        raise ConfigError(path, f"must be one of {', '.join(choices)}; got {_fmt(value)}")
    return value


def boolean(value, path: str) -> bool:
    if not isinstance(value, bool):
        raise ConfigError(path, f"expected true or false; got {_fmt(value)}")
    return value


def vector(value, path: str, n: int, **kw) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise ConfigError(path, f"expected a list of {n} numbers; got {_fmt(value)}")
    return tuple(number(v, _join(path, i), **kw) for i, v in enumerate(value))


def sequence(value, path: str, *, nonempty=True) -> list:
    if not isinstance(value, list):
        raise ConfigError(path, f"expected a list; got {_fmt(value)}")
    if nonempty and not value:
        raise ConfigError(path, "expected a non-empty list")
    return value


# --------------------------------------------------------------------------------- spec types
@dataclass
class SectionSpec:
    shape: str
    center: tuple[float, float] = (0.0, 0.0)
    semi_axes: tuple[float, float] | None = None
    radius: float | None = None
    size: tuple[float, float] | None = None
    curves: list | None = None            # inline outline: [{name, points}]
    file: str | None = None               # sections file (Type III format)
    loop: str | None = None
    spline_degree: int = 3
    cubature_degree: int = 6
    compress: bool = True
    spline_degree_given: bool = False


# Gauss points along ξ per element.  2 (reduced integration along the beam) is the
# accurate rule: 3 (the paper's full rule) shear- and volume-locks slender or clamped beams
# (docs/verification.md, "Locking"); configs that reproduce the paper state axial_points: 3.
DEFAULT_AXIAL_POINTS = 2


@dataclass
class BeamSpec:
    name: str
    section: SectionSpec
    material: dict
    elements: int
    axial_points: int = DEFAULT_AXIAL_POINTS
    element: str = "3363"                 # element type, see element3363.ELEMENT_VECTORS
    locking: str = "none"                 # 'ecm': Poisson-locking remedy (model.Beam.parts)


@dataclass
class BCSpec:
    beam: int
    node: int
    dofs: list[tuple[int, int]]           # (vector slot 0..5, component 0..2)
    path: str = ""


@dataclass
class LoadSpec:
    beam: int
    node: int
    kind: str                             # 'force' | 'traction_force'
    force: tuple[float, float, float]
    path: str = ""


@dataclass
class ProbeSpec:
    name: str
    beam: int
    node: int
    vector: str = "r"


@dataclass
class ContactSpec:
    mode: str = "sliding"                  # sliding | unilateral (contact/laws.py)
    interfaces: list = field(default_factory=list)   # [(beam_a, beam_b, curve name or None)]
    axial_points: int = 3
    curve_points: int = 2
    search_margin: float = 0.1            # fraction of the beam length a point may slide
    # Bernstein degrees (along the beam, across the interface) of the contact pressure
    # (contact/multipliers.py).  Default: the trace of the elements along the beam
    # (axial_points − 1), linear across (1): docs/contact.md, "Which pressure space"
    projection: tuple[int, int] = (2, 1)
    per_element: bool = False             # pressure discontinuous between A elements
    scaling: float = 1.0                  # factor on k_s, the multipliers' unit (no effect on answers)


@dataclass
class SolverSpec:
    max_increment: float | None = None
    initial_increment: float | None = None    # first increment (default: the first level)
    min_increment: float = 1e-4
    max_cutbacks: int = 12
    growth: float = 2.0
    easy_iterations: int = 8
    predictor: str = "secant"              # none | secant (extrapolate the last increment)
    merit: str = "energy"                 # what bt/l2 line searches decrease: energy | residual
    min_det_f: float = 0.1                # Newton steps are shortened to keep det F above this
    max_newton_iterations: int | None = None   # budget for the whole run (None: no limit)
    stability_cutbacks: int = 4           # retries with smaller steps when a step lands less stable
    matrix: str = "auto"                  # Jacobian storage: auto | aij | sbaij (solver.matrix_type)
    allow_unstable: bool = False          # True: levels with negative tangent eigenvalues are accepted


@dataclass
class OutputSpec:
    dir: str
    vtk: bool = True
    vtk_samples: int = 4


@dataclass
class AccuracySpec:
    """``accuracy:``: pick the coarsest element count whose probe is within rtol (refinement.py)."""
    probe: str
    rtol: float = 1e-3
    component: str = "norm"               # x | y | z | norm of the probe's displacement
    level: float | None = None            # load factor the probe is read at (default: last step)
    start: int = 1                        # elements of the first beam on the first rung
    max_elements: int = 64


@dataclass
class ModelSpec:
    name: str
    length: float
    twist_deg: float
    twist_axis: tuple[float, float]
    beams: list[BeamSpec]
    boundary_conditions: list[BCSpec]
    loads: list[LoadSpec]
    steps: list[float]
    probes: list[ProbeSpec]
    output: OutputSpec
    solver: SolverSpec
    petsc: dict[str, str]
    contact: ContactSpec | None
    base_dir: str
    raw: dict = field(repr=False, default_factory=dict)
    partition: str = "blocks"              # 'blocks' (contiguous per beam) or 'metis'
    accuracy: AccuracySpec | None = None
    sections: Any = None                   # geometry.sections (geometry_input.spec.SectionsSpec)
    twist_rule: tuple = ("point",)         # twist-axis rule (model.resolve_twist_axis); twist_axis then
    twist_default: bool = False            # holds the resolved point; True: the rule was not given

    def beam_index(self, name: str) -> int:
        return [b.name for b in self.beams].index(name)


# --------------------------------------------------------------------------------- sections
def _section(value, path: str, base_dir: str) -> SectionSpec:
    common = ("shape", "center", "cubature_degree")
    shape = string(mapping(value, path, required=("shape",),
                           optional=common[1:] + ("semi_axes", "radius", "size", "curves", "file",
                                                  "loop", "spline_degree", "compress"))["shape"],
                   _join(path, "shape"), SECTION_SHAPES)
    per_shape = {"ellipse": ("semi_axes",), "circle": ("radius",), "rectangle": ("size",),
                 "outline": ()}
    opt_outline = ("curves", "file", "loop", "spline_degree", "compress")
    allowed_extra = per_shape[shape] + (opt_outline if shape == "outline" else ())
    mapping(value, path, required=("shape",) + per_shape[shape], optional=common[1:] + allowed_extra)
    s = SectionSpec(shape=shape)
    if "center" in value:
        s.center = vector(value["center"], _join(path, "center"), 2)
    if "cubature_degree" in value:
        s.cubature_degree = integer(value["cubature_degree"], _join(path, "cubature_degree"), lo=1, hi=30)
    if shape == "ellipse":
        s.semi_axes = vector(value["semi_axes"], _join(path, "semi_axes"), 2, positive=True)
    elif shape == "circle":
        s.radius = number(value["radius"], _join(path, "radius"), positive=True, hint=" (metres)")
    elif shape == "rectangle":
        s.size = vector(value["size"], _join(path, "size"), 2, positive=True)
    else:
        has_curves, has_file = "curves" in value, "file" in value
        if has_curves == has_file and not (has_curves is False and "loop" in value):
            raise ConfigError(path, "an outline needs either 'curves' (inline loop of point lists), "
                                    "'file' + 'loop' (sections file) or 'loop' alone (an outline of "
                                    "geometry.sections), not both/neither")
        if not has_curves and not has_file:
            s.loop = string(value["loop"], _join(path, "loop"))
        elif has_file:
            mapping(value, path, required=("shape", "file", "loop"), optional=common[1:] + opt_outline)
            f = string(value["file"], _join(path, "file"))
            s.file = f if os.path.isabs(f) else os.path.normpath(os.path.join(base_dir, f))
            if not os.path.isfile(s.file):
                raise ConfigError(_join(path, "file"), f"file not found: {s.file} "
                                  "(paths are relative to the config file)")
            s.loop = string(value["loop"], _join(path, "loop"))
        else:
            curves = sequence(value["curves"], _join(path, "curves"))
            out = []
            for i, c in enumerate(curves):
                cp = _join(_join(path, "curves"), i)
                mapping(c, cp, required=("points",), optional=("name",))
                pts = sequence(c["points"], _join(cp, "points"))
                if len(pts) < 2:
                    raise ConfigError(_join(cp, "points"), "a curve needs at least 2 points")
                pts = [vector(p, _join(_join(cp, "points"), j), 2) for j, p in enumerate(pts)]
                entry = {"points": pts}
                if "name" in c:      # named curves shared by two outlines are contact interfaces
                    entry["name"] = string(c["name"], _join(cp, "name"))
                out.append(entry)
            s.curves = out
        if "spline_degree" in value:
            s.spline_degree = integer(value["spline_degree"], _join(path, "spline_degree"), lo=1, hi=7)
            s.spline_degree_given = True
        if "compress" in value:
            s.compress = boolean(value["compress"], _join(path, "compress"))
    return s


def _material(value, path: str) -> dict:
    model = string(mapping(value, path, required=("model",),
                           optional=("mu", "bulk_modulus", "c10", "d", "E", "nu"))["model"],
                   _join(path, "model"), MATERIAL_MODELS)
    ours, papers = [k for k in ("mu", "bulk_modulus") if k in value], [k for k in ("c10", "d") if k in value]
    if model == "neo-hookean" and ours and papers:
        raise ConfigError(path, f"give either mu and bulk_modulus or the paper's c10 and d "
                                f"(mu = 2 c10, bulk_modulus = d), not both; got {', '.join(ours + papers)}")
    if model == "svk":
        mapping(value, path, required=("model", "E", "nu"))
        nu = number(value["nu"], _join(path, "nu"), lo=-0.999, hint=" (Poisson ratio)")
        if nu >= 0.5:
            raise ConfigError(_join(path, "nu"), f"must be < 0.5 for St. Venant-Kirchhoff; got {nu:g}")
        return {"model": model, "E": number(value["E"], _join(path, "E"), positive=True,
                                            hint=" (Young's modulus in Pa)"), "nu": nu}
    if "mu" in value or "bulk_modulus" in value:
        mapping(value, path, required=("model", "mu", "bulk_modulus"))
        mu = number(value["mu"], _join(path, "mu"), positive=True, hint=" (shear modulus in Pa)")
        K = number(value["bulk_modulus"], _join(path, "bulk_modulus"), positive=True,
                   hint=" (bulk modulus in Pa)")
    elif "c10" in value or "d" in value:
        # the paper's form: Ψ = c10 (Ī₁ − 3) + d/2 (J − 1)²  →  μ = 2 c10, K = d
        mapping(value, path, required=("model", "c10", "d"))
        mu = 2.0 * number(value["c10"], _join(path, "c10"), positive=True, hint=" (Pa)")
        K = number(value["d"], _join(path, "d"), positive=True, hint=" (Pa)")
    else:
        raise ConfigError(path, "neo-hookean needs 'mu' and 'bulk_modulus' (or the paper's "
                                "'c10' and 'd', with mu = 2 c10, bulk_modulus = d)")
    return {"model": model, "mu": mu, "bulk_modulus": K}


# --------------------------------------------------------------------------------- top level
def _node_ref(value, path: str, n_nodes: int) -> int:
    if value == "first":
        return 0
    if value == "last":
        return n_nodes - 1
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(path, f"expected 'first', 'last' or a node index; got {_fmt(value)}")
    idx = value + n_nodes if value < 0 else value
    if not 0 <= idx < n_nodes:
        raise ConfigError(path, f"node {value} does not exist; this beam has nodes 0..{n_nodes - 1}")
    return idx


def _beam_ref(value, path: str, names: list[str]) -> int:
    if value not in names:
        raise ConfigError(path, f"unknown beam {_fmt(value)}; beams are: {', '.join(names)}")
    return names.index(value)


FIX_PRESETS = {
    "clamped": [(v, c) for v in range(6) for c in range(3)],
    # the paper's "r fixed, cross-section free to contract": all but r_y·e_y and r_z·e_z
    "reduced": [(v, c) for v in range(6) for c in range(3) if (v, c) not in ((1, 1), (2, 2))],
}


def _fix(value, path: str) -> list[tuple[int, int]]:
    if isinstance(value, str):
        if value not in FIX_PRESETS:
            raise ConfigError(path, f"unknown preset {_fmt(value)}; use clamped, reduced or a "
                                    "mapping like {r: xyz, r_y: xz}")
        return list(FIX_PRESETS[value])
    mapping(value, path, optional=VECTORS)
    dofs = []
    for name, comps in value.items():
        cp = _join(path, name)
        if not isinstance(comps, str) or not comps or any(c not in "xyz" for c in comps) \
                or len(set(comps)) != len(comps):
            raise ConfigError(cp, f"expected components as a string from 'xyz' (e.g. xz); "
                                  f"got {_fmt(comps)}")
        dofs += [(VECTORS.index(name), "xyz".index(c)) for c in comps]
    if not dofs:
        raise ConfigError(path, "fixes nothing; name at least one vector, e.g. {r: xyz}")
    return sorted(dofs)


def _axial_points(value, path: str) -> int:
    """Gauss points along ξ: one point leaves the three-node element's stiffness singular."""
    n = integer(value, path, hi=10)
    if n < 2:
        raise ConfigError(path, f"must be >= 2; got {n}: one point along the beam leaves the "
                                "three-node element's stiffness singular (zero-energy modes); "
                                "use 2 (reduced) or 3 (full, the paper's)")
    return n


def _name(value) -> str:
    """The model's name, which names its default output directory results/<name>."""
    name = string(value, "name")
    if "/" in name or "\\" in name or name.startswith(".") or not name.isprintable():
        raise ConfigError("name", f"it names the output directory results/<name>: no '/', '\\', "
                                  f"leading '.' or control characters; got {_fmt(name)}")
    return name


def _petsc(value) -> dict[str, str]:
    """``petsc:`` options as PETSc will read them (values checked like PETSc parses them)."""
    from .petsc_options import check_value
    if not isinstance(value, dict):
        raise ConfigError("petsc", "expected a mapping of PETSc options, e.g. {snes_rtol: 1e-10}")
    petsc = {}
    for k, v in value.items():
        if not isinstance(k, str) or not k.strip("-"):
            raise ConfigError(f"petsc.{k}", "option names are strings like snes_monitor")
        if isinstance(v, (dict, list)):
            raise ConfigError(f"petsc.{k}", "option values are scalars (number, string, true/false)")
        name = k.lstrip("-")
        text = "" if v is None or v is True else ("0" if v is False else str(v))
        why = check_value(name, None if v is None or v is True else text)
        if why:
            raise ConfigError(f"petsc.{k}", why)
        petsc[name] = text
    return petsc


PARTITION_METHODS = ("blocks", "metis")
TOP_KEYS = ("name", "units", "geometry", "beams", "boundary_conditions", "loads", "steps",
            "probes", "output", "solver", "petsc", "contact", "partition", "bundle", "accuracy")


def parse_config(raw: Any, base_dir: str = ".", source: str = "config") -> ModelSpec:
    """Validate a loaded YAML document and return the ``ModelSpec``."""
    if isinstance(raw, dict) and "bundle" in raw:
        from .bundle import expand_bundle
        raw = expand_bundle(raw)
    mapping(raw, "", required=("name", "geometry", "beams", "steps"), optional=TOP_KEYS[1:])
    name = _name(raw["name"])
    if "units" in raw and raw["units"] != "SI":
        raise ConfigError("units", "only SI (m, N, Pa) is supported; write units: SI or omit it")
    geo = mapping(raw["geometry"], "geometry", required=("length",),
                  optional=("twist_deg", "twist_axis", "sections"))
    length = number(geo["length"], "geometry.length", positive=True, hint=" (metres)")
    twist = number(geo.get("twist_deg", 0.0), "geometry.twist_deg", lo=-3600, hi=3600)
    axis, twist_rule = _twist_axis(geo.get("twist_axis", "centroid"))
    sections = None
    if geo.get("sections") is not None:      # measured sections (docs/geometry.md)
        from .sections import parse_sections
        sections = parse_sections(geo["sections"], "geometry.sections", base_dir, length)

    beams_raw = sequence(raw["beams"], "beams")
    beams: list[BeamSpec] = []
    for i, b in enumerate(beams_raw):
        p = f"beams[{i}]"
        mapping(b, p, required=("name", "section", "material", "elements"),
                optional=("axial_points", "element", "locking"))
        bname = string(b["name"], f"{p}.name")
        if bname in [x.name for x in beams]:
            raise ConfigError(f"{p}.name", f"duplicate beam name {bname!r}; names must be unique")
        beams.append(BeamSpec(
            name=bname,
            section=_section(b["section"], f"{p}.section", base_dir),
            material=_material(b["material"], f"{p}.material"),
            elements=integer(b["elements"], f"{p}.elements", lo=1, hi=100000),
            axial_points=_axial_points(b.get("axial_points", DEFAULT_AXIAL_POINTS), f"{p}.axial_points")))
        beams[-1].element = string(str(b.get("element", "3363")), f"{p}.element", ELEMENT_TYPES)
        default_locking = "ecm" if beams[-1].element == "3333" else "none"
        beams[-1].locking = string(b.get("locking", default_locking), f"{p}.locking", LOCKING)
    names = [b.name for b in beams]
    n_nodes = [2 * b.elements + 1 for b in beams]
    _check_imported_loops(beams, sections)
    if twist_rule[0] == "centroid_of":
        _beam_ref(twist_rule[1], "geometry.twist_axis.centroid_of", names)

    bcs = []
    for i, bc in enumerate(sequence(raw.get("boundary_conditions", []), "boundary_conditions",
                                    nonempty=False)):
        p = f"boundary_conditions[{i}]"
        mapping(bc, p, required=("beam", "node", "fix"))
        bi = _beam_ref(bc["beam"], f"{p}.beam", names)
        bcs.append(BCSpec(bi, _node_ref(bc["node"], f"{p}.node", n_nodes[bi]),
                          _fix(bc["fix"], f"{p}.fix"), p))

    loads = []
    for i, ld in enumerate(sequence(raw.get("loads", []), "loads", nonempty=False)):
        p = f"loads[{i}]"
        mapping(ld, p, required=("beam", "node"), optional=("force", "traction_force"))
        if ("force" in ld) == ("traction_force" in ld):
            raise ConfigError(p, "give exactly one of 'force' (point force on r) or "
                                 "'traction_force' (total force spread over the end section)")
        bi = _beam_ref(ld["beam"], f"{p}.beam", names)
        node = _node_ref(ld["node"], f"{p}.node", n_nodes[bi])
        kind = "force" if "force" in ld else "traction_force"
        if kind == "traction_force" and node not in (0, n_nodes[bi] - 1):
            raise ConfigError(f"{p}.node", "a traction_force acts on an end section: use first or last")
        loads.append(LoadSpec(bi, node, kind, vector(ld[kind], f"{p}.{kind}", 3), p))

    steps = [number(s, f"steps[{i}]", positive=True)
             for i, s in enumerate(sequence(raw["steps"], "steps"))]
    if any(b <= a for a, b in zip(steps, steps[1:])):
        raise ConfigError("steps", f"load factors must increase strictly; got {steps}")

    probes = []
    for i, pr in enumerate(sequence(raw.get("probes", []), "probes", nonempty=False)):
        p = f"probes[{i}]"
        mapping(pr, p, required=("name", "beam", "node"), optional=("vector",))
        bi = _beam_ref(pr["beam"], f"{p}.beam", names)
        pname = string(pr["name"], f"{p}.name")
        if pname in [x.name for x in probes]:
            raise ConfigError(f"{p}.name", f"duplicate probe name {pname!r}")
        probes.append(ProbeSpec(pname, bi, _node_ref(pr["node"], f"{p}.node", n_nodes[bi]),
                                string(pr.get("vector", "r"), f"{p}.vector", VECTORS)))

    out = mapping(raw.get("output", {}), "output", optional=("dir", "vtk", "vtk_samples"))
    odir = string(out.get("dir", os.path.join("results", name)), "output.dir")
    output = OutputSpec(dir=odir, vtk=boolean(out.get("vtk", True), "output.vtk"),
                        vtk_samples=integer(out.get("vtk_samples", 4), "output.vtk_samples", lo=1, hi=64))

    sv = mapping(raw.get("solver", {}), "solver",
                 optional=("max_increment", "initial_increment", "min_increment", "max_cutbacks", "growth", "easy_iterations",
                           "predictor", "merit", "min_det_f", "max_newton_iterations", "matrix",
                           "stability_cutbacks", "allow_unstable"))
    solver = SolverSpec()
    if sv.get("max_increment") is not None:
        solver.max_increment = number(sv["max_increment"], "solver.max_increment", positive=True)
    if sv.get("initial_increment") is not None:
        solver.initial_increment = number(sv["initial_increment"], "solver.initial_increment", positive=True)
    if "min_increment" in sv:
        solver.min_increment = number(sv["min_increment"], "solver.min_increment", positive=True)
    if "max_cutbacks" in sv:
        solver.max_cutbacks = integer(sv["max_cutbacks"], "solver.max_cutbacks", lo=0, hi=60)
    if "growth" in sv:
        solver.growth = number(sv["growth"], "solver.growth", lo=1.0, hi=10.0)
    if "min_det_f" in sv:
        solver.min_det_f = number(sv["min_det_f"], "solver.min_det_f", lo=0.0, hi=0.9)
    if "merit" in sv:
        solver.merit = string(sv["merit"], "solver.merit", ("energy", "residual"))
    if "predictor" in sv:
        solver.predictor = string(sv["predictor"], "solver.predictor", ("none", "secant"))
    if "easy_iterations" in sv:
        solver.easy_iterations = integer(sv["easy_iterations"], "solver.easy_iterations", lo=1)
    if "matrix" in sv:
        solver.matrix = string(sv["matrix"], "solver.matrix", ("auto", "aij", "sbaij"))
    if "stability_cutbacks" in sv:
        solver.stability_cutbacks = integer(sv["stability_cutbacks"], "solver.stability_cutbacks", lo=0, hi=20)
    if "allow_unstable" in sv:
        solver.allow_unstable = boolean(sv["allow_unstable"], "solver.allow_unstable")
    if sv.get("max_newton_iterations") is not None:
        solver.max_newton_iterations = integer(sv["max_newton_iterations"], "solver.max_newton_iterations", lo=1)

    petsc = _petsc(raw.get("petsc", {}) or {})

    contact = _contact(raw["contact"], names) if raw.get("contact") is not None else None
    partition = "blocks"
    if raw.get("partition") is not None:
        mapping(raw["partition"], "partition", optional=("method",))
        partition = string(raw["partition"].get("method", "blocks"), "partition.method",
                           PARTITION_METHODS)
    accuracy = _accuracy(raw["accuracy"], probes, steps) if raw.get("accuracy") is not None else None
    return ModelSpec(name=name, length=length, twist_deg=twist, twist_axis=axis, beams=beams,
                     boundary_conditions=bcs, loads=loads, steps=steps, probes=probes,
                     output=output, solver=solver, petsc=petsc, contact=contact,
                     base_dir=base_dir, raw=raw, partition=partition, accuracy=accuracy,
                     sections=sections, twist_rule=twist_rule,
                     twist_default="twist_axis" not in geo)


TWIST_RULES = ("centroid", "origin", "junction")


def _twist_axis(value) -> tuple[tuple[float, float], tuple]:
    """geometry.twist_axis: a point [y, z] (m) or a rule (resolved by model.resolve_twist_axis)."""
    p = "geometry.twist_axis"
    if isinstance(value, str) and value in TWIST_RULES:
        return (0.0, 0.0), ((value,) if value != "origin" else ("point",))
    if isinstance(value, dict):
        mapping(value, p, required=("centroid_of",))
        return (0.0, 0.0), ("centroid_of", string(value["centroid_of"], f"{p}.centroid_of"))
    if not isinstance(value, (list, tuple)):
        raise ConfigError(p, "expected a list of 2 numbers [y, z] (metres) or a rule: centroid "
                             "(the whole section's area centroid, default), origin, junction (the "
                             f"point all outlines share) or {{centroid_of: <beam>}}; got {_fmt(value)}")
    return vector(value, p, 2), ("point",)


def _check_imported_loops(beams: list, sections) -> None:
    """beams[i].section {shape: outline, loop: <name>} without file/curves names an outline of
    geometry.sections."""
    for i, b in enumerate(beams):
        s = b.section
        if s.shape != "outline" or s.file is not None or s.curves is not None:
            continue
        p = f"beams[{i}].section"
        if sections is None:
            raise ConfigError(f"{p}.loop", "names an outline of geometry.sections, which this config "
                                           "does not have; add geometry.sections or give curves / file")
        if s.loop not in sections.names:
            raise ConfigError(f"{p}.loop", f"no outline {s.loop!r} in geometry.sections; available: "
                                           f"{', '.join(sections.names)}")
        if s.spline_degree_given:
            raise ConfigError(f"{p}.spline_degree", "imported outlines share one spline degree: set "
                                                    "geometry.sections.spline_degree instead")


def _accuracy(value, probes: list, steps: list[float]) -> AccuracySpec:
    p = "accuracy"
    mapping(value, p, required=("probe",), optional=("rtol", "component", "level", "start", "max_elements"))
    names = [x.name for x in probes]
    probe = string(value["probe"], f"{p}.probe")
    if probe not in names:
        raise ConfigError(f"{p}.probe", f"no probe {probe!r}; define it under probes "
                                        f"(have: {', '.join(names) or 'none'})")
    acc = AccuracySpec(probe=probe,
                       rtol=number(value.get("rtol", 1e-3), f"{p}.rtol", positive=True, hi=0.5),
                       component=string(value.get("component", "norm"), f"{p}.component",
                                        ("x", "y", "z", "norm")),
                       start=integer(value.get("start", 1), f"{p}.start", lo=1, hi=10000),
                       max_elements=integer(value.get("max_elements", 64), f"{p}.max_elements", lo=1, hi=100000))
    if "level" in value:
        acc.level = number(value["level"], f"{p}.level", positive=True)
        if not any(math.isclose(acc.level, s, rel_tol=1e-12) for s in steps):
            raise ConfigError(f"{p}.level", f"must be one of the steps ({', '.join(f'{s:g}' for s in steps)})")
    if acc.max_elements < 4 * acc.start:
        raise ConfigError(f"{p}.max_elements", "the ladder needs three rungs: use at least 4 x start "
                                               f"(= {4 * acc.start})")
    return acc


#: contact keys of the penalty formulation, gone since contact is enforced by Lagrange multipliers
REMOVED_CONTACT_KEYS = ("penalty", "penalty_scale", "augmented", "gap_tolerance", "max_augmentations",
                        "smoothing")


def _contact(value, names: list[str]) -> ContactSpec:
    p = "contact"
    if isinstance(value, dict):
        for key in REMOVED_CONTACT_KEYS:
            if key in value:
                raise ConfigError(f"{p}.{key}", "contact is enforced exactly by Lagrange multipliers "
                                                "(no penalty, nothing to tune); remove this key")
    mapping(value, p, optional=("mode", "interfaces", "axial_points", "curve_points", "search_margin",
                                "projection", "scaling"))
    c = ContactSpec()
    c.mode = string(value.get("mode", "sliding"), f"{p}.mode", CONTACT_MODES)
    c.axial_points = integer(value.get("axial_points", 3), f"{p}.axial_points", lo=1, hi=10)
    c.curve_points = integer(value.get("curve_points", 2), f"{p}.curve_points", lo=1, hi=10)
    c.search_margin = number(value.get("search_margin", 0.1), f"{p}.search_margin", positive=True, hi=1.0)
    c.scaling = number(value.get("scaling", 1.0), f"{p}.scaling", positive=True,
                       hint=" (a factor on the multipliers' unit k_s; it does not change the answer)")
    proj = value.get("projection", None)
    if proj == "pointwise":
        raise ConfigError(f"{p}.projection", "a multiplier per point over-constrains the quadratic "
                                             "section fields; give {axial: .., curve: ..} degrees")
    if proj is None:
        c.projection = (c.axial_points - 1, 1)
    else:
        pp = f"{p}.projection"
        mapping(proj, pp, required=("axial", "curve"), optional=("per_element",))
        c.projection = (integer(proj["axial"], f"{pp}.axial", lo=0, hi=c.axial_points - 1),
                        integer(proj["curve"], f"{pp}.curve", lo=0, hi=8))
        c.per_element = boolean(proj.get("per_element", False), f"{pp}.per_element")
    if (c.projection[0] + 1) * (c.projection[1] + 1) > 18:
        raise ConfigError(f"{p}.projection", "(axial + 1) x (curve + 1) pressure functions per element "
                                             "must not exceed 18 (one node block)")
    inter = value.get("interfaces", "auto")
    if inter == "auto":
        c.interfaces = []
    else:
        for i, it in enumerate(sequence(inter, f"{p}.interfaces")):
            ip = f"{p}.interfaces[{i}]"
            mapping(it, ip, required=("a", "b"), optional=("curve", "curve_b"))
            a = _beam_ref(it["a"], f"{ip}.a", names)
            b = _beam_ref(it["b"], f"{ip}.b", names)
            if a == b:
                raise ConfigError(ip, "a beam cannot be in contact with itself here; name two beams")
            if "curve_b" in it and "curve" not in it:
                raise ConfigError(ip, "curve_b (the curve on b) needs curve (the curve on a)")
            c.interfaces.append((a, b, string(it["curve"], f"{ip}.curve") if "curve" in it else None,
                                 string(it["curve_b"], f"{ip}.curve_b") if "curve_b" in it else None))
    return c


def load_config(path: str) -> ModelSpec:
    """Read and validate a YAML config file; raises ConfigError (never a traceback-worthy error)."""
    if os.path.isdir(path):
        raise ConfigError("", f"{path}: is a directory, not a config file")
    if not os.path.isfile(path):
        raise ConfigError("", f"{path}: no such config file")
    try:
        with open(path, "rb") as fh:
            text = fh.read().decode("utf-8")
        raw = yaml.safe_load(text)
    except UnicodeDecodeError as exc:
        raise ConfigError("", f"{path}: not a text (UTF-8) YAML file: byte 0x{exc.object[exc.start]:02x} "
                              f"at offset {exc.start}") from None
    except OSError as exc:
        raise ConfigError("", f"{path}: cannot read: {exc.strerror}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ConfigError("", f"{path}: YAML syntax error{where}: {problem}") from None
    if raw is None:
        raise ConfigError("", f"{path}: the file is empty")
    return parse_config(raw, base_dir=os.path.dirname(os.path.abspath(path)), source=path)
