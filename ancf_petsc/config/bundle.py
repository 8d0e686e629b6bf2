"""Scene generator: a twisted bundle of fascicles in hexagonal packing.

A ``bundle:`` block in a config is expanded into ordinary config entries (beams with inline outline
sections, boundary conditions, loads, probes and contact) before validation, so everything else
(validation, contact discovery, partitioning, output) treats a bundle like any other model.

* ``hexagon`` fascicles tile the cross-section: neighbours share a whole edge, written as one named
  straight curve in both outlines, which makes it a sliding-contact interface.
* ``circle`` fascicles touch their neighbours along a line: each circle's outline is split into
  arcs, the arcs facing a neighbour are paired as a two-curve interface, and contact is unilateral
  (they may separate, not interpenetrate).

Packing: 1, 7, 19, 37, 61, 91, ... fascicles = the centre plus 0, 1, 2, ... hexagonal rings
(1 + 3 r (r + 1) for r rings, up to ``MAX_RINGS``).
"""
from __future__ import annotations

import math
import re

import numpy as np

from ..contact.laws import SlidingLaw, UnilateralLaw
from .specs import DEFAULT_AXIAL_POINTS
from .values import ConfigError, integer, mapping, number, shown, string, vector

MAX_RINGS = 20
COUNTS = {1 + 3 * r * (r + 1): r for r in range(MAX_RINGS + 1)}     # fascicles → rings
SECTIONS = ("hexagon", "circle")
KEYS_REQUIRED = ("count", "fascicle_section", "radius", "elements", "material", "force")
KEYS_OPTIONAL = ("packing", "gap", "arc_deg", "cubature_degree", "axial_points", "pulled_end",
                 "element", "locking", "column")
# a grip holds the pulled end's section orientation and transverse position (as a testing
# machine's clamp); the end moves along x only.  "free" lets every fascicle end align with the
# pull, and a frictionless twisted bundle then untwists like a rope (a near-mechanism at load 0)
GRIP = {"r": "yz", "r_y": "xz", "r_z": "xy"}


def hex_centres(rings: int, pitch: float) -> np.ndarray:
    """Centres of a hexagonal patch with ``rings`` rings around the origin, spacing ``pitch``.

    Axial coordinates (q, r) with |q|, |r|, |q + r| <= rings; flat-topped lattice so that
    neighbours are ``pitch`` apart in the directions 0°, 60°, ..., 300°.
    """
    out = []
    for q in range(-rings, rings + 1):
        for r in range(-rings, rings + 1):
            if abs(q + r) <= rings:
                out.append((q, r))
    qr = np.array(sorted(out, key=lambda a: (max(abs(a[0]), abs(a[1]), abs(a[0] + a[1])), a)))
    # unit vectors of the lattice at 0° and 60°
    e1 = np.array([1.0, 0.0])
    e2 = np.array([0.5, math.sqrt(3) / 2])
    return pitch * (qr[:, :1] * e1 + qr[:, 1:] * e2)


def _key(p: np.ndarray) -> tuple:
    return tuple(np.round(p * 1e9).astype(np.int64))          # nanometre grid


def hexagon_beams(centres: np.ndarray, circumradius: float) -> list[list[dict]]:
    """Inline outlines of pointy-topped hexagons (vertices at 30° + k 60°) that tile the patch:
    every edge shared by two hexagons carries the same name (and points) in both."""
    names: dict[tuple, str] = {}
    loops = []
    ang = np.deg2rad(30.0 + 60.0 * np.arange(7))
    for i, c in enumerate(centres):
        verts = c + circumradius * np.column_stack([np.cos(ang), np.sin(ang)])
        loop = []
        for k in range(6):
            a, b = verts[k], verts[k + 1]
            key = tuple(sorted([_key(a), _key(b)]))
            if key not in names:
                names[key] = f"edge{len(names)}"
            loop.append({"name": names[key], "points": [a.tolist(), b.tolist()]})
        loops.append(loop)
    return loops


def circle_beams(centres: np.ndarray, radius: float, pitch: float, arc_deg: float):
    """Circle outlines as 12 arcs: six facing the lattice neighbours (±arc_deg/2 around the
    contact line) and six between.  Returns the loops and the (fascicle, neighbour, arc name,
    neighbour's arc name) pairs."""
    half = np.deg2rad(arc_deg) / 2.0
    loops, pairs = [], []
    present = {_key(c): i for i, c in enumerate(centres)}
    for i, c in enumerate(centres):
        loop = []
        for k in range(6):
            mid = np.deg2rad(60.0 * k)
            for lo, hi, kind in ((mid - half, mid + half, "face"), (mid + half, mid + np.deg2rad(60) - half, "free")):
                t = np.linspace(lo, hi, 5)
                pts = c + radius * np.column_stack([np.cos(t), np.sin(t)])
                name = f"f{i}_{kind}{k}"
                loop.append({"name": name, "points": pts.tolist()})
            j = present.get(_key(c + pitch * np.array([np.cos(mid), np.sin(mid)])))
            if j is not None and j > i:
                pairs.append((i, j, f"f{i}_face{k}", f"f{j}_face{(k + 3) % 6}"))
        loops.append(loop)
    return loops, pairs


#: keys of the beams and loads a bundle generates, as the bundle's own (``bundle_key``)
GENERATED_KEYS = ((re.compile(r"beams\[\d+\]\.section\.cubature_degree"), "bundle.cubature_degree"),
                  (re.compile(r"beams\[\d+\]\.(material|element|locking|elements|axial_points)"), r"bundle.\1"),
                  (re.compile(r"loads\[\d+\]\.traction_force"), "bundle.force"),
                  (re.compile(r"loads\[\d+\]\.column"), "bundle.column"),
                  (re.compile(r"loads\[\d+\]"), "bundle.force"))


def bundle_key(path: str) -> str:
    """A config error's key path in the beams and loads a bundle generated, as the bundle key the
    user wrote (``beams[0].material.mu`` → ``bundle.material.mu``): the generated keys are not
    the user's, and writing them is refused."""
    for pattern, key in GENERATED_KEYS:
        m = pattern.match(path)
        if m:
            return m.expand(key) + path[m.end():]
    return path


def _circle_contact(contact: dict) -> None:
    """Circle fascicles touch along lines, their facing arcs apart elsewhere: sliding contact
    (gaps held at zero) and a tangential law (whose relative slip is zero only where the partners
    coincide: an elastic layer pulled on the arcs at rest, 8.3e-4 N at 1e10 Pa/m, and a run that
    loosened its tolerance from it) need interfaces that coincide, as hexagons share their edges."""
    if contact.get("mode") != UnilateralLaw.name:
        raise ConfigError("contact.mode", "circle fascicles touch along lines only: their contact is "
                                          "unilateral (remove mode), or use fascicle_section: hexagon")
    law = (contact.get("tangential") or {}).get("law", "none") if isinstance(contact.get("tangential"), dict) \
        else "none"
    if law != "none":
        raise ConfigError("contact.tangential", "a tangential law needs interfaces that coincide at rest; "
                                                "circle fascicles touch along lines only: use fascicle_section: "
                                                "hexagon, or remove contact.tangential")


def expand_bundle(raw: dict) -> dict:
    """Replace ``bundle:`` by beams, boundary conditions, loads, probes and contact (in place copy)."""
    b = mapping(raw["bundle"], "bundle", required=KEYS_REQUIRED, optional=KEYS_OPTIONAL)
    count = integer(b["count"], "bundle.count")
    if count not in COUNTS:
        raise ConfigError("bundle.count", f"must be a full hexagonal patch, 1 + 3 r (r + 1) for r "
                                          f"rings: {', '.join(map(str, list(COUNTS)[:7]))}, ... "
                                          f"({max(COUNTS)} at most); got {count}")
    string(b.get("packing", "hexagonal"), "bundle.packing", ("hexagonal",))
    shape = string(b["fascicle_section"], "bundle.fascicle_section", SECTIONS)
    radius = number(b["radius"], "bundle.radius", positive=True, hint=" (fascicle radius in m)")
    elements = integer(b["elements"], "bundle.elements", lo=1, hi=10000)
    force = vector(b["force"], "bundle.force", 3)
    if b.get("pulled_end", "grip") == "grip" and any(force[1:]):
        raise ConfigError("bundle.force", "the grip (pulled_end: grip) holds the pulled ends' y and z: "
                                          "give an axial force [F, 0, 0], or pulled_end: free; "
                                          f"got {shown(b['force'])}")
    for key in ("beams", "boundary_conditions", "loads"):
        if key in raw:
            raise ConfigError(key, "a bundle generates its beams, supports and loads; remove this key")
    out = {k: v for k, v in raw.items() if k != "bundle"}
    rings = COUNTS[count]
    section_opts = {"cubature_degree": integer(b.get("cubature_degree", 4), "bundle.cubature_degree", lo=1, hi=20),
                    "spline_degree": 3}
    if shape == "hexagon":
        for key in ("gap", "arc_deg"):
            if key in b:
                raise ConfigError(f"bundle.{key}", "applies to circle fascicles only (hexagons tile the "
                                                   "section, sharing their edges); remove it")
        pitch = math.sqrt(3.0) * radius              # flat-to-flat: the hexagons tile the plane
        centres = hex_centres(rings, pitch)
        loops = hexagon_beams(centres, radius)
        pairs = None
    else:
        # touching circles meet along lines: unilateral contact on the facing arcs
        gap = number(b.get("gap", 0.0), "bundle.gap", nonneg=True)
        pitch = 2.0 * radius + gap
        centres = hex_centres(rings, pitch)
        loops, pairs = circle_beams(centres, radius, pitch,
                                    number(b.get("arc_deg", 40.0), "bundle.arc_deg", positive=True, hi=59.0))
    axial = b.get("axial_points", DEFAULT_AXIAL_POINTS)      # checked per beam (0 said '>= 1', 1 '>= 2')
    per_beam = {k: b[k] for k in ("element", "locking") if k in b}     # checked per beam
    out["beams"] = [{"name": f"fascicle{i}", "elements": elements, "axial_points": axial,
                     "material": b["material"], **per_beam,
                     "section": {"shape": "outline", "curves": loop, **section_opts}}
                    for i, loop in enumerate(loops)]
    out["boundary_conditions"] = [{"beam": f"fascicle{i}", "node": "first", "fix": "reduced"}
                                  for i in range(count)]
    if string(b.get("pulled_end", "grip"), "bundle.pulled_end", ("grip", "free")) == "grip":
        out["boundary_conditions"] += [{"beam": f"fascicle{i}", "node": "last", "fix": dict(GRIP)}
                                       for i in range(count)]
    follows = {"column": b["column"]} if "column" in b else {}     # a load history's (history.py)
    out["loads"] = [{"beam": f"fascicle{i}", "node": "last",
                     "traction_force": [f / count for f in force], **follows} for i in range(count)]
    if "probes" not in out:
        outer = int(np.argmax(np.linalg.norm(centres, axis=1)))
        out["probes"] = [{"name": "centre", "beam": "fascicle0", "node": "last"},
                         {"name": "outer", "beam": f"fascicle{outer}", "node": "last"}]
    if count > 1:
        contact = dict(out.get("contact") or {})
        if shape == "circle":
            contact.setdefault("mode", UnilateralLaw.name)
            _circle_contact(contact)
            # closing contact from a touching start: the bt line search halves the iterations
            # (157 against 290 with basic on bundle_circle7)
            petsc = dict(out.get("petsc") or {})
            petsc.setdefault("snes_linesearch_type", "bt")
            out["petsc"] = petsc
            contact["interfaces"] = [{"a": f"fascicle{j}", "b": f"fascicle{i}", "curve": ca, "curve_b": cb}
                                     for i, j, cb, ca in pairs]
        else:
            # two points per edge and a gap linear along it: one mid-edge point per edge would
            # leave each hexagon free to spin about its own axis (mid-edge points move tangentially)
            contact.setdefault("mode", SlidingLaw.name)
            contact.setdefault("curve_points", 2)
            # (along the beam: the contact default, capped by the elements' degree and linear under friction)
            contact.setdefault("projection", {"curve": 1})
        out["contact"] = contact
    elif out.get("contact") is not None:
        raise ConfigError("contact", "a bundle of one fascicle has no interfaces (bundle.count: 1); "
                                     "remove contact, or give count 7 or more")
    return out
