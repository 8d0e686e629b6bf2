"""YAML config → validated ``ModelSpec`` (SI units).  Every error names its key path and the fix.

Nothing is computed here beyond checking; ``model.build.build_model`` turns the spec into arrays.
The keys are documented in README.md ("Config reference"); each part of the file has its module:
``beams`` (sections, materials), ``conditions`` (supports, loads, steps, probes), ``contact``,
``solving`` (solver, petsc, output, partition, accuracy), ``sections`` (measured outlines) and
``bundle`` (fascicle bundles expanded into beams).
"""
from __future__ import annotations

import os
from typing import Any

import yaml

from .. import yamlio
from ..errors import UNKNOWN_KEY
from ..physics.elements import ELEMENTS
from ..physics.goh import GOH

from .beams import check_imported_loops, parse_beams
from .bundle import bundle_key, expand_bundle
from .conditions import beam_ref, check_curves, parse_boundary_conditions, parse_loads, parse_probes, parse_steps
from .contact import parse_contact
from .history import check_scale, parse_history
from .sections import parse_sections
from .solving import (check_increments, parse_accuracy, parse_output, parse_partition, parse_petsc,
                      parse_solver)
from .specs import TWIST_RULES, ModelSpec, SolverSpec
from .values import ConfigError, mapping, number, shown, string, vector

TOP_KEYS = ("name", "units", "geometry", "beams", "boundary_conditions", "loads", "steps",
            "probes", "output", "solver", "petsc", "contact", "partition", "bundle", "accuracy",
            "history")


def parse_config(raw: Any, base_dir: str = ".", source: str = "config") -> ModelSpec:
    """Validate a loaded YAML document and return the ``ModelSpec``; relative paths in it are
    read from ``base_dir``, taken absolute now (a relative one was joined again when ``solve``
    read the sections once more: parse_config(raw, base_dir='configs') then solve refused
    'configs/configs/data/...', and a directory changed between them moved every file)."""
    base_dir = os.path.abspath(base_dir)
    if isinstance(raw, dict) and "bundle" in raw:
        raw = expand_bundle(raw)
        try:
            return _parse(raw, base_dir, source)
        except ConfigError as exc:             # the generated beams' keys are the bundle's
            raise ConfigError(bundle_key(exc.path), exc.message, exc.kind) from None
    return _parse(raw, base_dir, source)


def _parse(raw: Any, base_dir: str, source: str) -> ModelSpec:
    """``parse_config`` of a document whose bundle is expanded."""
    history = None
    if isinstance(raw, dict) and raw.get("history") is not None:
        history = parse_history(raw["history"], base_dir)
    _per_beam_key(raw)
    mapping(raw, "", required=("name", "geometry", "beams") + (() if history else ("steps",)),
            optional=TOP_KEYS[1:])
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
        sections = parse_sections(geo["sections"], "geometry.sections", base_dir, length)
    beams = parse_beams(raw["beams"], base_dir)
    names = [b.name for b in beams]
    blocks = [ELEMENTS[b.element].block for b in beams]     # each beam's nodal vectors and axial nodes
    n_nodes = [blk.nodes_of(b.elements) for b, blk in zip(beams, blocks)]
    check_imported_loops(beams, sections)
    if twist_rule[0] == "centroid_of":
        beam_ref(twist_rule[1], "geometry.twist_axis.centroid_of", names)
    steps = _steps(raw, history)
    probes = parse_probes(raw.get("probes", []), names, n_nodes, blocks)
    spec = ModelSpec(
        name=name, length=length, twist_deg=twist, twist_axis=axis, beams=beams,
        boundary_conditions=parse_boundary_conditions(raw.get("boundary_conditions", []), names, n_nodes,
                                                      history, blocks),
        loads=parse_loads(raw.get("loads", []), names, n_nodes, history), steps=steps, probes=probes,
        output=parse_output(raw.get("output", {}), name), solver=parse_solver(raw.get("solver", {})),
        petsc=parse_petsc({} if raw.get("petsc") is None else raw["petsc"]),
        contact=parse_contact(raw["contact"], names, blocks[0].dofs_per_node,
                              min(ELEMENTS[b.element].order for b in beams),
                              min(blk.axial_nodes for blk in blocks) - 1)
        if raw.get("contact") is not None else None,
        base_dir=base_dir, raw=raw, partition=parse_partition(raw.get("partition")),
        accuracy=parse_accuracy(raw["accuracy"], probes, steps) if raw.get("accuracy") is not None else None,
        sections=sections, twist_rule=twist_rule, twist_default="twist_axis" not in geo, history=history)
    check_curves(spec)
    check_scale(spec)
    check_increments(spec.solver, spec.steps)
    for key, default in MODEL_DEFAULTS.items():
        if key not in (raw.get("solver") or {}):
            setattr(spec.solver, key, default(spec))
            spec.solver.defaulted[key] = getattr(spec.solver, key)
    return spec


def refresh_defaults(spec: ModelSpec) -> None:
    """The solver keys the config left to the model (``MODEL_DEFAULTS``) chosen again for the
    model as it is now: a neo-Hookean bar edited to GOH through the API kept the secant predictor,
    where the GOH config parsed takes the tangent (the elastica: 412 Newton iterations against
    288).  A value changed after parsing is kept."""
    for key, parsed in spec.solver.defaulted.items():
        if getattr(spec.solver, key) == parsed:
            setattr(spec.solver, key, MODEL_DEFAULTS[key](spec))
            spec.solver.defaulted[key] = getattr(spec.solver, key)


def _per_beam_key(raw: Any) -> None:
    """A material at the top level (one for all beams) was 'unknown key; allowed here: ...',
    without where it belongs or how to share it."""
    key = next((k for k in ("material", "materials") if isinstance(raw, dict) and k in raw), None)
    if key is not None:
        raise ConfigError(key, "is given per beam, as beams[i].material (one for several beams: material: &m "
                               "{...} on the first, material: *m on the others; a bundle: bundle.material); "
                               f"got {key}: at the top level", UNKNOWN_KEY)


def default_section_update(spec: ModelSpec) -> str:
    """``solver.section_update`` when the config gives none (petsc/section_rotation.py):
    ``rotation`` for a model with a fibre-reinforced law or without contact, else ``linear``.
    The GOH envelope (docs/gait.md, thirty-fourth session): columns over the target at twist
    <= 90 deg 84 -> 67, Newton iterations to 1.2 kN 0.77 of the linear update's (median).
    Without contact (docs/running.md, forty-seventh session): the pretwisted bar over twists
    0/60/180 deg, 1-16 elements, 3363/3333/33103, neo-Hookean and SVK (75 runs), 3 972 -> 1 404
    Newton iterations and 113 -> 0 cut-backs, the tips within 3e-11 of the largest displacement.
    Isotropic contact models keep ``linear``: their strongly twisted unilateral columns and
    strides move both ways."""
    return "rotation" if _fibres(spec) or spec.contact is None else "linear"


def _fibres(spec: ModelSpec) -> bool:
    """Whether a beam of ``spec`` has a fibre-reinforced (GOH) law (also with k1 = 0: defaults
    stay as a calibration's samples change k1 in place)."""
    return any(b.material.get("model") == GOH.name for b in spec.beams)


def default_predictor(spec: ModelSpec) -> str:
    """``solver.predictor`` when the config gives none (solving/predictor.py): ``tangent`` for a
    load history (non-proportional frames), for a model with a fibre-reinforced law (a
    stiffening path, where the secant overshoots) and for a model with contact (the gait
    envelope's proportional grids, docs/gait.md: frictionless, columns over the target at twist
    <= 90 deg 28 -> 10, Newton iterations 70 896 -> 68 617, 10 failing cells either way; Coulomb
    mu 0.1-0.5, 4 -> 1 and 15 029 -> 11 928; the interface study's 52 tangential-law columns
    25 491 -> 21 148); else ``secant``.  One of those columns loses (soleus-loaded, mu = 3, 4
    elements: 148 -> 1 137): the tangent's cut-backs creep toward the stuck interface's
    breakaway, a limit point near 90.11 N the secant's 10 N steps jump over; past it the answer
    depends on the increments whatever the predictor (docs/interface.md, Limits)."""
    return "tangent" if spec.history is not None or _fibres(spec) or spec.contact is not None else "secant"


def default_min_increment(spec: ModelSpec) -> float:
    """``solver.min_increment`` when the config gives none: 1e-4, times the largest load factor
    where that is below 1, so that a failed step is halved as often whatever unit the load
    factors are in.  An elastica at P L²/EI = 20 in one step took 10 sub-steps as force 20 N x
    load factor 1, and failed as 2e4 N x 1e-3 (three halvings to the floor) or 2e5 N x 1e-4 (no
    cut-back at all).  Every shipped config's load factors reach 1 or more: 1e-4 there."""
    top = max((s for s in spec.steps if isinstance(s, (int, float)) and s > 0), default=1.0)
    return SolverSpec.min_increment * min(1.0, top)


#: solver keys whose default depends on the model: the key -> its default for a spec
MODEL_DEFAULTS = {"predictor": default_predictor, "section_update": default_section_update,
                  "min_increment": default_min_increment}


def _steps(raw: dict, history) -> list[float]:
    """The reported load factors: ``steps``, or with a load history every frame (1 … N)."""
    if history is None:
        return parse_steps(raw["steps"])
    if raw.get("steps") is not None:
        raise ConfigError("steps", f"with history every frame of {history.source} is a reported step "
                                   f"(load factor k = frame k, 1 ... {history.n_frames}); remove steps")
    return [float(k) for k in range(1, history.n_frames + 1)]


def _name(value) -> str:
    """The model's name, which names its default output directory results/<name>."""
    name = string(value, "name")
    if "/" in name or "\\" in name or name.startswith(".") or not name.isprintable():
        raise ConfigError("name", f"it names the output directory results/<name>: no '/', '\\', "
                                  f"leading '.' or control characters; got {shown(name)}")
    return name


def check_edited_geometry(spec: ModelSpec) -> None:
    """``geometry`` of a spec edited after parsing (the Python API) read as the config's: length
    -0.1 or twist_deg '90' raised deep in the build (ValueError; nan: LinAlgError), twist_deg 5000
    ran (the config refuses it), and a twist_axis point set where the config gave a rule
    (centroid) was ignored: it is now that point (a rule, e.g. 'junction', that rule)."""
    spec.length = number(spec.length, "geometry.length", positive=True, hint=" (metres)")
    spec.twist_deg = number(spec.twist_deg, "geometry.twist_deg", lo=-3600, hi=3600)
    value = spec.twist_axis.tolist() if hasattr(spec.twist_axis, "tolist") else spec.twist_axis
    point, rule = _twist_axis(list(value) if isinstance(value, tuple) else value)
    given = isinstance(value, (str, dict)) or spec.twist_rule[0] == "point"
    if given or point not in ((0.0, 0.0), spec.twist_resolved):     # else the rule's own point
        spec.twist_default &= rule == spec.twist_rule
        spec.twist_rule, spec.twist_axis = rule, point
    if spec.twist_rule[0] == "centroid_of":
        beam_ref(spec.twist_rule[1], "geometry.twist_axis.centroid_of", [b.name for b in spec.beams])


def twist_axis_as_written(spec: ModelSpec, written: Any = "centroid"):
    """``geometry.twist_axis`` as a config writes the spec's: ``written`` (the config's) where it
    says the same, else a point [y, z] or the rule."""
    point, rule = _twist_axis(written)
    if rule == spec.twist_rule and (rule[0] != "point" or point == tuple(spec.twist_axis)):
        return written
    if spec.twist_rule[0] == "point":
        return [float(v) for v in spec.twist_axis]
    return {"centroid_of": spec.twist_rule[1]} if spec.twist_rule[0] == "centroid_of" else spec.twist_rule[0]


def _twist_axis(value) -> tuple[tuple[float, float], tuple]:
    """geometry.twist_axis: a point [y, z] (m) or a rule (resolved by model.build.resolve_twist_axis)."""
    p = "geometry.twist_axis"
    if isinstance(value, str) and value in TWIST_RULES:
        return (0.0, 0.0), ((value,) if value != "origin" else ("point",))
    if isinstance(value, dict):
        mapping(value, p, required=("centroid_of",))
        return (0.0, 0.0), ("centroid_of", string(value["centroid_of"], f"{p}.centroid_of"))
    if not isinstance(value, (list, tuple)):
        raise ConfigError(p, "expected a list of 2 numbers [y, z] (metres) or a rule: centroid "
                             "(the whole section's area centroid, default), origin, junction (the "
                             f"point all outlines share) or {{centroid_of: <beam>}}; got {shown(value)}")
    return vector(value, p, 2), ("point",)


def load_config(path: str) -> ModelSpec:
    """Read and validate a YAML config file; raises ConfigError (never a traceback-worthy error)."""
    if os.path.isdir(path):
        raise ConfigError("", f"{path}: is a directory, not a config file")
    if os.path.exists(path) and not os.path.isfile(path):
        # a pipe (/dev/stdin, <(...)), a terminal or a socket: every MPI rank reads the config
        # and relative paths in it are resolved from its directory, so it must be a file
        raise ConfigError("", f"{path}: a pipe or device, not a config file: pipes are not "
                              "supported (every rank reads the config); write it to a file first")
    if not os.path.isfile(path):
        raise ConfigError("", f"{path}: no such config file")
    try:
        raw = yamlio.load(yamlio.read_text(path))
    except UnicodeDecodeError as exc:
        raise ConfigError("", f"{path}: not a text (UTF-8) YAML file: byte 0x{exc.object[exc.start]:02x} "
                              f"at offset {exc.start}") from None
    except OSError as exc:
        raise ConfigError("", f"{path}: cannot read: {exc.strerror}") from None
    except yaml.YAMLError as exc:
        raise ConfigError("", f"{path}: {yamlio.syntax_error(exc)}") from None
    if raw is None:
        raise ConfigError("", f"{path}: the file is empty")
    return parse_config(raw, base_dir=os.path.dirname(os.path.abspath(path)), source=path)
