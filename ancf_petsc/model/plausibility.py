"""Plausibility of a model's sizes and of its first converged level: lengths written in
millimetres where the config means metres (``length: 70`` for 0.07) solve for hundreds of Newton
iterations and fail without a word.  Each check gives one warning line naming the key and the
likely unit mistake; the model is built and solved as given."""
from __future__ import annotations

import math
import os
import re

import numpy as np

from ..physics.cubature import gauss_legendre
from ..physics.elements import ELEMENTS
from ..physics.geometry import rotation, twist_angle
from ..physics.materials import NeoHookean, StVenantKirchhoff

__all__ = ["MAX_LENGTH", "MAX_WIDTH", "SLENDERNESS", "MAX_FIRST_STRAIN", "MIN_OVERFLOW_STRETCH",
           "MIN_SHEAR_MODULUS", "MIN_FIBRE_STIFFNESS", "MAX_BULK_RATIO", "MAX_TWIST_DEG", "TWIST_AXIS_REACH", "MAX_SECTION_AREA_ERROR",
           "fibre_warnings", "load_warnings", "material_warnings", "size_warnings", "strain_warning",
           "point_force_warnings", "pretwist_resolution_warnings", "reversed_load_warnings",
           "section_area_errors", "twist_warnings"]

#: a tendon, fascicle or bar longer than this [m] is most likely given in mm
MAX_LENGTH = 5.0
#: a section wider than this [m] is most likely given in mm
MAX_WIDTH = 0.5
#: plausible range of a beam's length over the square root of its section area
SLENDERNESS = (1.0, 1000.0)
#: an axial strain beyond this (either sign) at the first converged level suggests wrong units
MAX_FIRST_STRAIN = 0.5
#: a fibre law whose exponential overflows (double precision) below this fibre stretch is warned
#: of: tendon fibres stretch by several per cent
MIN_OVERFLOW_STRETCH = 1.1
#: a (matrix) shear modulus below this [Pa] is most likely kPa or MPa written as Pa: the softest
#: published tendon matrix is 15 kPa (docs/fibres.md), the paper's subtendons 103-227 MPa
MIN_SHEAR_MODULUS = 1e3
#: a fibre stiffness k1 in (0, this) [Pa] is most likely kPa or MPa written as Pa: the published
#: sets have k1 = 1.0-135.5 MPa (docs/fibres.md); k1 = 0 switches the fibres off
MIN_FIBRE_STIFFNESS = 1e4
#: K / mu beyond this is incompressible past what Newton's tolerance resolves (studies sweep to 1e4)
MAX_BULK_RATIO = 1e6
#: a pretwist beyond this [deg] over the tendon's length is more than a full turn (measured: 0-180)
MAX_TWIST_DEG = 360.0
#: a twist axis farther than this many section widths from every section winds them on a helix
TWIST_AXIS_REACH = 10.0
#: the reference section's area (det of the interpolated reference Jacobian over the exact pretwisted
#: one's) may be off by this fraction at an axial Gauss point: on the Achilles tendon (2 axial points)
#: the soleus elongation is off by about as much as the area (docs/model.md, "Resolving the pretwist")
MAX_SECTION_AREA_ERROR = 0.01
#: ln of the largest double: e^x is inf beyond it
LOG_MAX_DOUBLE = float(np.log(np.finfo(float).max))


def _section_key(spec, i: int) -> str:
    """The config key a beam's section dimensions come from."""
    bs = spec.beams[i].section
    if bs.curves is not None:            # inline outlines; a bundle's fascicles are written so
        bundle = re.fullmatch(r"fascicle\d+", spec.beams[i].name) is not None
        return "bundle.radius" if bundle else f"beams[{i}].section.curves"
    if bs.shape == "outline" and bs.file is None:
        return "geometry.sections"
    return f"beams[{i}].section" + (".file" if bs.file else "")


def section_warnings(spec, beams) -> list[str]:
    """The notes of the beams' section rules (a cubature compression that failed: the raw rule kept,
    points possibly outside the section, negative weights), which were built and never shown."""
    return [f"warning: {_section_key(spec, i)}: beam {b.name}: {n}" for i, b in enumerate(beams)
            for n in b.section.notes]


def cubature_warnings(spec, beams) -> list[str]:
    """A section rule below degree 2 × the element's section order (4 for 3363; 33103 and 33153 are
    raised to theirs, ``Element.section_degree``) under-integrates the section field: a 2 × 2
    rectangle rule leaves 3363 spurious section modes (the bending scene's error stalls at 3 %,
    docs/studies.md), and the answer depends on how the section is written (the elastica on a
    square at degree 3: the rectangle's rule and the same square as an outline 2e-4 apart)."""
    out, said = [], set()
    for i, b in enumerate(beams):
        order, got = ELEMENTS[b.element].order, spec.beams[i].section.cubature_degree
        key = ("bundle" if _section_key(spec, i) == "bundle.radius" else f"beams[{i}].section") + ".cubature_degree"
        if got < 2 * order and key not in said:
            said.add(key)
            out.append(f"warning: {key}: {got} under-integrates element {b.element}'s order-{order} "
                       f"section field (spurious section modes; docs/studies.md): use {2 * order} or more")
    return out


def size_warnings(spec, beams) -> list[str]:
    """Warnings (one line each) for a length or section sizes that look like millimetres
    (SI units: metres), else for a beam length / sqrt(area) outside ``SLENDERNESS``."""
    out = []
    L = spec.length
    if L > MAX_LENGTH:
        out.append(f"warning: geometry.length is {L:g} m (longer than {MAX_LENGTH:g} m): lengths are in "
                   f"metres (units: SI); if you meant {L:g} mm, write length: {L * 1e-3:g}")
    wide = [(i, b, 2.0 * float(np.max(b.section.extent))) for i, b in enumerate(beams)
            if 2.0 * float(np.max(b.section.extent)) > MAX_WIDTH]
    if wide:
        i, b, w = wide[0]
        more = f" (and {len(wide) - 1} more beam(s))" if len(wide) > 1 else ""
        out.append(f"warning: {_section_key(spec, i)}: the section of beam {b.name} is {w:g} m wide"
                   f"{more} (more than {MAX_WIDTH:g} m): section sizes are in metres (units: SI); "
                   f"if they are millimetres, divide them by 1000")
    if out:
        return out
    lo, hi = SLENDERNESS
    for i, b in enumerate(beams):
        s = L / np.sqrt(b.section.area)
        if not lo <= s <= hi:
            short = s < lo
            out.append(f"warning: beam {b.name}: length / sqrt(section area) = {s:.3g} (plausible "
                       f"{lo:g} to {hi:g}): geometry.length {L:g} m against a section of "
                       f"{b.section.area * 1e6:.4g} mm^2; check the units (metres) of "
                       + (f"{_section_key(spec, i)} (too large?)" if short else
                          f"geometry.length (too long?) and {_section_key(spec, i)}"))
            break
    return out


def strain_warning(model, q: np.ndarray, load_factor: float) -> str | None:
    """A warning when some beam's axis (its nodes' r) is stretched or shortened by more than
    ``MAX_FIRST_STRAIN`` at the first converged level (nodal vectors ``q``, (n_nodes, 6, 3))."""
    worst, where = 0.0, None
    for b in model.beams:
        nodes = b.node_offset + np.arange(b.n_nodes)
        d = np.linalg.norm(np.diff(q[nodes, 0], axis=0), axis=1)
        d0 = np.linalg.norm(np.diff(model.q0[nodes, 0], axis=0), axis=1)
        e = d / d0 - 1.0
        k = int(np.argmax(np.abs(e)))
        if abs(e[k]) > abs(worst):
            worst, where = float(e[k]), b.name
    if abs(worst) <= MAX_FIRST_STRAIN:
        return None
    return (f"warning: at the first converged level (load factor {load_factor:g}) beam {where}'s axis "
            f"is {abs(worst) * 100:.0f} % {'longer' if worst > 0 else 'shorter'} (axial strain beyond "
            f"{MAX_FIRST_STRAIN * 100:.0f} %): check the units (SI: N in loads, Pa in materials, "
            "e.g. mu: 103.1e6 not 103.1; m in geometry)")


def point_force_warnings(spec, beams) -> list[str]:
    """One warning per point force on r of a beam with ``locking: mixed``: a point force on r
    deforms the loaded end section in the mode (axial strain ∝ ρ²) that ``mixed`` frees from the
    volumetric term and the quadratic section resists only weakly; the node's displacement is then
    4-5 % larger than without the remedy, where a traction changes nothing (docs/locking.md)."""
    return [f"warning: {ld.path or 'loads'}: a point force on r of beam {beams[ld.beam].name}, which has "
            "locking: mixed; its node's displacement includes the end section's local deformation, which "
            "mixed leaves 4-5 % softer (docs/locking.md): for the beam's response load it with traction_force"
            for ld in spec.loads if ld.kind == "force" and beams[ld.beam].locking == "mixed"]


def _zero(vector, curve) -> bool:
    """Whether a load or prescribed displacement is zero at every load factor."""
    return all(v == 0.0 for v in vector) or (curve is not None and all(m == 0.0 for _, m in curve))


def load_warnings(spec) -> list[str]:
    """One warning when nothing moves the model: every load and prescribed displacement zero at
    every load factor (all-zero forces, or curves and history columns of zeros).  The solution is
    then the reference state at every level, where the stability check's inertia count is not
    meaningful (a saddle-point matrix without pressures)."""
    loads = [(ld.force, ld.curve) for ld in spec.loads]
    moved = [([v for _, _, v in bc.displacement], bc.curve) for bc in spec.boundary_conditions if bc.displacement]
    if loads + moved and not all(_zero(v, c) for v, c in loads + moved):
        return []
    return ["warning: loads: every load and prescribed displacement is zero at every level: the solution is "
            "the reference state; give a load a nonzero force (or a history column with nonzero values)"]


def _frames(ks: list[int]) -> str:
    """Frame numbers as ranges: 9-10, 14."""
    runs, start = [], ks[0]
    for a, b in zip(ks, ks[1:] + [None]):
        if b != a + 1:
            runs.append(f"{start}-{a}" if a > start else f"{a}")
            start = b
    return ", ".join(runs[:4]) + (", ..." if len(runs) > 4 else "")


def _outward(spec, ld) -> float:
    """The x component of a load's vector out of its beam: +x on the last node, -x on the first
    (0 on an interior node: neither pull nor push)."""
    b = spec.beams[ld.beam]
    last = ELEMENTS[b.element].block.nodes_of(b.elements) - 1
    return ld.force[0] if ld.node == last else -ld.force[0] if ld.node == 0 else 0.0


def reversed_load_warnings(spec) -> list[str]:
    """One warning per load of a ``history`` that pushes the end section it acts on into its
    beam at some frames: a negative column under a vector pointing out of the beam, or a
    positive one under a vector pointing in (forces written negative and mapped with a vector
    -x pull).  Muscle forces pull only, and a tendon pushed at its end buckles: on the paper's
    tendon at 90° the frames at −20 and −50 N stopped the sliding, unilateral and μ = 0.3 runs
    (docs/gait.md, "A load history")."""
    if spec.history is None:
        return []
    out = []
    for ld in spec.loads:
        outward = _outward(spec, ld)
        push = [(int(round(k)), m) for k, m in ld.curve or () if outward * m < 0.0]
        if not push:
            continue
        frames, where = _frames([k for k, _ in push]), ld.path or "loads"
        if outward > 0.0:
            out.append(f"warning: {where}: its history column is negative at frame(s) {frames} "
                       f"(down to {min(m for _, m in push):g} x its {ld.kind}): the load then points against its "
                       f"vector, a pull turned into a push (muscle forces are positive; a pushed tendon buckles); "
                       f"check the column's sign or scale")
        else:
            end = "last" if ld.force[0] == outward else "first"
            out.append(f"warning: {where}: its {ld.kind} points into beam {spec.beams[ld.beam].name} at its {end} "
                       f"node (x component {ld.force[0]:g}): the column positive at frame(s) {frames} (up to "
                       f"{max(m for _, m in push):g}) pushes the end section (muscle forces pull; a pushed tendon "
                       f"buckles); point the vector out of the beam, or check the column's sign")
    return out


def _material_beams(spec, beams) -> list[tuple[str, object, str]]:
    """(the config key of its material, beam, its name for a message) per beam; a bundle's
    fascicles share bundle.material, named once (7 fascicles gave 7 alike warnings, each keyed
    beams[i].material, which the config does not have)."""
    out, bundle = [], False
    for i, b in enumerate(beams):
        if _section_key(spec, i) != "bundle.radius":
            out.append((f"beams[{i}].material", b, b.name))
        elif not bundle:
            bundle = True
            out.append(("bundle.material", b, f"{b.name} (and every other fascicle)"))
    return out


def fibre_warnings(spec, beams) -> list[str]:
    """One warning per fibre-reinforced beam whose e^(k2 Ē²) overflows below a fibre stretch of
    ``MIN_OVERFLOW_STRETCH`` (Ē = I4 − 1 without dispersion): its fibre stresses there are inf
    (surface_NNNN.vtu stores single precision, which overflows sooner)."""
    out = []
    for key, b, name in _material_beams(spec, beams):
        k2 = getattr(b.material, "k2", None)
        if k2 is None or not b.material.k1:            # k1 = 0: the fibres are off, nothing overflows
            continue
        E = float(np.sqrt(LOG_MAX_DOUBLE / k2))
        stretch = float(np.sqrt(1.0 + E))
        if stretch < MIN_OVERFLOW_STRETCH:
            out.append(f"warning: {key}.k2: {k2:g}: the fibre term e^(k2 E^2) of beam {name} "
                       f"overflows (inf stress) from a fibre stretch of {stretch:.4g} (E = {E:.3g}); tendon "
                       f"fibres stretch by several per cent; the published sets have k2 = 4.8 to 525 (docs/fibres.md)")
    return out + [w for key, b, name in _material_beams(spec, beams) for w in _lateral_fibre_warning(key, b, name)]


def _lateral_fibre_warning(key: str, beam, name: str) -> list[str]:
    """One warning for a beam with a linear section field (3333) whose fibres see the section's
    lateral strains (dispersion kappa > 0, or families at an angle to the material lines): that
    field cannot vary them over the section (Poisson locking) and ``locking: ecm`` frees only the
    matrix, so bending came out 6-9 % off with no word (tension stays exact; docs/fibres.md)."""
    law = beam.material
    if ELEMENTS[beam.element].order > 1 or not getattr(law, "k1", 0.0):
        return []
    angles = [a for a in law.fibres["angles_deg"] if a]
    seen = ([f"kappa {law.kappa:g}"] if law.kappa else []) + \
        ([f"fibres at {', '.join(f'{a:g}' for a in angles)} deg"] if angles else [])
    if not seen:
        return []
    return [f"warning: {key.rsplit('.', 1)[0]}.element: {beam.element} with fibres that see the section's lateral "
            f"strains (beam {name}: {'; '.join(seen)}): its linear section field cannot vary those strains over the "
            f"section, and locking: ecm frees only the matrix, so bending comes out wrong (a cantilever: "
            f"7.8 % too stiff at kappa 0.2, 9.3 % at +-30 deg, 6.3 % too soft with fibres across; tension stays exact; "
            f"docs/fibres.md); use element 3363 or 33103"]


def material_warnings(spec, beams) -> list[str]:
    """One warning per beam whose (matrix) shear modulus mu is below ``MIN_SHEAR_MODULUS`` (SVK: E
    below 3x it; a unit slip), else whose bulk modulus K gives a negative small-strain Poisson
    ratio (K < 2 mu / 3: an auxetic tendon, most likely a unit slip in K) or K / mu above
    ``MAX_BULK_RATIO``; and one whose fibre stiffness k1 is in (0, ``MIN_FIBRE_STIFFNESS``)
    (k1: 3.7859 for 3.7859 MPa ran to 'completed' with no word, the bar as soft as its matrix)."""
    out = []
    for where, b, name in _material_beams(spec, beams):
        law = getattr(b.material, "matrix", b.material)         # GOH: its neo-Hookean matrix
        key = f"warning: {where}"
        k1 = getattr(b.material, "k1", 0.0)
        if 0.0 < k1 < MIN_FIBRE_STIFFNESS:
            out.append(f"{key}.k1: {k1:g} Pa for beam {name}: fibres this soft add next to nothing to the matrix "
                       f"(the published sets have k1 = 1.0-135.5 MPa, docs/fibres.md): moduli are in Pa (units: "
                       f"SI); if you meant {k1:g} MPa, write {k1:g}e6 (k1: 0 switches the fibres off)")
        if isinstance(law, StVenantKirchhoff) and law.E < 3.0 * MIN_SHEAR_MODULUS:
            out.append(f"{key}.E: {law.E:g} Pa for beam {name} is softer than any tendon (matrices from 15 kPa, "
                       f"the paper's subtendons 103-227 MPa): moduli are in Pa (units: SI); if you meant "
                       f"{law.E:g} MPa, write {law.E:g}e6")
        if not isinstance(law, NeoHookean):
            continue
        mu, K = law.mu, law.K
        if mu < MIN_SHEAR_MODULUS:
            out.append(f"{key}.mu: {mu:g} Pa for beam {name} is softer than any tendon (matrices from 15 kPa, "
                       f"the paper's subtendons 103-227 MPa): moduli are in Pa (units: SI); if you meant "
                       f"{mu:g} MPa, write {mu:g}e6")
        elif K < 2.0 * mu / 3.0 or K > MAX_BULK_RATIO * mu:
            nu = law.poisson
            what = "negative (auxetic)" if nu < 0 else f"incompressible beyond K/mu = {MAX_BULK_RATIO:g}"
            out.append(f"{key}.bulk_modulus: K = {K:g} Pa is {K / mu:.3g} x mu for beam {name}: a small-strain "
                       f"Poisson ratio of {nu:.7g}, {what}; tendon is nearly incompressible (the paper's "
                       f"K/mu 3.8-8.3); check K's units (Pa)")
    return out


def twist_warnings(spec, beams) -> list[str]:
    """Warnings for a pretwist of more than ``MAX_TWIST_DEG`` and for a twist axis farther than
    ``TWIST_AXIS_REACH`` section widths from every section's centroid (millimetres written as
    metres: the sections then wind round it on a helix of that radius)."""
    out = []
    if abs(spec.twist_deg) > MAX_TWIST_DEG:
        out.append(f"warning: geometry.twist_deg: {spec.twist_deg:g} deg is more than a full turn over the tendon's "
                   f"length (measured subtendon twists are 0-180 deg); twist_deg is in degrees")
    if spec.twist_deg and spec.twist_axis is not None and beams:
        width = max(2.0 * float(np.max(b.section.extent)) for b in beams)
        dist = min(float(np.linalg.norm(b.section.centroid - np.asarray(spec.twist_axis))) for b in beams)
        if dist > TWIST_AXIS_REACH * width:
            out.append(f"warning: geometry.twist_axis: the axis is {dist:.3g} m from the nearest section centroid "
                       f"({dist / width:.3g} x the sections' width), so the sections wind round it on a helix; "
                       f"coordinates are in metres (units: SI): if they are millimetres, divide them by 1000")
    return out


def sections_file_length_warnings(spec, file_lengths: dict[str, float | None]) -> list[str]:
    """A sections file's ``length_m`` (the source's tendon length, not read by the model) that is
    not geometry.length: a traced subject's file with its own length ran silently at the config's."""
    out = []
    for path, length in file_lengths.items():
        if length is not None and not math.isclose(length, spec.length, rel_tol=1e-6):
            out.append(f"warning: geometry.length: {spec.length:g} m, but the sections file "
                       f"'{os.path.basename(path)}' gives length_m {length:g} m; the config's length is "
                       "used (set geometry.length to the file's if that is the tendon's)")
    return out


def section_area_errors(beam, q0: np.ndarray, length: float, twist_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """det J0 / det J0_exact − 1 at the axial Gauss points on a beam's axis, (E, na), and their x (E, na):
    J0 the element's interpolation of the reference nodal vectors ``q0`` (the solver's det of the
    reference Jacobian), J0_exact the exact pretwisted map's, (h/2) det R(θ(x)) (the section area)."""
    xa, _ = gauss_legendre(beam.axial_points)
    conn = beam.connectivity
    q0e = q0[conn][:, :, list(beam.vectors)].reshape(len(conn), -1, 3)
    det = np.linalg.det(np.einsum("eai,paj->epij", q0e, beam.dN_axis))
    x0, x1 = q0[conn[:, 0], 0, 0], q0[conn[:, -1], 0, 0]
    x = x0[:, None] + 0.5 * (1.0 + xa[None, :]) * (x1 - x0)[:, None]
    exact = 0.5 * (x1 - x0)[:, None] * np.linalg.det(rotation(twist_angle(x, length, twist_deg)))
    return det / exact - 1.0, x


def _elements_needed(beam, twist_deg: float) -> tuple[int, float] | None:
    """``elements_resolving`` a beam's pretwist, more elements than it has."""
    return elements_resolving(twist_deg, beam.axial_points, beam.layout.block, beam.n_elements + 1)


def elements_resolving(twist_deg: float, axial_points: int, block, fewest: int = 1) -> tuple[int, float] | None:
    """The fewest elements (at least ``fewest``) whose interpolation of the uniformly turning
    directors keeps the area error within ``MAX_SECTION_AREA_ERROR``, and that error: the area ratio
    at ξ is |Σ_i L_i(ξ) e^(iφ t_i)|² (φ the twist per element, t_i the nodes' places in it)."""
    L, _ = block.axial(gauss_legendre(axial_points)[0])
    E = np.arange(fewest, 10001)
    phi = np.deg2rad(twist_deg) / E
    t = np.linspace(0.0, 1.0, block.axial_nodes)
    ratio = np.abs(np.exp(1j * phi[:, None, None] * t[None, None, :]) @ L.T[None, :, :]) ** 2   # (E, 1, na)
    err = np.max(np.abs(ratio[:, 0] - 1.0), axis=1)
    ok = np.flatnonzero(err <= MAX_SECTION_AREA_ERROR)
    return (int(E[ok[0]]), float(err[ok[0]])) if len(ok) else None


def pretwist_resolution_warnings(spec, beams, q0: np.ndarray) -> list[str]:
    """One warning when some beam's reference section area, as its element interpolates the
    pretwisted nodal vectors, is off by more than ``MAX_SECTION_AREA_ERROR`` at an axial Gauss point
    (180 deg over one 3363 element: 22 %, and the soleus elongation 29 % too large), naming the
    worst beam, the error, its place and the elements that would bring it within the limit."""
    bad = []
    for i, b in enumerate(beams):
        err, x = section_area_errors(b, q0, spec.length, spec.twist_deg)
        k = np.unravel_index(int(np.argmax(np.abs(err))), err.shape)
        if abs(err[k]) > MAX_SECTION_AREA_ERROR:
            bad.append((abs(err[k]), i, b, float(err[k]), k, float(x[k])))
    if not bad:
        return []
    _, i, b, e, (k, g), x = max(bad, key=lambda t: t[0])
    more = f" (and {len(bad) - 1} more beam(s))" if len(bad) > 1 else ""
    xi = gauss_legendre(b.axial_points)[0][g]
    need = _elements_needed(b, spec.twist_deg) if spec.twist_deg else None
    fix = (f"use elements: {need[0]} or more ({need[1] * 100:.2g} %)" if need else "use more elements")
    key = "bundle.elements" if _section_key(spec, i) == "bundle.radius" else f"beams[{i}].elements"
    return [f"warning: {key}: the pretwist ({spec.twist_deg:g} deg over {b.n_elements} element(s)) is under-resolved "
            f"in beam {b.name}{more}: the element's interpolation of r_y, r_z between its nodes "
            f"{'shrinks' if e < 0 else 'grows'} the reference section's area by {abs(e) * 100:.2g} % at "
            f"x = {x * 1e3:.4g} mm (element {k + 1}, axial Gauss point xi = {xi:.3g}), beyond "
            f"{MAX_SECTION_AREA_ERROR * 100:g} %, and the answer with it (docs/model.md); {fix}"]
