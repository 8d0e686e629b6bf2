"""``beams:`` of a config: sections, materials, elements (paper Secs. 2.1-2.3)."""
from __future__ import annotations

import numbers
import os

from ..errors import MISSING_KEY, UNKNOWN_KEY
from ..physics.elements import DEFAULT_ELEMENT, ELEMENTS
from ..physics.goh import GOH
from ..physics.laws import VOLUMETRIC_LAWS
from ..physics.materials import NeoHookean, StVenantKirchhoff
from .specs import (DEFAULT_AXIAL_POINTS, FIBRE_FOLLOW, LOCKING, MATERIAL_MODELS, SECTION_SHAPES, BeamSpec,
                    SectionSpec)
from .values import (ConfigError, boolean, integer, key_path, mapping, number, sequence, shown, spline_degree, string,
                     vector)


def parse_beams(value, base_dir: str) -> list[BeamSpec]:
    """``beams``: name, section, material, element count and type, Gauss points along ξ."""
    beams: list[BeamSpec] = []
    for i, b in enumerate(sequence(value, "beams")):
        p = f"beams[{i}]"
        mapping(b, p, required=("name", "section", "material", "elements"),
                optional=("axial_points", "element", "locking"))
        bname = string(b["name"], f"{p}.name")
        if bname in [x.name for x in beams]:
            raise ConfigError(f"{p}.name", f"duplicate beam name {bname!r}; names must be unique")
        element = _element_name(b.get("element", DEFAULT_ELEMENT), f"{p}.element")
        beams.append(BeamSpec(
            name=bname,
            section=parse_section(b["section"], f"{p}.section", base_dir),
            material=parse_material(b["material"], f"{p}.material"),
            elements=integer(b["elements"], f"{p}.elements", lo=1, hi=100000),
            axial_points=_axial_points(b.get("axial_points", DEFAULT_AXIAL_POINTS), f"{p}.axial_points",
                                       ELEMENTS[element].block.axial_nodes)))
        beams[-1].element = element
        _element_choices(beams[-1], b, p)
    return beams


def _element_choices(beam: BeamSpec, raw: dict, p: str) -> None:
    """What the element decides for ``beams[i]``: the section rule raised to its least degree
    (2 × order for 33103, 33153: ``Element.section_degree``), the locking remedy (its default
    unless given) among those it accepts (``Element.remedies``)."""
    e = ELEMENTS[beam.element]
    e.raise_section_rule(beam.section)
    beam.locking = string(raw.get("locking", e.default_locking), f"{p}.locking", LOCKING)
    beam.parsed = (beam.element, "locking" in raw)
    _check_remedy(beam, p)


def check_edited_beams(beams: list[BeamSpec]) -> None:
    """``parse_beams``' checks and element choices again, for beams changed after parsing (the
    Python API): element count, type and axial points refused as in a config; a changed element
    type takes its own locking remedy unless the config gave one or it was changed too (3333 kept
    3363's 'none': Poisson locking, the bending tip 12x short), and one with another node block
    is refused (33103 kept 3363's 18 clamped DOFs of its 30: the tip 8 % off); the material is
    read again (mu -1e6 ran, to 'unstable')."""
    for i, beam in enumerate(beams):
        p = f"beams[{i}]"
        beam.elements = integer(_plain(beam.elements), f"{p}.elements", lo=1, hi=100000)
        beam.element = _element_name(beam.element, f"{p}.element")
        now = ELEMENTS[beam.element]
        beam.axial_points = _axial_points(_plain(beam.axial_points), f"{p}.axial_points", now.block.axial_nodes)
        if beam.parsed is not None and beam.parsed[0] != beam.element:
            was, locking_given = ELEMENTS[beam.parsed[0]], beam.parsed[1]
            if was.block != now.block:
                raise ConfigError(f"{p}.element", f"changed after parsing from {was.name}, whose node block "
                                  f"({', '.join(was.block.names)}) the supports, loads, probes and contact "
                                  f"were read for; set it in the config and parse that (parse_config) instead; "
                                  f"got {beam.element!r}")
            if not locking_given and beam.locking == was.default_locking:
                beam.locking = now.default_locking
            beam.parsed = (beam.element, locking_given)
        beam.material = parse_material(material_as_written(beam.material), f"{p}.material")
        beam.locking = string(beam.locking, f"{p}.locking", LOCKING)
        _check_remedy(beam, p)


def material_as_written(material: dict) -> dict:
    """A parsed material as a config gives it (GOH's fibres.angles_deg back to angle_deg): what
    results.h5's config_yaml stores for a material edited through the API (api.py).  An
    angle_deg beside angles_deg is an edit in the config's key (a parsed material has none), and
    wins (fibres['angle_deg'] = 60 was dropped for the parsed 0 deg: the 0 deg answer)."""
    fibres = material.get("fibres") if isinstance(material, dict) else None
    if not isinstance(fibres, dict) or "angles_deg" not in fibres:
        return material
    written = {k: v for k, v in fibres.items() if k != "angles_deg"}
    return dict(material, fibres=dict(written, angle_deg=written.get("angle_deg", list(fibres["angles_deg"]))))


def _plain(value):
    """A numpy integer as a Python int (``spec.beams[0].elements = np.int64(4)``)."""
    return int(value) if isinstance(value, numbers.Integral) and not isinstance(value, bool) else value


def _check_remedy(beam: BeamSpec, p: str) -> None:
    """The locking remedy of ``beams[i]`` is one its element and material accept."""
    e = ELEMENTS[beam.element]
    if beam.locking not in e.remedies:
        raise ConfigError(f"{p}.locking", f"{beam.locking!r} is not a remedy of element {e.name} "
                          f"({e.refused_because}, docs/locking.md); use " + " or ".join(repr(r) for r in e.remedies))
    if beam.locking == "ecm" and e.order >= 2 and "fibres" in beam.material:
        raise ConfigError(f"{p}.locking", f"'ecm' on element {e.name} with a fibre law loads the quadratic modes "
                          "(d(y^2/2)/dx has a non-zero section mean) with the nu = 0 matrix's axial stress, the "
                          "law's only where the fibres carry no lateral stress: uniaxial tension with kappa 0.2 "
                          "is 0.92 % off, the section warped (docs/locking.md); use 'none' or 'mixed'")
    if beam.locking == "mixed" and beam.material["model"] not in VOLUMETRIC_LAWS:
        raise ConfigError(f"{p}.locking", f"'mixed' projects the volumetric term K/2 (J - 1)^2 of "
                          f"{' or '.join(VOLUMETRIC_LAWS)}; {beam.material['model']!r} has none: "
                          "use 'none'")


def parse_section(value, path: str, base_dir: str) -> SectionSpec:
    """``beams[i].section``: an analytic shape or an outline (paper Sec. 2.2)."""
    common = ("shape", "center", "cubature_degree")
    shape = string(mapping(value, path, required=("shape",),
                           optional=common[1:] + ("semi_axes", "radius", "size", "curves", "file",
                                                  "loop", "spline_degree", "compress"))["shape"],
                   key_path(path, "shape"), SECTION_SHAPES)
    per_shape = {"ellipse": ("semi_axes",), "circle": ("radius",), "rectangle": ("size",),
                 "outline": ()}
    opt_outline = ("curves", "file", "loop", "spline_degree", "compress")
    allowed_extra = per_shape[shape] + (opt_outline if shape == "outline" else ())
    mapping(value, path, required=("shape",) + per_shape[shape], optional=common[1:] + allowed_extra)
    s = SectionSpec(shape=shape)
    if "center" in value:
        s.center = vector(value["center"], key_path(path, "center"), 2)
    if "cubature_degree" in value:
        s.cubature_degree = _cubature_degree(value["cubature_degree"], key_path(path, "cubature_degree"))
    if shape == "ellipse":
        s.semi_axes = vector(value["semi_axes"], key_path(path, "semi_axes"), 2, positive=True)
    elif shape == "circle":
        s.radius = number(value["radius"], key_path(path, "radius"), positive=True, hint=" (metres)")
    elif shape == "rectangle":
        s.size = vector(value["size"], key_path(path, "size"), 2, positive=True)
    else:
        _outline(value, path, base_dir, s, common)
    return s


def _outline(value, path: str, base_dir: str, s: SectionSpec, common: tuple) -> None:
    """An outline section: inline curves, a sections file + loop, or a loop of geometry.sections."""
    opt_outline = ("curves", "file", "loop", "spline_degree", "compress")
    has_curves, has_file = "curves" in value, "file" in value
    if has_curves == has_file and not (has_curves is False and "loop" in value):
        raise ConfigError(path, "an outline needs either 'curves' (inline loop of point lists), "
                                "'file' + 'loop' (sections file) or 'loop' alone (an outline of "
                                "geometry.sections), not both/neither")
    if not has_curves and not has_file:
        s.loop = string(value["loop"], key_path(path, "loop"))
    elif has_file:
        mapping(value, path, required=("shape", "file", "loop"), optional=common[1:] + opt_outline)
        f = string(value["file"], key_path(path, "file"))
        s.file = f if os.path.isabs(f) else os.path.normpath(os.path.join(base_dir, f))
        if not os.path.isfile(s.file):
            raise ConfigError(key_path(path, "file"), f"file not found: {s.file} "
                              "(paths are relative to the config file)")
        s.loop = string(value["loop"], key_path(path, "loop"))
    else:
        curves = sequence(value["curves"], key_path(path, "curves"))
        out = []
        for i, c in enumerate(curves):
            cp = key_path(key_path(path, "curves"), i)
            mapping(c, cp, required=("points",), optional=("name",))
            pts = sequence(c["points"], key_path(cp, "points"))
            if len(pts) < 2:
                raise ConfigError(key_path(cp, "points"), "a curve needs at least 2 points")
            pts = [vector(p, key_path(key_path(cp, "points"), j), 2) for j, p in enumerate(pts)]
            entry = {"points": pts}
            if "name" in c:      # named curves shared by two outlines are contact interfaces
                entry["name"] = string(c["name"], key_path(cp, "name"))
            out.append(entry)
        s.curves = out
    if "spline_degree" in value:
        s.spline_degree = spline_degree(value["spline_degree"], key_path(path, "spline_degree"), hi=7)
        s.spline_degree_given = True
    if "compress" in value:
        s.compress = boolean(value["compress"], key_path(path, "compress"))


GOH_KEYS = ("k1", "k2", "kappa", "fibres")
NEO_HOOKEAN_KEYS = ("model", "mu", "bulk_modulus", "c10", "d")
#: each model's keys (a fibre key on an isotropic law has its own message: ``_no_fibres``)
MATERIAL_KEYS = {NeoHookean.name: NEO_HOOKEAN_KEYS, StVenantKirchhoff.name: ("model", "E", "nu"),
                 GOH.name: NEO_HOOKEAN_KEYS + GOH_KEYS}


def parse_material(value, path: str) -> dict:
    """``beams[i].material``: neo-Hookean (mu, K or the paper's c10, d; eq. 14), SVK, or GOH
    (a neo-Hookean matrix given the same way, plus k1, k2, kappa, fibres); a key is checked
    against its model's keys (a goh key on another law: ``_no_fibres``)."""
    every = tuple(dict.fromkeys(k for keys in MATERIAL_KEYS.values() for k in keys))
    given = tuple(value) if isinstance(value, dict) else ()
    model = string(mapping(value, path, required=("model",), optional=given or every)["model"],
                   key_path(path, "model"), MATERIAL_MODELS)
    for key in value:
        if key not in MATERIAL_KEYS[model] + GOH_KEYS:
            owner = next((m for m, keys in MATERIAL_KEYS.items() if key in keys), None)
            raise ConfigError(key_path(path, key), f"unknown key for model: {model}"
                              + (f" (a key of model: {owner})" if owner else "")
                              + f"; allowed here: {', '.join(sorted(MATERIAL_KEYS[model]))}", UNKNOWN_KEY)
    return MATERIAL_PARSERS[model](value, path)


def _no_fibres(value, path: str) -> None:
    extra = [k for k in GOH_KEYS if k in value]
    if extra:
        raise ConfigError(key_path(path, extra[0]), f"a fibre parameter of model: {GOH.name}, not of "
                          f"{value['model']}; remove {', '.join(extra)} or give model: {GOH.name}")


def _goh_material(value, path: str) -> dict:
    matrix = {k: v for k, v in value.items() if k not in GOH_KEYS}
    return dict(_neo_hookean(matrix, path), model=GOH.name, **_goh(value, path))


def _svk(value, path: str) -> dict:
    _no_fibres(value, path)
    mapping(value, path, required=("model", "E", "nu"))
    nu = number(value["nu"], key_path(path, "nu"), lo=-0.999, hint=" (Poisson ratio)")
    if nu >= 0.5:
        raise ConfigError(key_path(path, "nu"), f"must be < 0.5 for St. Venant-Kirchhoff; got {nu:g}")
    return {"model": StVenantKirchhoff.name, "E": number(value["E"], key_path(path, "E"), positive=True,
                                                         hint=" (Young's modulus in Pa)"), "nu": nu}


def _neo_hookean(value, path: str) -> dict:
    """The neo-Hookean law (also GOH's matrix, ``value`` without the fibre keys)."""
    _no_fibres(value, path)
    ours, papers = [k for k in ("mu", "bulk_modulus") if k in value], [k for k in ("c10", "d") if k in value]
    if ours and papers:
        raise ConfigError(path, f"give either mu and bulk_modulus or the paper's c10 and d "
                                f"(mu = 2 c10, bulk_modulus = d), not both; got {', '.join(ours + papers)}")
    if "mu" in value or "bulk_modulus" in value:
        mapping(value, path, required=("model", "mu", "bulk_modulus"))
        mu = number(value["mu"], key_path(path, "mu"), positive=True, hint=" (shear modulus in Pa)")
        K = number(value["bulk_modulus"], key_path(path, "bulk_modulus"), positive=True,
                   hint=" (bulk modulus in Pa)")
    elif "c10" in value or "d" in value:
        # the paper's form: Ψ = c10 (Ī₁ − 3) + d/2 (J − 1)²  →  μ = 2 c10, K = d
        mapping(value, path, required=("model", "c10", "d"))
        mu = 2.0 * number(value["c10"], key_path(path, "c10"), positive=True, hint=" (Pa)")
        K = number(value["d"], key_path(path, "d"), positive=True, hint=" (Pa)")
    else:
        raise ConfigError(path, "neo-hookean (and goh's matrix) needs 'mu' and 'bulk_modulus' (or the paper's "
                                "'c10' and 'd', with mu = 2 c10, bulk_modulus = d)")
    return {"model": NeoHookean.name, "mu": mu, "bulk_modulus": K}


def _goh(value, path: str) -> dict:
    """The fibre part of ``model: goh`` (physics/goh.py): k1, k2, kappa and the fibre field."""
    for key in ("k1", "k2"):
        if value.get(key) is None:
            raise ConfigError(key_path(path, key), "missing value (required): goh needs k1 (fibre stiffness, "
                              "Pa) and k2 (dimensionless) besides the matrix's mu and bulk_modulus "
                              "(or c10 and d)", MISSING_KEY)
    k1 = number(value["k1"], key_path(path, "k1"), nonneg=True,
                hint=" (fibre stiffness in Pa; 0 switches the fibres off)")
    k2 = number(value["k2"], key_path(path, "k2"), positive=True,
                hint=" (dimensionless stiffening exponent; for a nearly linear fibre give a small k2)")
    kappa = number(value.get("kappa", 0.0), key_path(path, "kappa"), lo=0.0, hi=1.0 / 3.0,
                   hint=" (fibre dispersion: 0 aligned, 1/3 isotropic)")
    fp = key_path(path, "fibres")
    f = value.get("fibres", {})
    mapping(f, fp, optional=("follow", "extra_twist_deg", "angle_deg"))
    follow = string(f.get("follow", "twist"), key_path(fp, "follow"), FIBRE_FOLLOW)
    extra = number(f.get("extra_twist_deg", 0.0), key_path(fp, "extra_twist_deg"), lo=-720.0, hi=720.0,
                   hint=" (fibre twist about the beam's axis over the length, degrees)")
    ap = key_path(fp, "angle_deg")
    raw = f.get("angle_deg", 0.0)
    if isinstance(raw, list):
        items = sequence(raw, ap)
        if len(items) > 4:
            raise ConfigError(ap, f"at most 4 fibre families; got {len(items)}")
        angles = tuple(number(a, key_path(ap, i), lo=-90.0, hi=90.0, hint=" (degrees)")
                       for i, a in enumerate(items))
        _distinct_families(angles, ap)
    else:
        angles = (number(raw, ap, lo=-90.0, hi=90.0, hint=" (degrees; a list gives one family each)"),)
    return {"k1": k1, "k2": k2, "kappa": kappa,
            "fibres": {"follow": follow, "extra_twist_deg": extra, "angles_deg": list(angles)}}


def _distinct_families(angles: tuple, path: str) -> None:
    """Each fibre family once ([10, 10], or [90, -90]: one line, was k1 doubled along it, no word)."""
    for i, j in ((i, j) for i in range(len(angles)) for j in range(i) if (angles[i] - angles[j]) % 180.0 == 0.0):
        raise ConfigError(key_path(path, i), f"the same fibre family as angle_deg[{j}] ({angles[j]:g} deg"
                          f"{'; +90 and -90 are one line' if angles[i] != angles[j] else ''}): counted twice (k1 doubled "
                          f"along it); give each once (a pair: [a, -a]); got {shown([float(v) for v in angles])}")


#: how each material of the registry (physics/laws.py ``MATERIALS``) is read from a config
MATERIAL_PARSERS = {NeoHookean.name: _neo_hookean, StVenantKirchhoff.name: _svk, GOH.name: _goh_material}


def _axial_points(value, path: str, nodes: int = 3) -> int:
    """Gauss points along ξ: one point leaves the three-node element's stiffness singular, and
    fewer points than nodes an element with four or more nodes along the beam (measured on a
    four-node 3363: with 2 or 3 points the uniaxial bar and the Achilles column end "unstable")."""
    n = integer(value, path, hi=10)
    if nodes <= 3 and n < 2:
        raise ConfigError(path, f"must be >= 2; got {n}: one point along the beam leaves the "
                                "three-node element's stiffness singular (zero-energy modes); "
                                "use 2 (reduced) or 3 (full, the paper's)")
    if nodes > 3 and n < nodes:
        raise ConfigError(path, f"must be >= {nodes} for an element with {nodes} nodes along the beam; "
                                f"got {n}: fewer points leave its stiffness singular (zero-energy "
                                f"modes); use {nodes}")
    return n


def _element_name(value, path: str) -> str:
    """An element's registry name; an integer (element: 3363) is its name written as a number
    (element: null read "got 'None'", a list "got '[3363]'")."""
    return string(str(value) if isinstance(value, int) and not isinstance(value, bool) else value, path,
                  tuple(ELEMENTS))


def _cubature_degree(value, path: str) -> int:
    """The section rule's degree: 1 does not integrate y², z² (one point on a rectangle, points on
    one line of an ellipse), so bending had no stiffness: the elastica failed or ended unstable."""
    n = integer(value, path, hi=30)
    if n < 2:
        raise ConfigError(path, f"must be >= 2; got {n}: a rule of degree {n} does not integrate y^2, z^2, "
                                "so bending has no (or a wrong) stiffness; use 2 or more (the default: 6 for a section, 4 in a bundle)")
    return n


def check_imported_loops(beams: list, sections) -> None:
    """beams[i].section {shape: outline, loop: <name>} without file/curves names an outline of
    geometry.sections, and geometry.sections is used by a beam (outlines beside a bundle's
    generated beams were ignored with no word)."""
    imported = [(i, b.section) for i, b in enumerate(beams) if b.section.shape == "outline"
                and b.section.file is None and b.section.curves is None]
    if sections is not None and not imported:
        raise ConfigError("geometry.sections", f"no beam uses its outlines ({', '.join(sections.names)}): "
                                               "give a beam section: {shape: outline, loop: <name>}, or "
                                               "remove geometry.sections")
    for i, s in imported:
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
    _check_outline_places(beams)
    _check_shared_curve_offsets(beams)


def _check_shared_curve_offsets(beams: list) -> None:
    """Inline curves named alike in two beams are one curve, their interface: a center on one side
    moved that side only (0.5 mm off its neighbour, the border still listed as shared)."""
    users: dict[str, list[int]] = {}
    for i, b in enumerate(beams):
        if b.section.shape == "outline" and b.section.curves is not None:
            for c in b.section.curves:
                if "name" in c:
                    users.setdefault(c["name"], []).append(i)
    for name, idx in users.items():
        centres = {tuple(float(v) for v in beams[i].section.center) for i in idx}
        if len(centres) > 1:
            i = next(k for k in idx if any(float(v) != 0.0 for v in beams[k].section.center))
            j = next(k for k in idx if k != i)
            raise ConfigError(f"beams[{i}].section.center", f"its curve {name!r} is also the section curve of "
                                                            f"beams[{j}] ({beams[j].name}), one curve, their "
                                                            "interface: a center moves one side only; give the "
                                                            f"points where they are; got {shown(list(beams[i].section.center))}")


def _check_outline_places(beams: list) -> None:
    """A measured outline (geometry.sections, or a sections file shared by several beams) is the
    section of one beam, where its file places it: two beams with the outline 'l' filled one region,
    and a beam's center moved it 1 mm into its neighbour across their shared border, with no word."""
    owner: dict[tuple, int] = {}
    files: dict[str | None, int] = {}
    for b in beams:
        s = b.section
        if s.shape == "outline" and s.curves is None:
            files[s.file] = files.get(s.file, 0) + 1
    for i, b in enumerate(beams):
        s, p = b.section, f"beams[{i}].section"
        if s.shape != "outline" or s.curves is not None:
            continue
        if (s.file, s.loop) in owner:
            j = owner[(s.file, s.loop)]
            raise ConfigError(f"{p}.loop", f"outline {s.loop!r} is already the section of beams[{j}] "
                                           f"({beams[j].name}): two beams would fill one region; give each "
                                           f"beam its own outline; got {s.loop!r}")
        owner[(s.file, s.loop)] = i
        if any(float(c) != 0.0 for c in s.center) and (s.file is None or files[s.file] > 1):
            where = "geometry.sections" if s.file is None else "a sections file with its neighbours"
            raise ConfigError(f"{p}.center", f"an outline of {where} sits where its file places it, against "
                                             "its neighbours (their shared borders are the interfaces): move it "
                                             f"there, not by center (twist axis: geometry.twist_axis); got "
                                             f"{shown(list(s.center))}")
