"""The Python API: load a config, build its model, solve it, read its results.

    import ancf_petsc as ap
    spec = ap.load_config("configs/uniaxial_neohookean.yaml")
    spec.output.dir = "/tmp/bar"
    result = ap.solve(spec)                      # collective on PETSc.COMM_WORLD
    print(result.status, ap.read_results("/tmp/bar").probe("tip")[-1])

A spec may be changed before ``solve`` (``spec.beams[0].elements = 8``, its ``material['mu']``,
``element`` within one node block: 3363/3333, ``spec.steps``, ``spec.petsc``, ``spec.contact``'s
keys, a config's ``contact:`` mapping or None): ``solve`` places
'first'/'last' of the supports, loads and probes on the beams as they are then, checks the beams,
sections, geometry, steps, contact and PETSc options as the config's, and stores the element
counts, types, materials, sections, length, twist, steps, contact and PETSc options solved with
in results.h5.
``solve`` initialises PETSc on first use (with no command-line options; call
``petsc4py.init(argv)`` first to pass some).  Everything here is re-exported by ``ancf_petsc``.

Errors: ``InputError`` (``ConfigError`` is the same class) for the config and options;
``OutputError`` when ``spec.output.dir`` cannot hold results (a file in the way, no permission,
another run's lock).  A write failing after the run started ends it instead: ``status``
'failed', ``reason_code`` OUTPUT_ERROR, ``exit_code`` 2.
"""
from __future__ import annotations

import os
from typing import Callable

from .config import ConfigError, ModelSpec, load_config, parse_config
from .errors import InputError, OutputError
from .io.reader import Results, read_results
from .model.beams import Model


def solve(spec: ModelSpec, comm=None, log: Callable[[str], None] | None = print, restart: str | None = None):
    """Solve ``spec`` and return a ``solving.run.RunResult`` (status, message, exit code, summary
    on rank 0); every converged level is written to ``spec.output.dir`` as it is reached.
    With ``accuracy:`` in the config the element count is chosen first (workflows/accuracy.py);
    ``restart``: continue the run in that directory from its last converged level.  ``comm``: a
    PETSc or mpi4py communicator (default PETSc.COMM_WORLD).  ``log``: called with each line of
    the run's report on rank 0 (None: no report)."""
    _init_petsc()
    from mpi4py import MPI
    from petsc4py import PETSc

    from .solving.run import run_model
    if not isinstance(spec, ModelSpec):
        raise TypeError(f"solve: expected a ModelSpec (load_config, parse_config); got {type(spec).__name__}")
    if log is None:            # 'NoneType' object is not callable, after the output directory was made
        log = _quiet
    elif not callable(log):
        raise TypeError(f"solve: log must be a function of one line (str), or None for no report; "
                        f"got {type(log).__name__}")
    # an mpi4py communicator ended in an AttributeError ('Intracomm' has no 'tompi4py') mid-setup
    comm = PETSc.COMM_WORLD if comm is None else PETSc.Comm(comm) if isinstance(comm, MPI.Comm) else comm
    check_edited(spec)
    restart = None if restart is None else os.path.expanduser(restart)
    if spec.accuracy is not None:
        if restart is not None:
            raise InputError("--restart", "a run with accuracy: chooses its mesh first; restart "
                                          "the chosen run's config instead")
        from .workflows.accuracy import check_rungs_carry, select_and_run
        check_rungs_carry(spec)
        return select_and_run(spec, comm, log, run_model)
    return run_model(spec, comm, log, restart=restart)


def build_model(spec: ModelSpec) -> Model:
    """The model ``solve`` would solve for ``spec``: its edits checked and placed first
    (``check_edited``; built as it stood, a bar edited from 1 to 3 elements had its load and tip
    probe on interior node 2), then ``model.build.build_model``."""
    from .model.build import build_model as build
    check_edited(spec)
    return build(spec)


def _quiet(*_) -> None:
    """The report of a run solved with ``log=None``: nothing."""


def check_edited(spec: ModelSpec) -> None:
    """What a spec changed after parsing must still satisfy: its beams' element counts, types
    and axial points are the config's kinds (a changed type takes its own locking remedy), its
    supports, loads and probes read as the config's (config.conditions.check_edited_conditions)
    and follow its beams' element counts ('last' is the last node of the beam as it is now), its
    steps increase strictly (a spec edited to decreasing steps raised an UnboundLocalError in
    the load stepping; with a history they are its first frames), and its
    ``petsc`` options read as the config's ``petsc:`` (an edited {'snes_rtol': 'abc'} was PETSc's
    refusal naming no key), its contact reads as the config's for the edited beams
    (config.contact_edits), its solver, partition, output and accuracy keys read as the config's
    (config.solving.check_edited_solver, check_edited_accuracy), and the solver keys the config
    left to the model are the edited model's (config.parse.refresh_defaults).
    Raises ConfigError, as the config itself would."""
    from .config.beams import check_edited_beams
    from .config.conditions import as_python, check_edited_conditions, parse_steps, resolve_nodes
    from .config.contact_edits import check_edited_contact
    from .config.history import check_frames, check_history_edits
    from .config.parse import check_edited_geometry, refresh_defaults
    from .config.solving import check_edited_accuracy, check_edited_solver, parse_petsc
    check_edited_geometry(spec)
    check_edited_beams(spec.beams)
    _check_edited_sections(spec)
    check_edited_conditions(spec)
    contact = check_edited_contact(spec)
    refresh_defaults(spec)
    spec.petsc = parse_petsc(spec.petsc)
    resolve_nodes(spec)
    steps = as_python(spec.steps)                   # np.linspace(...)
    steps = list(steps) if isinstance(steps, tuple) else steps
    spec.steps = parse_steps(steps) if spec.history is None else check_frames(steps, spec.history)
    check_edited_solver(spec)
    check_edited_accuracy(spec)
    check_history_edits(spec)
    _raw_as_solved(spec, contact)


def _raw_as_solved(spec: ModelSpec, contact: dict | None = None) -> None:
    """The config stored with the results (results.h5 ``/model`` ``config_yaml``) says the element
    counts, types, locking remedies, axial points, materials, steps, contact (``contact``: as
    written, config.contact_edits) and probes the spec is solved with, also where they were
    changed after parsing (a new dict: ``spec.raw`` may be shared, e.g. by a sample's record of
    its config)."""
    import copy

    from .config.beams import material_as_written
    from .config.specs import DEFAULT_AXIAL_POINTS
    from .physics.elements import DEFAULT_ELEMENT, ELEMENTS
    raw = copy.deepcopy(spec.raw)
    beams = raw.get("beams") if isinstance(raw, dict) else None
    if isinstance(beams, list) and len(beams) == len(spec.beams):
        for entry, beam in zip(beams, spec.beams):
            if isinstance(entry, dict) and entry.get("name") == beam.name:
                entry["elements"] = beam.elements
                if entry.get("axial_points", DEFAULT_AXIAL_POINTS) != beam.axial_points:
                    entry["axial_points"] = beam.axial_points
                if str(entry.get("element", DEFAULT_ELEMENT)) != beam.element:
                    entry["element"] = beam.element
                if entry.get("locking", ELEMENTS[beam.element].default_locking) != beam.locking:
                    entry["locking"] = beam.locking
                if _material_of(entry) != beam.material:
                    entry["material"] = material_as_written(beam.material)
                if _section_of(entry, beam, spec.base_dir) != beam.section:
                    entry["section"] = _section_as_written(beam.section)
    geo = raw.get("geometry") if isinstance(raw, dict) else None
    if isinstance(geo, dict):                    # an edited length, twist or twist axis
        from .config.parse import twist_axis_as_written
        for key, value in (("length", spec.length), ("twist_deg", spec.twist_deg)):
            if geo.get(key, 0.0) != value:
                geo[key] = value
        axis = twist_axis_as_written(spec, geo.get("twist_axis", "centroid"))
        if axis != geo.get("twist_axis", "centroid"):
            geo["twist_axis"] = axis
    if isinstance(raw, dict) and "steps" in raw and spec.history is None:
        raw["steps"] = list(spec.steps)
    if isinstance(raw, dict) and _petsc_of(raw) != spec.petsc:
        raw["petsc"] = {k: v if v else None for k, v in spec.petsc.items()}   # '': a flag
    if isinstance(raw, dict) and _contact_of(raw, spec) != spec.contact:
        raw["contact"] = contact
    probes = _probes_as_written(spec)
    if isinstance(raw, dict) and [{"vector": "r", **p} for p in raw.get("probes") or []] != probes:
        raw["probes"] = probes
    if raw != spec.raw:
        spec.raw = raw


def _probes_as_written(spec: ModelSpec) -> list[dict]:
    """The probes solved, as a config writes them (ancf-report --existing reads them: a probe
    edited to another node kept its config's node there, and the run passed for the paper's)."""
    return [{"name": p.name, "beam": spec.beams[p.beam].name, "node": p.given, "vector": p.vector}
            for p in spec.probes]


def _check_edited_sections(spec: ModelSpec) -> None:
    """Each beam's section read again as a config's, raised to its element's least degree (an
    edited cubature_degree 1 ran to 'unstable'; the config refuses it)."""
    from .config.beams import parse_section
    from .physics.elements import ELEMENTS
    for i, beam in enumerate(spec.beams):
        section = ELEMENTS[beam.element].raise_section_rule(
            parse_section(_section_as_written(beam.section), f"beams[{i}].section", spec.base_dir))
        section.spline_degree_given |= beam.section.spline_degree_given
        beam.section = section


def _section_as_written(s) -> dict:
    """A parsed ``SectionSpec`` as a config writes it (results.h5's config_yaml)."""
    out: dict = {"shape": s.shape, "cubature_degree": s.cubature_degree}
    if tuple(s.center) != (0.0, 0.0):
        out["center"] = list(s.center)
    size = {"ellipse": "semi_axes", "circle": "radius", "rectangle": "size"}.get(s.shape)
    if size is not None:
        value = getattr(s, size)
        out[size] = list(value) if isinstance(value, (tuple, list)) else value
        return out
    out.update({"curves": s.curves} if s.curves is not None else
               {"file": s.file, "loop": s.loop} if s.file is not None else {"loop": s.loop})
    if s.spline_degree_given or s.spline_degree != 3:
        out["spline_degree"] = s.spline_degree
    if s.compress is not True:
        out["compress"] = s.compress
    return out


def _section_of(entry: dict, beam, base_dir: str):
    """A config beam entry's section as parsed for ``beam``'s element (None where it does not parse)."""
    from .config.beams import parse_section
    from .physics.elements import ELEMENTS
    try:
        return ELEMENTS[beam.element].raise_section_rule(parse_section(entry.get("section"), "section", base_dir))
    except ConfigError:
        return None


def _petsc_of(raw: dict) -> dict | None:
    """A config's ``petsc:`` as parsed (None where it does not parse)."""
    from .config.solving import parse_petsc
    try:
        return parse_petsc(raw.get("petsc") or {})
    except ConfigError:
        return None


def _contact_of(raw: dict, spec: ModelSpec):
    """A config's ``contact:`` as parsed for ``spec``'s beams (None where it does not parse)."""
    from dataclasses import replace

    from .config.contact_edits import check_edited_contact
    probe = replace(spec, contact=raw.get("contact"), raw={})
    try:
        check_edited_contact(probe)
    except ConfigError:
        return None
    return probe.contact


def _material_of(entry: dict) -> dict | None:
    """A config beam entry's material as parsed (None where it does not parse)."""
    from .config.beams import parse_material
    try:
        return parse_material(entry.get("material"), "material")
    except ConfigError:
        return None


def _init_petsc() -> None:
    """Initialise MPI, then PETSc (once; a no-op when the program already did).  The session's
    SIGPIPE handler is kept: PETSc's (PetscInitialize) aborted the process (exit 59, a PETSc
    error dump) at a later write into a closed pipe (``script.py | head``), not BrokenPipeError."""
    import signal
    import sys
    import threading

    import petsc4py
    from mpi4py import MPI  # noqa: F401  (MPI before PETSc)
    if "petsc4py.PETSc" in sys.modules:
        return
    session = signal.getsignal(signal.SIGPIPE)
    petsc4py.init()
    from petsc4py import PETSc  # noqa: F401  (PetscInitialize installs PETSc's signal handlers)
    if session is not None and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGPIPE, session)


__all__ = ["ConfigError", "InputError", "Model", "ModelSpec", "OutputError", "Results", "build_model",
           "load_config", "parse_config", "read_results", "solve"]
