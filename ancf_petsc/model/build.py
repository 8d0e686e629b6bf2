"""ModelSpec → Model: sections (analytic, outlines, measured stations), materials, reference
nodal coordinates of the pretwisted beams (eqs. 1-3), quadrature, supports and loads.

The numbering and the Model/Beam types are in beams.py.
"""
from __future__ import annotations

import os

import numpy as np

from ..config.specs import ModelSpec, SectionSpec
from ..config.values import ConfigError, shown
from ..physics import element3363 as el
from ..physics.cubature import gauss_legendre
from ..physics.elements import ELEMENTS, element
from ..physics.geometry import reference_nodal_vectors
from ..physics.laws import make_material
from ..physics.section import Section, make_circle, make_ellipse, make_outline, make_rectangle
from ..physics.sections_file import inline_loop, load_sections_file
from ..physics.spline import SectionError
from ..contact.interfaces import unlisted_warnings
from .beams import Beam, Model, Support
from .face_turns import slope_warnings
from .fibre_setup import set_fibre_directions
from .loading import LoadCurve, LoadGroup, group_for
from .plausibility import (cubature_warnings, fibre_warnings, load_warnings, material_warnings,
                           point_force_warnings, pretwist_resolution_warnings, reversed_load_warnings,
                           section_warnings, sections_file_length_warnings, size_warnings, twist_warnings)

_SECTIONS_FILE_CACHE: dict = {}


def _share_inline_curves(loop, named: set, registry: dict, path: str):
    """Inline curves with the same name in several beams become one curve (a contact interface)."""
    out = []
    for cv, flip in loop:
        if cv.name not in named:
            out.append((cv, flip))
            continue
        prev = registry.get(cv.name)
        if prev is None:
            registry[cv.name] = cv
            out.append((cv, flip))
        elif cv.points.shape == prev.points.shape and np.allclose(cv.points, prev.points, rtol=0, atol=1e-12):
            out.append((prev, flip))
        elif cv.points.shape == prev.points.shape and np.allclose(cv.points[::-1], prev.points, rtol=0, atol=1e-12):
            out.append((prev, not flip))
        else:
            raise ConfigError(path, f"curve name {cv.name!r} is used by two outlines with different "
                                    "points; shared interfaces need identical points (either order)")
    return out


def _sections_file(path: str, spline_degree: int):
    """A sections file, read once per version: the cache was keyed on the path alone, so a file
    edited between two builds in one process (the API, a notebook) kept its first curves."""
    try:
        st = os.stat(path)
        stamp: tuple = (st.st_mtime_ns, st.st_size)
    except OSError:
        stamp = ()                                # load_sections_file says what is wrong
    key = (path, spline_degree)
    if key not in _SECTIONS_FILE_CACHE or _SECTIONS_FILE_CACHE[key][0] != stamp:
        _SECTIONS_FILE_CACHE[key] = (stamp, load_sections_file(path, spline_degree))
    return _SECTIONS_FILE_CACHE[key][1]


def build_section(spec: SectionSpec, path: str, registry: dict | None = None,
                  tendon=None) -> Section:
    """Build a beam's cross-section; section problems become ConfigErrors at ``path``.
    ``tendon``: the measured sections (geometry.sections) an outline ``loop`` alone refers to."""
    try:
        if spec.shape == "outline" and spec.file is None and spec.curves is None:
            return make_outline(tendon.loop(spec.loop, 0.0), spec.cubature_degree,
                                compress=spec.compress, center=spec.center)
        if spec.shape == "ellipse":
            return make_ellipse(spec.semi_axes, spec.center, spec.cubature_degree)
        if spec.shape == "circle":
            return make_circle(spec.radius, spec.center, spec.cubature_degree)
        if spec.shape == "rectangle":
            return make_rectangle(spec.size, spec.center, spec.cubature_degree)
        if spec.file is not None:
            sf = _sections_file(spec.file, spec.spline_degree)
            if spec.loop not in sf.loops:
                raise ConfigError(f"{path}.loop", f"no loop {spec.loop!r} in {spec.file}; "
                                  f"available: {', '.join(sf.loops)}")
            loop = sf.loops[spec.loop]
        else:
            loop = inline_loop(spec.curves, spec.spline_degree)
            named = {c["name"] for c in spec.curves if "name" in c}
            if registry is not None and named:
                loop = _share_inline_curves(loop, named, registry, path)
        return make_outline(loop, spec.cubature_degree, compress=spec.compress, center=spec.center)
    except SectionError as exc:
        raise ConfigError(path, str(exc)) from None


def _check_sides(section: Section, i: int, sspec: SectionSpec, beams: list[Beam]) -> None:
    """A curve shared with an earlier beam's outline is their border, one on each side: both
    counter-clockwise loops run along it in opposite senses.  One sense is both on one side,
    overlapping: two beams on one closed curve, or a half-lens inside its half-disc neighbour,
    ran to 'completed' with contact around the whole curve."""
    mine = {id(cv): (cv, flip) for cv, flip in section.loop or []}
    for other in beams:
        for cv, flip in other.section.loop or []:
            if id(cv) in mine and mine[id(cv)][1] == flip:
                key = "curves" if sspec.curves is not None else "loop"
                fix = (f"a curve closing on itself is a whole outline: give beams[{i}] its own" if cv.periodic or
                       np.array_equal(cv.start, cv.end) else f"put this outline on the other side of {cv.name!r}")
                raise ConfigError(f"beams[{i}].section.{key}", f"its curve {cv.name!r} is also a border of "
                                  f"beams[{other.index}] ({other.name}), and both sections lie on the same side "
                                  f"of it: they overlap (a shared curve has one neighbour on each side); {fix}; "
                                  "got both running along it the same way round")


def _measured(bs) -> bool:
    """The beam's section is an outline of geometry.sections."""
    s = bs.section
    return s.shape == "outline" and s.file is None and s.curves is None


def resolve_twist_axis(spec: ModelSpec, beams: list[Beam], tendon) -> tuple[np.ndarray, str]:
    """The twist axis a (tendon frame, m) from ``geometry.twist_axis`` and a line saying which
    rule gave it: a point, ``centroid`` (area centroid of all sections at x = 0, the default),
    ``centroid_of`` one beam, or ``junction`` (the point where all measured outlines meet)."""
    rule = spec.twist_rule
    if rule[0] == "point":
        a, how = np.asarray(spec.twist_axis, dtype=float), "the given point"
    elif rule[0] == "centroid":
        areas = np.array([b.section.area for b in beams])
        a = areas @ np.array([b.section.centroid for b in beams]) / areas.sum()
        how = "area centroid of all sections at x = 0"
    elif rule[0] == "centroid_of":
        b = next(b for b in beams if b.name == rule[1])
        a, how = b.section.centroid.copy(), f"centroid of {b.name}'s section at x = 0"
    else:
        names = [bs.section.loop for bs in spec.beams if _measured(bs)]
        if tendon is None:          # outlines of a sections file or inline curves
            J = outline_junctions(beams)
        else:
            J = tendon.junctions(names) if len(names) >= 2 else np.zeros((0, 2))
            J = J + np.asarray(next((bs.section.center for bs in spec.beams if _measured(bs)), (0.0, 0.0)))
        if len(J) != 1:
            raise ConfigError("geometry.twist_axis", f"junction needs one point where all measured "
                              f"outlines meet; found {len(J)} (use centroid, a point [y, z] or "
                              "{centroid_of: <beam>}); got junction")
        a, how = J[0], "junction of all outlines"
    default = " (default rule; set geometry.twist_axis to change it)" if spec.twist_default else ""
    return a, (f"twist axis: {how} at ({a[0] * 1e3:.4g}, {a[1] * 1e3:.4g}) mm{default}, "
               f"twist {spec.twist_deg:g} deg")


def outline_junctions(beams: list[Beam]) -> np.ndarray:
    """Points (k, 2), tendon frame, where a curve of every outline section ends: the triple point of
    a sections file's loops (configs/data/achilles_type3_sections.yaml).  ``junction`` looked only
    at geometry.sections, and on the paper's own file said 'found 0'."""
    ends = [np.array([p for cv, _ in b.section.loop for p in (cv.start, cv.end)])
            + b.section.shape_params.get("offset", 0.0) for b in beams if b.section.loop is not None]
    if len(ends) < 2:
        return np.zeros((0, 2))
    tol = 1e-9 * max(float(np.ptp(e, axis=0).max()) for e in ends)
    out: list[np.ndarray] = []
    for p in ends[0]:
        if all(np.linalg.norm(e - p, axis=1).min() <= tol for e in ends[1:]) and \
                not any(np.linalg.norm(p - q) <= tol for q in out):
            out.append(p)
    return np.array(out).reshape(-1, 2)


def _varying_rules(beam: Beam, tendon, bs, length: float) -> None:
    """Per-element section rules of a beam whose measured section varies along x: at every axial
    Gauss point the rule of the section there (cubature of eq. 11 on the interpolated loop),
    in the beam's frame (origin: the centroid of its section at x = 0); rules are padded with
    zero weights to one point count.  Also the beam's outline ring at any x (output)."""
    xa, wa = gauss_legendre(bs.axial_points)
    h = length / beam.n_elements
    xg = (np.arange(beam.n_elements)[:, None] + 0.5 * (xa[None, :] + 1.0)) * h      # (E, na)
    c0 = beam.section.centroid
    secs = [[build_section_at(bs.section, tendon, x) for x in row] for row in xg]
    beam.section.notes += sorted({f"at x = {x * 1e3:.4g} mm: {n}" for row, xr in zip(secs, xg)
                                  for s, x in zip(row, xr) for n in s.notes})[:1]
    n = max(len(s.weights) for row in secs for s in row)
    E, na = xg.shape
    yz = np.zeros((E, na, n, 2))
    w = np.zeros((E, na, n))
    area = np.zeros((E, na))
    for e in range(E):
        for g in range(na):
            s = secs[e][g]
            k = len(s.weights)
            yz[e, g, :k] = s.points + s.centroid - c0
            yz[e, g, k:] = s.centroid - c0                       # padding: zero weight
            w[e, g, :k] = s.weights
            area[e, g] = s.area
    xi = np.repeat(xa, n)
    _, dN = beam.layout.shape_functions(np.tile(xi, E), yz[..., 0].ravel(), yz[..., 1].ravel())
    beam.xi = xi
    beam.yz = yz.reshape(E, na * n, 2)
    beam.dN = dN.reshape(E, na * n, -1, 3)
    beam.wq = (wa[None, :, None] * w).reshape(E, na * n)
    beam.wq_axis = wa[None, :] * area
    offset = np.asarray(bs.section.center, dtype=float) - c0
    beam.ring_at = lambda x, _n=bs.section.loop: tendon.ring(_n, x) + offset


def build_section_at(sspec: SectionSpec, tendon, x: float) -> Section:
    """The measured section of ``sspec`` at x (tendon frame, like ``build_section``)."""
    try:
        return make_outline(tendon.loop(sspec.loop, x), sspec.cubature_degree,
                            compress=sspec.compress, center=sspec.center)
    except SectionError as exc:
        raise ConfigError("geometry.sections", f"the section of {sspec.loop} interpolated at "
                          f"x = {x * 1e3:.4g} mm: {exc}") from None


def _end_moments(beam: Beam, tendon, bs, x: float) -> np.ndarray:
    """∫ m_k dA / A over the section at x in the beam frame (a uniform end traction; a section
    mean probe)."""
    block = beam.layout.block
    if beam.ring_at is None:
        sec = beam.section
        m = block.section_monomials(sec.points[:, 0], sec.points[:, 1])
        return sec.weights @ m / sec.weights.sum()
    sec = build_section_at(bs.section, tendon, x)
    P = sec.points + sec.centroid - beam.section.centroid
    m = block.section_monomials(P[:, 0], P[:, 1])
    return sec.weights @ m / sec.weights.sum()


def _interpolated(bc, beam: Beam, vector: int, comp: int, value: float) -> None:
    """A prescribed displacement moves a vector the beam's element interpolates: 3333's r_yy,
    r_zz and r_yz are held at 0 outside it, and moving them changed nothing (completed, no word)."""
    if vector in beam.layout.held:
        name = beam.layout.block.names[vector]
        moved = ", ".join(beam.layout.block.names[k] for k in beam.vectors)
        raise ConfigError(f"{bc.path}.displacement.{name}.{'xyz'[comp]}", f"element {beam.element} of beam "
                          f"{beam.name} does not interpolate {name} (held at 0); prescribe one of {moved}; "
                          f"got {value:g}")


def _check_load_on_support(ld, beam: Beam, first_dof: int, spec: ModelSpec, supports: list[Support]) -> None:
    """A load on a component of r that a support holds goes into that support's reaction: refused,
    naming the component and the support (it said only 'the load pushes on a fixed component')."""
    for c in (c for c in range(3) if ld.force[c] != 0.0):
        for bc, support in zip(spec.boundary_conditions, supports):
            if first_dof + c in support.dofs:
                raise ConfigError(f"{ld.path}.{ld.kind}", f"{beam.name} node {ld.node if ld.given is None else ld.given}: "
                                  f"r.{'xyz'[c]} is held by {bc.path} ({bc.name!r}), whose reaction would take this "
                                  f"load; load another node or free that component; got {shown(list(ld.force))}")


def build_model(spec: ModelSpec) -> Model:
    """Assemble the replicated model description from a validated spec."""
    beams: list[Beam] = []
    q0_parts = []
    node_offset = elem_offset = 0
    registry: dict = {}
    tendon = None
    report: list[str] = []
    if spec.sections is not None:
        from ..geometry_input.tendon import build_tendon
        tendon = build_tendon(spec.sections)
        report += tendon.report()
        if spec.contact is not None and tendon.varies and not tendon.field.structured:
            raise ConfigError("contact", "sections that vary along x work with contact only when every "
                              f"interface curve is the same at every station ({tendon.field.reason}); "
                              "remove contact or give equal borders at every station")
    block = element(spec.beams[0].element).block
    for i, bs in enumerate(spec.beams):
        if element(bs.element).block != block:
            same = " or ".join(repr(n) for n, e in ELEMENTS.items() if e.block == block)
            raise ConfigError(f"beams[{i}].element", f"has another node block than {spec.beams[0].element} "
                              f"(beams[0].element): the beams of one model share their node layout; give "
                              f"{same} here, or the same element to every beam; got {bs.element!r}")
        section = build_section(bs.section, f"beams[{i}].section", registry, tendon)
        _check_sides(section, i, bs.section, beams)
        x_nodes = np.linspace(0.0, spec.length, block.nodes_of(bs.elements))
        beam = Beam(index=i, name=bs.name, section=section, material=make_material(bs.material),
                    n_elements=bs.elements, node_offset=node_offset, element_offset=elem_offset,
                    x_nodes=x_nodes, axial_points=bs.axial_points, element=bs.element,
                    locking=bs.locking, volumetric_degree=bs.volumetric_degree,
                    pressure_columns=bs.pressure_columns)
        xa, wa = gauss_legendre(bs.axial_points)
        beam.xi, y, z = el.tensor_points(xa, section.points)
        beam.yz = np.column_stack([y, z])
        beam.wq = np.repeat(wa, len(section.weights)) * np.tile(section.weights, len(xa))
        _, beam.dN = beam.layout.shape_functions(beam.xi, y, z)
        zero = np.zeros_like(xa)     # the beam axis y = z = 0 runs through the section centroid
        _, beam.dN_axis = beam.layout.shape_functions(xa, zero, zero)
        beam.wq_axis = wa * section.weights.sum()
        if tendon is not None and tendon.varies and _measured(bs):
            _varying_rules(beam, tendon, bs, spec.length)
        beams.append(beam)
        node_offset += beam.n_nodes
        elem_offset += beam.n_elements
    axis, line = resolve_twist_axis(spec, beams, tendon)
    spec.twist_axis = spec.twist_resolved = (float(axis[0]), float(axis[1]))
    report.append(line)
    for beam in beams:
        q0_parts.append(reference_nodal_vectors(beam.x_nodes, beam.section.centroid, spec.length,
                                                spec.twist_deg, spec.twist_axis, block.vectors_per_node))
        set_fibre_directions(beam, spec.length, spec.twist_deg, spec.twist_axis)
    q0 = np.concatenate(q0_parts)

    D = block.dofs_per_node
    fixed = set()
    for beam in beams:     # vectors the element does not interpolate (3333: r_yy, r_zz, r_yz) held at 0
        held = list(beam.layout.held)
        nodes = beam.node_offset + np.arange(beam.n_nodes)
        fixed.update((D * nodes[:, None] + (3 * np.array(held, dtype=int)[:, None] + np.arange(3)).ravel())
                     .ravel().tolist())
    n_dofs = D * q0.shape[0]
    loading = [LoadGroup(None, np.zeros(n_dofs), np.zeros(n_dofs))]      # the λ-proportional one
    supports = []
    for bc in spec.boundary_conditions:
        node = beams[bc.beam].node_offset + bc.node
        dofs = [D * node + 3 * v + c for v, c in bc.dofs]
        group = group_for(loading, None if bc.curve is None else LoadCurve(bc.curve), n_dofs)
        for v, c, value in bc.displacement:
            _interpolated(bc, beams[bc.beam], v, c, value)
            dofs.append(D * node + 3 * v + c)
            group.moves[dofs[-1]] = value
        fixed.update(dofs)
        supports.append(Support(bc.name, node, np.array(sorted(dofs), dtype=np.int64)))
    fixed_dofs = np.array(sorted(fixed), dtype=np.int64)

    for ld in spec.loads:
        beam = beams[ld.beam]
        node = beam.node_offset + ld.node
        force = np.asarray(ld.force)
        f_ext = group_for(loading, None if ld.curve is None else LoadCurve(ld.curve), n_dofs).forces
        if ld.kind == "force":
            f_ext[D * node:D * node + 3] += force
        else:
            # uniform dead traction t = F / A over the end section: f_k = t ∫ m_k dA
            moments = _end_moments(beam, tendon, spec.beams[ld.beam], beam.x_nodes[ld.node])
            f_ext[D * node:D * node + D] += np.outer(moments, force).ravel()
        _check_load_on_support(ld, beam, D * node, spec, supports)

    probes = {p.name: (beams[p.beam].node_offset + p.node,
                       _end_moments(beams[p.beam], tendon, spec.beams[p.beam], beams[p.beam].x_nodes[p.node])
                       if p.vector == "mean" else np.eye(block.vectors_per_node)[block.index(p.vector)])
              for p in spec.probes}
    warnings = (section_warnings(spec, beams) + cubature_warnings(spec, beams) + size_warnings(spec, beams) + point_force_warnings(spec, beams) + fibre_warnings(spec, beams)
                + material_warnings(spec, beams) + twist_warnings(spec, beams)
                + pretwist_resolution_warnings(spec, beams, q0) + load_warnings(spec) + reversed_load_warnings(spec)
                + unlisted_warnings(beams, spec.contact) + slope_warnings(spec)
                + sections_file_length_warnings(spec, {b.section.file: _sections_file(b.section.file, b.section.spline_degree)
                                                       .length_m for b in spec.beams if b.section.file is not None}))
    end_means, root_means = ([_end_moments(b, tendon, spec.beams[b.index], b.x_nodes[k]) for b in beams]
                             for k in (-1, 0))
    return Model(spec=spec, beams=beams, q0=q0, fixed_dofs=fixed_dofs, loading=loading, probes=probes,
                 geometry_report=report, warnings=warnings, supports=supports, end_means=end_means,
                 root_means=root_means)
