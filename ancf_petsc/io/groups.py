"""The groups of results.h5 (written by results.ResultsWriter on rank 0): ``/model`` (config,
reference nodal vectors, fingerprint, partition, sections) and per converged level
``/steps/step_NNNN`` with its nodal vectors, record, contact fields, reactions and restart data."""
from __future__ import annotations

import numpy as np
import yaml

from ..model.section_forces import element_means
from ..physics.elements import DEFAULT_ELEMENT, ELEMENTS
from . import h5fast as fast
from .files import OutputError, os_reason, plain
from .restart import fingerprint
from .surface_fields import SURFACE_FIELDS

def nodal_units(block) -> str:
    """The "units" attribute of /model/reference_nodal_vectors and steps/…/nodal_vectors."""
    return "; ".join(f"{v} [{u}]" for v, u in block.units().items()) + " (the slots of dof_order)"


def probe_units(block) -> dict[str, str]:
    """The units of a probe's change by its nodal vector (``vector: mean``: a displacement)."""
    return {**block.units(), "mean": "m"}


#: 3363's (the default block; a model's own: ``nodal_units(model.block)``)
NODAL_UNITS = nodal_units(ELEMENTS[DEFAULT_ELEMENT].block)
PROBE_UNITS = probe_units(ELEMENTS[DEFAULT_ELEMENT].block)
#: the SI units of the surface point fields written beside the VTUs (io/surface_fields.py)
SURFACE_UNITS = {"points": "m (deformed positions)", **{f.name: f.si_unit for f in SURFACE_FIELDS.values()}}
#: the "frame" attribute of /model/beams/<name>/section_points and section_outline
CENTROID_FRAME = "section centroid, m (add the beam group's centroid attribute for the tendon frame)"
#: the "units" attribute of steps/…/contact
CONTACT_UNITS = ("SI: m, Pa, N; interfaces 'curve (first|second)' in config order (summary.json "
                 "contact_interfaces); x, x0 on the beam carrying the points; slip, tangential_slip "
                 "= u_first - u_second [m]; shear_stress, multiplier_shear = the first beam's "
                 "traction on the second [Pa]; pressure > 0 presses [Pa] (docs/running.md)")
#: the "units" attribute of each dataset of steps/…/restart (one row per node block)
RESTART_UNITS = {
    "blocks": "the state, a row per node block: each node's nodal vectors (the slots of dof_order: "
              "r [m], r_y, r_z [1], ...), then the contact multipliers' z [m] (restart state)",
    "increment_blocks": "the last accepted increment of blocks, in their units (restart state)"}
#: the "units" attribute of each dataset of steps/…/contact (a law's ``history_*``: its state)
CONTACT_FIELD_UNITS = {
    "interface": "1: the interface's index in summary.json contact_interfaces",
    "x": "m: current position on the beam carrying the points",
    "x0": "m: reference position on the beam carrying the points",
    "area": "m^2: reference area w_p (pressure x area is the point's normal force)",
    "weight": "1: the point's weight in the weighted gaps (0: out of contact)",
    "gap": "m", "pressure": "Pa: > 0 presses, the point's weight included",
    "slip": "m: u_first - u_second of the material points in contact now",
    "projection": "B's element [1], xi [1], curve parameter [m]",
    "tangential_slip": "m: u_first - u_second from the reference partner, in B's tangent plane",
    "shear_stress": "Pa: the first beam's traction on the second",
    "stick": "1: 1 sticks, 0 slips", "slip_increment": "m: tangential slip in the level's last increment",
    "multiplier_pressure": "Pa: pressure coefficient (0 where inactive)",
    "multiplier_active": "1: 1 active, 0 open",
    "multiplier_shear": "Pa: tangential traction coefficient, the first beam's on the second",
    "multiplier_stick": "1: 1 sticks, 0 slips",
    "multiplier_blocks": "m: the multipliers' unknowns z (pressure coefficient = k_s z / area; restart state)",
    "history_anchor": "m: the tangential law's state (restart)"}


def config_text(spec) -> str:
    """/model's ``config_yaml``: the config the levels were solved with (a restart's, which may
    add steps, replaces the stopped run's)."""
    return yaml.safe_dump(plain(spec.raw), sort_keys=False)


def write_model_group(h5, model, layout, run_info: dict, info: dict) -> None:
    """The file's attributes and ``/model``: config, reference nodal vectors, the fingerprint a
    restart compares, the partition, the beams' connectivity and sections; an empty ``/steps``."""
    spec = model.spec
    h5.attrs["ancf_version"] = info["version"]
    h5.attrs["ancf_git"] = info["git"] or ""
    h5.attrs["status"] = "running"
    g = h5.create_group("model")
    g.attrs["name"] = spec.name
    g.attrs["config_yaml"] = config_text(spec)
    g.attrs["dof_order"] = "per node: " + ", ".join(model.block.names) + " (x, y, z each)"
    g.create_dataset("reference_nodal_vectors", data=model.q0).attrs["units"] = nodal_units(model.block)
    fp = g.create_group("fingerprint")       # what a restart compares (io/restart.py)
    for key, arr in fingerprint(model).items():
        fp.create_dataset(key, data=arr)
    write_partition(g, layout, run_info.get("partition"))
    for beam in model.beams:
        b = g.create_group(f"beams/{beam.name}")
        b.create_dataset("connectivity", data=beam.connectivity)
        b.create_dataset("x_nodes", data=beam.x_nodes).attrs["units"] = "m: reference x of each node"
        # (y, z) relative to the section's area centroid (the beam axis), not the tendon frame
        b.create_dataset("section_points", data=beam.section.points).attrs["frame"] = CENTROID_FRAME
        b.create_dataset("section_weights", data=beam.section.weights).attrs["units"] = "m^2"
        b.create_dataset("section_outline", data=beam.section.boundary_polyline(8)
                         ).attrs["frame"] = CENTROID_FRAME
        b.attrs["centroid"] = beam.section.centroid
        b.attrs["area"] = beam.section.area
    steps = h5.create_group("steps")
    steps.attrs["converged"] = 0
    steps.attrs["last_load_factor"] = 0.0


def load_factor_units(spec) -> str:
    """What a level's ``load_factor`` is: the multiple of the config's loads and displacements, or
    with load curves their argument, or for a load history the frame number."""
    if spec.history is not None:
        return ("1 (the frame number of the load history: the loads are the config's times their columns "
                "at that frame)")
    if any(x.curve is not None for x in [*spec.loads, *spec.boundary_conditions] if hasattr(x, "curve")):
        return "1 (the load factor: a load or displacement on a curve is the config's times the curve's value at it)"
    return "1 (the multiple of the config's loads and displacements)"


def write_level_group(g, record, q: np.ndarray, extra: dict | None, contact: dict | None,
                      path: dict | None, model) -> None:
    """One converged level (``steps/step_NNNN``): nodal vectors, the solve's record, the probes,
    the section forces, the contact fields, the supports' reactions, the subtendons'
    displacement differences and what a restart needs (``h5fast``: h5py's low-level calls)."""
    gid, extra = g.id, extra or {}
    fast.attribute(fast.dataset(gid, "nodal_vectors", q), "units", nodal_units(model.block))
    fast.attributes(gid, {
        "load_factor": record.load_factor,
        "load_factor_units": load_factor_units(model.spec),
        "snes_iterations": record.iterations, "snes_reason": record.reason,
        "substeps": record.substeps, "wall_time": record.wall_time,
        "negative_eigenvalues": -1 if record.negative_eigenvalues is None else record.negative_eigenvalues})
    if contact is not None:
        write_contact_group(gid, contact, path["blocks"][model.n_nodes:])
    write_probes(gid, extra.get("probes", {}), model)
    for name, value in extra.get("surface", {}).items():     # surface_NNNN.vtu's, in double
        d = fast.dataset(gid, f"surface/{name}", np.asarray(value, dtype=float))
        fast.attribute(d, "units", SURFACE_UNITS.get(name, ""))
    write_section_forces(gid, extra.get("section_forces"), model)
    if "reactions" in extra:       # force of each support on r [N]
        r = fast.dataset(gid, "reactions", np.array(list(extra["reactions"].values())))
        fast.attributes(r, {"supports": list(extra["reactions"]),
                            "units": "N: the force (x, y, z) the support exerts on the beam at its node's r"})
    if "reaction_moments" in extra:     # its moment about the node's section centroid [N m]
        m = fast.dataset(gid, "reaction_moments", np.array(list(extra["reaction_moments"].values())))
        fast.attributes(m, {"supports": list(extra["reaction_moments"]),
                            "units": "N m: the moment (x, y, z) the support exerts on the beam about "
                                     "its node's section centroid r"})
    for pair, d in extra.get("displacement_differences", {}).items():   # io/derived.py
        dd = fast.dataset(gid, f"displacement_differences/{pair}", np.asarray(d["profile"]))
        fast.attribute(dd, "units", "m: u_x of the first beam's centroid line minus the second's, per node station")
    for name, d in extra.get("subtendons", {}).items():       # io/subtendons.py
        fast.attributes(fast.group(gid, f"subtendons/{name}"), {
            "end_force_N": np.asarray(d["end_force"]), "elongation_m": d["elongation"], "strain": d["strain"]})
    if "frame" in extra:            # a load history's frame (config.history)
        fast.attributes(gid, {"frame": extra["frame"], "time_s": extra["time"]})
    if path is not None:
        write_restart_group(gid, record, path)


def write_probes(gid, probes: dict, model) -> None:
    """``steps/…/probes/<name>``: the probe's change of its nodal vector (x, y, z) and its value
    (summary.json's ``displacement`` and ``value``), with its vector and units (``gid``: the
    level group's low-level id)."""
    vectors = {p.name: p.vector for p in model.spec.probes}
    units = probe_units(model.block)
    for name, p in probes.items():
        d = fast.dataset(gid, f"probes/{name}", np.array([p["displacement"], p["value"]]))
        vector = vectors.get(name, "r")
        fast.attributes(d, {"vector": vector, "rows": "change since the reference state; value",
                            "units": units.get(vector, "m")})


def write_section_forces(gid, forces: dict | None, model) -> None:
    """``steps/…/section_forces/<beam>`` (model/section_forces.py): per axial Gauss point the
    reference x [m] and the force (x, y, z) [N] the cross-section carries; ``<beam>_mean`` the
    same per element (its mean over the element's length, at its mid x)."""
    if not forces:
        return
    for name, (x, f) in forces.items():
        d = fast.dataset(gid, f"section_forces/{name}", np.column_stack([x, f]))
        fast.attribute(d, "columns", "x [m], force x, y, z [N]: through the cross-section at x, at the axial Gauss points")
    for name, (x, f) in element_means(model, forces).items():
        d = fast.dataset(gid, f"section_forces/{name}_mean", np.column_stack([x, f]))
        fast.attribute(d, "columns", "element mid x [m], mean force x, y, z [N] over the element")


def write_restart_group(gid, record, path: dict) -> None:
    """What ``restart.read_restart`` continues from (``steps/…/restart``)."""
    r = fast.group(gid, "restart")
    for key in ("blocks", "increment_blocks"):
        fast.attribute(fast.dataset(r, key, path[key]), "units", RESTART_UNITS[key])
    fast.attributes(r, {"increment": record.increment, "last_increment": record.last_increment,
                        "accepted_negative": path["accepted_negative"]})
    if path.get("fade_forces_pointwise_from") is not None:        # solving/fade_switch.py
        fast.attribute(r, "fade_forces_pointwise_from", path["fade_forces_pointwise_from"])
    if path.get("search_window_whole_from") is not None:          # solving/window_widening.py
        fast.attribute(r, "search_window_whole_from", path["search_window_whole_from"])
    if path.get("settled_increments"):                            # solving/newton.py
        fast.attribute(r, "settled_increments", path["settled_increments"])


def write_contact_group(gid, contact: dict, multipliers: np.ndarray) -> None:
    """The level's contact fields, multipliers and projection state (``steps/…/contact``)."""
    c = fast.group(gid, "contact")
    fast.attribute(c, "units", CONTACT_UNITS)
    # every field the contact and its terms report (contact.reports.point_fields); the points
    # and multipliers are in id order, so the ids themselves are not stored
    for key, value in list(contact.items()) + [("multiplier_blocks", multipliers)]:
        if key not in ("id", "multiplier_id"):
            state = "the tangential law's state (restart)" if key.startswith("history_") else CONTACT_UNITS
            fast.attribute(fast.dataset(c, key, value), "units", CONTACT_FIELD_UNITS.get(key, state))


def recover_level(h5_path: str, name: str) -> bool:
    """After a failed write of level ``name`` (``step_NNNN``): drop a partial level; True if
    the level is complete in the file after all (``/steps`` attributes then name it)."""
    try:
        with fast.open_file(h5_path, "a") as h5:
            steps = h5["steps"]
            if name + ".partial" in steps:
                del steps[name + ".partial"]
            if name in steps:
                steps.attrs["converged"] = int(name.split("_")[1])
                steps.attrs["last_load_factor"] = steps[name].attrs["load_factor"]
                return True
    except (OSError, RuntimeError, KeyError):
        pass
    return False


def write_partition(model_group, layout, stats: dict | None) -> None:
    """``/model/partition``: element and node ranks, the PETSc numbering and ``stats``
    (``partition_stats``) as attributes; a restart's replaces the stopped run's."""
    if "partition" in model_group:
        del model_group["partition"]
    part = model_group.create_group("partition")
    part.create_dataset("element_rank", data=layout.elem_owner)
    part.create_dataset("node_rank", data=layout.node_owner)
    part.create_dataset("petsc_node_of_model_node", data=layout.perm)
    for key, val in (stats or {}).items():
        part.attrs[key] = val


def truncate_levels(h5_path: str, step: int, load_factor: float, config: str | None = None,
                    layout=None, stats: dict | None = None) -> None:
    """Continue results.h5 after level ``step`` (a restart): the later and partial levels go,
    ``config`` (the restarted run's ``config_text``) is stored as the one solved with, and
    ``layout`` with its ``stats`` as the partition (the restart's ranks may differ)."""
    try:
        with fast.open_file(h5_path, "a") as h5:
            if config is not None:
                h5["model"].attrs["config_yaml"] = config
            if layout is not None:
                write_partition(h5["model"], layout, stats)
            steps = h5["steps"]
            for name in list(steps):
                if name.endswith(".partial") or int(name.split("_")[1]) > step:
                    del steps[name]
            steps.attrs["converged"] = step
            steps.attrs["last_load_factor"] = load_factor
            h5.attrs["status"] = "running"
    except (OSError, RuntimeError) as exc:
        raise OutputError(h5_path, f"cannot continue: {os_reason(exc)}") from None
