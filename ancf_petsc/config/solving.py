"""Solver, PETSc, output, partition and accuracy keys of a config: how a model is solved and kept."""
from __future__ import annotations

import math
import numbers
import os
import re

from ..linalg.option_syntax import START_UP_OPTIONS, check_value, option_kind
from .specs import PARTITION_METHODS, TANGENTS, AccuracySpec, OutputSpec, SolverSpec
from .values import ConfigError, boolean, integer, mapping, number, shown, string

#: ``accuracy.section_order``: none, or check the start rung one rung up the section ladder
#: (workflows/section_order.py)
SECTION_ORDER_CHECKS = ("none", "check")

#: ``solver:`` keys → (validator, whether null means "the default")
SOLVER_KEYS = {
    "max_increment": (lambda v, p: number(v, p, positive=True), True),
    "initial_increment": (lambda v, p: number(v, p, positive=True), True),
    "min_increment": (lambda v, p: number(v, p, positive=True), False),
    "max_cutbacks": (lambda v, p: integer(v, p, lo=0, hi=60), False),
    "growth": (lambda v, p: number(v, p, lo=1.0, hi=10.0), False),
    "min_det_f": (lambda v, p: number(v, p, lo=0.0, hi=0.9), False),
    "merit": (lambda v, p: string(v, p, ("energy", "residual")), False),
    "section_update": (lambda v, p: string(v, p, ("rotation", "linear")), False),
    "predictor": (lambda v, p: string(v, p, ("none", "secant", "tangent")), False),
    "tangent": (lambda v, p: string(v, p, TANGENTS), False),
    "easy_iterations": (lambda v, p: integer(v, p, lo=1), False),
    "matrix": (lambda v, p: string(v, p, ("auto", "aij", "sbaij")), False),
    "linear": (lambda v, p: string(v, p, ("auto", "direct", "fieldsplit")), True),
    "stability_cutbacks": (lambda v, p: integer(v, p, lo=0, hi=20), False),
    "allow_unstable": (boolean, False),
    "branch_switch": (boolean, False),
    "step_over_jumps": (boolean, False),
    "full_step_first": (boolean, False),
    "band_step": (lambda v, p: band_step(v, p), False),
    "reuse_tangent": (boolean, False),
    "compact_factor": (boolean, False),
    "max_newton_iterations": (lambda v, p: integer(v, p, lo=1), True),
    "options_prefix": (lambda v, p: options_prefix(v, p), False),
}


#: the most increments the largest load factor may take at ``solver.max_increment``
MAX_INCREMENTS = 100_000
#: the smallest ``solver.band_step`` besides 0 (off): steps held to a millionth of a band width
#: crawled (693 Newton iterations and a stall at 45 N at 1e-9); 1.5 is the measured choice
MIN_BAND_STEP = 0.1


def band_step(value, path: str) -> float:
    """``solver.band_step``: 0 (off) or at least MIN_BAND_STEP band widths."""
    v = number(value, path, lo=0.0)
    if 0.0 < v < MIN_BAND_STEP:
        raise ConfigError(path, f"{v:g} band widths would hold Newton's steps to crawling; give 0 (off) "
                                f"or at least {MIN_BAND_STEP:g} (1.5 measured best, docs/running.md)")
    return v


def check_increments(solver, steps: list[float]) -> None:
    """``solver.max_increment`` against the largest load factor: more than MAX_INCREMENTS
    increments is no run (1e-12 to 100 N ran until killed)."""
    top = max(steps, default=0.0)
    if solver.max_increment is not None and top / solver.max_increment > MAX_INCREMENTS:
        raise ConfigError("solver.max_increment", f"{solver.max_increment:g} would take "
                          f"{top / solver.max_increment:.3g} increments to load factor {top:g}; give at "
                          f"least {top / MAX_INCREMENTS:g}")


def options_prefix(value, path: str) -> str:
    """A PETSc options prefix: letters, digits and underscores, ending in an underscore."""
    text = string(value, path)
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*_", text):
        raise ConfigError(path, "a PETSc options prefix is letters, digits and underscores, starts "
                                f"with a letter and ends with '_' (e.g. left_); got {text!r}")
    return text


def parse_solver(value) -> SolverSpec:
    """``solver``: load stepping (increments, cut-backs, predictor, merit, budgets, matrix format)."""
    sv = mapping(value, "solver", optional=tuple(SOLVER_KEYS))
    solver = SolverSpec()
    for key, (check, nullable) in SOLVER_KEYS.items():
        if key in sv and not (nullable and sv[key] is None):
            setattr(solver, key, check(sv[key], f"solver.{key}"))
    return solver


def check_edited_solver(spec) -> None:
    """``solver``, ``partition`` and ``output`` changed on a parsed spec (the Python API) checked as
    the config's: allow_unstable 'no' was taken as true, options_prefix '-left_' ended in a PETSc
    error dump, max_increment 1e-9 ran until killed, predictor 'bogus' and partition 'bogus'
    ran as defaults, output.vtk_samples 0 failed the run's first write."""
    solver = spec.solver
    for key, (check, nullable) in SOLVER_KEYS.items():
        value = getattr(solver, key)
        if not (nullable and value is None) and not (key == "options_prefix" and value == ""):
            plain = int(value) if isinstance(value, numbers.Integral) and not isinstance(value, bool) else value
            setattr(solver, key, check(plain, f"solver.{key}"))
    check_increments(solver, spec.steps)
    spec.partition = string(spec.partition, "partition.method", PARTITION_METHODS)
    out = spec.output
    if not isinstance(out.dir, (str, os.PathLike)):
        raise ConfigError("output.dir", f"expected a directory path; got {shown(out.dir)}")
    out.dir = os.path.expanduser(out.dir)     # '~/runs/a' was made as ./~/runs/a
    out.vtk = boolean(out.vtk, "output.vtk")
    out.vtk_samples = integer(out.vtk_samples, "output.vtk_samples", lo=1, hi=64)
    if out.vtk_compress is not None:
        out.vtk_compress = boolean(out.vtk_compress, "output.vtk_compress")


def parse_output(value, name: str) -> OutputSpec:
    """``output``: directory (default results/<name>; ~ is the home directory), VTK on/off, its
    samples per element edge and whether the VTUs are zlib-compressed."""
    out = mapping(value, "output", optional=("dir", "vtk", "vtk_samples", "vtk_compress"))
    for key in ("vtk_samples", "vtk_compress"):
        if key in out and out.get("vtk") is False:        # read by nothing: no ParaView files
            raise ConfigError(f"output.{key}", "applies to the ParaView files, which output.vtk: false "
                                               f"turns off; remove it or set output.vtk: true; got {shown(out[key])}")
    return OutputSpec(dir=os.path.expanduser(string(out.get("dir", os.path.join("results", name)), "output.dir")),
                      vtk=boolean(out.get("vtk", True), "output.vtk"),
                      vtk_samples=integer(out.get("vtk_samples", 4), "output.vtk_samples", lo=1, hi=64),
                      vtk_compress=_auto_boolean(out.get("vtk_compress", "auto"), "output.vtk_compress"))


def _auto_boolean(value, path: str) -> bool | None:
    """true, false, or auto (None)."""
    if value == "auto":
        return None
    if not isinstance(value, bool):
        raise ConfigError(path, f"expected true, false or auto; got {shown(value)}")
    return value


def parse_partition(value) -> str:
    """``partition.method``: how elements are distributed over ranks."""
    if value is None:
        return "blocks"
    mapping(value, "partition", optional=("method",))
    return string(value.get("method", "blocks"), "partition.method", PARTITION_METHODS)


def parse_petsc(value) -> dict[str, str]:
    """``petsc:`` options as PETSc will read them (values checked like PETSc parses them)."""
    if not isinstance(value, dict):
        raise ConfigError("petsc", f"expected a mapping of PETSc options, e.g. {{snes_rtol: 1e-10}}; got {shown(value)}")
    petsc, keys = {}, {}
    for k, v in value.items():
        if not isinstance(k, str) or not k.strip("-"):
            raise ConfigError(f"petsc.{k}", "option names are strings like snes_monitor")
        if isinstance(v, (dict, list)):
            raise ConfigError(f"petsc.{k}", "option values are scalars (number, string, true/false)")
        name = k.lstrip("-").lower()              # PETSc's option names ignore case
        if name in keys:        # {snes_rtol: 1e-8, SNES_RTOL: 0.5} ran at 1e-8 without a word
            raise ConfigError(f"petsc.{k}", f"the same PETSc option as petsc.{keys[name]} (PETSc reads "
                                            "names without their dashes and case); give it once")
        keys[name] = k
        if "=" in name:                   # PETSc would read an option named 'snes_max_it=3'
            raise ConfigError(f"petsc.{k}", f"an option's name has no '=': write {name.partition('=')[0]}: "
                                            f"{name.partition('=')[2]}; got {shown(k)}")
        text = "" if v is None or v is True else ("0" if v is False else str(v))
        if name in START_UP_OPTIONS:
            raise ConfigError(f"petsc.{k}", f"PETSc reads -{name} only while it starts, before the "
                                            "config is read; give it on the command line (ancf-solve "
                                            f"CONFIG.yaml -{name}" + (f" {text}" if text else "") + ")")
        # a monitor's false is refused in the config's own words (PETSc would read "0")
        shown_text = "false" if v is False and option_kind(name) == "viewer" else text
        why = check_value(name, None if v is None or v is True else shown_text)
        if why:
            raise ConfigError(f"petsc.{k}", why)
        petsc[name] = text
    return petsc


def parse_accuracy(value, probes: list, steps: list[float]) -> AccuracySpec:
    """``accuracy``: the probe, tolerance and ladder of the mesh choice (workflows/refinement.py)."""
    p = "accuracy"
    mapping(value, p, required=("probe",),
            optional=("rtol", "component", "level", "start", "max_elements", "section_order"))
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
                       max_elements=integer(value.get("max_elements", 64), f"{p}.max_elements", lo=1, hi=100000),
                       section_order=string(value.get("section_order", "none"), f"{p}.section_order",
                                            SECTION_ORDER_CHECKS))
    if "level" in value:
        acc.level = number(value["level"], f"{p}.level", positive=True)
        if not any(math.isclose(acc.level, s, rel_tol=1e-12) for s in steps):
            raise ConfigError(f"{p}.level", f"must be one of the steps ({', '.join(f'{s:g}' for s in steps)}); "
                                            f"got {acc.level:g}")
    if acc.max_elements < 4 * acc.start:
        raise ConfigError(f"{p}.max_elements", "the ladder needs three rungs: use at least 4 x start "
                                               f"(= {4 * acc.start}); got {acc.max_elements}")
    return acc


def check_edited_accuracy(spec) -> None:
    """``accuracy`` of a spec edited after parsing (the Python API) read as the config's (after
    its steps): a probe the run does not have raised a KeyError in the ladder, component 'w' a
    ValueError, and rtol -1 or a level not among the steps ran the whole ladder to 'accuracy not
    met'.  A config's ``accuracy:`` mapping is taken too."""
    acc = spec.accuracy
    if isinstance(acc, AccuracySpec):
        acc = {k: v for k, v in vars(acc).items() if v is not None}
    if acc is not None:
        spec.accuracy = parse_accuracy(acc, spec.probes, spec.steps)
