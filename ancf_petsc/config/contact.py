"""``contact:`` of a config: the law, the interfaces and the pressure space (docs/contact.md)."""
from __future__ import annotations

from ..contact.friction import CoulombFriction
from ..contact.elastic_interface import ElasticMatrix
from ..contact.laws import LAWS
from ..contact.tangential import TANGENTIAL_LAWS
from .conditions import beam_ref
from .specs import (CONTACT_MODES, DEFAULT_CONTACT_MODE, FADE_FORCES, FADE_RULES, REMOVED_CONTACT_KEYS,
                    SUPPORTED_END_RULES, TANGENTIAL_LAW_NAMES, ContactSpec, TangentialSpec)
from .values import ConfigError, boolean, integer, mapping, number, sequence, string


def _elastic(value: dict, p: str, t: TangentialSpec) -> None:
    """k_t [Pa/m] as ``stiffness``, or as ``shear_modulus`` / ``thickness`` of the matrix layer."""
    if "stiffness" in value and ("shear_modulus" in value or "thickness" in value):
        raise ConfigError(p, "give the matrix as stiffness (k_t = G / thickness, Pa/m) or as "
                             "shear_modulus and thickness, not both")
    if "stiffness" in value:
        t.stiffness = number(value["stiffness"], f"{p}.stiffness", positive=True,
                             hint=" (k_t = G / thickness of the interface matrix, Pa/m)")
        return
    if "shear_modulus" not in value and "thickness" not in value:
        raise ConfigError(f"{p}.stiffness", "missing value (required): give stiffness (Pa/m), or "
                                            "shear_modulus (Pa) and thickness (m) of the matrix layer")
    for key, given, what in (("thickness", "shear_modulus", "thickness (m)"),
                             ("shear_modulus", "thickness", "shear modulus (Pa)")):
        if key not in value:
            raise ConfigError(f"{p}.{key}", f"missing value (required with {given}): the matrix layer's "
                                            f"{what}, k_t = shear_modulus / thickness; or give stiffness alone")
    G = number(value["shear_modulus"], f"{p}.shear_modulus", positive=True, hint=" (Pa)")
    h = number(value["thickness"], f"{p}.thickness", positive=True, hi=1e-2,
               hint=" (m; interfascicular matrix layers are ~1e-5 m)")
    t.stiffness = G / h


def _coulomb(value: dict, p: str, t: TangentialSpec) -> None:
    """The friction coefficient μ (> 0; law none is μ = 0) and an optional augmentation."""
    if "friction" not in value:
        raise ConfigError(f"{p}.friction", "missing value (required): the friction coefficient mu")
    t.friction = number(value["friction"], f"{p}.friction", positive=True, hi=10.0,
                        hint=" (Coulomb's coefficient mu; frictionless is law: none)")
    if value.get("augmentation") is not None:
        # from 1e-4: c = 1e-9 took 20 698 Newton iterations without a level (0.001 is measured fine)
        t.augmentation = number(value["augmentation"], f"{p}.augmentation", lo=1e-4, hi=1e6,
                                hint=" (the stick test's stiffness in units of k_s / A; default G/E; "
                                     "it steers Newton's iteration; where an increment has several "
                                     "solutions it can pick another: docs/interface.md, Limits)")
    t.supported_ends = string(value.get("supported_ends", t.supported_ends), f"{p}.supported_ends",
                              SUPPORTED_END_RULES)


#: per tangential law: its keys and their reader (the laws are contact/tangential.py TANGENTIAL_LAWS)
TANGENTIAL_PARSERS = {ElasticMatrix.law: (("stiffness", "shear_modulus", "thickness"), _elastic),
                      CoulombFriction.law: (("friction", "augmentation", "supported_ends"), _coulomb)}


def parse_tangential(value, p: str = "contact.tangential") -> TangentialSpec:
    """``contact.tangential``: {law: none | elastic | coulomb, and the law's values}."""
    keys = tuple(k for ks, _ in TANGENTIAL_PARSERS.values() for k in ks)
    mapping(value, p, required=("law",), optional=keys)
    t = TangentialSpec(law=string(value["law"], f"{p}.law", TANGENTIAL_LAW_NAMES))
    own, reader = TANGENTIAL_PARSERS.get(t.law, ((), None))
    for key in value:
        if key != "law" and key not in own:
            raise ConfigError(f"{p}.{key}", f"not a value of law {t.law}; its values: "
                                            + (", ".join(own) if own else "none"))
    if reader is not None:
        reader(value, p, t)
    return t


def parse_contact(value, names: list[str], node_dofs: int = 18, section_order: int = 2, axial_order: int = 2) -> ContactSpec:
    """The contact law (sliding | unilateral), Gauss points, pressure space and interfaces;
    ``node_dofs``: the slots of a multiplier node (the beams' node block, physics/elements);
    ``section_order``, ``axial_order``: the beams' lowest degrees across and along (3363: 2, 2)."""
    p = "contact"
    if isinstance(value, dict):
        for key in REMOVED_CONTACT_KEYS:
            if key in value:
                raise ConfigError(f"{p}.{key}", "contact is enforced exactly by Lagrange multipliers "
                                                "(no penalty, nothing to tune); remove this key")
    mapping(value, p, optional=("mode", "interfaces", "axial_points", "curve_points", "search_margin",
                                "projection", "scaling", "tangential", "fade", "fade_forces"))
    c = ContactSpec()
    c.mode = string(value.get("mode", DEFAULT_CONTACT_MODE), f"{p}.mode", CONTACT_MODES)
    c.axial_points = integer(value.get("axial_points", 3), f"{p}.axial_points", hi=10)
    if c.axial_points < 2:
        # one point holds the gap only at each element's middle: the pressed strips at 2 elements
        # sank 0.48 mm (48 % of the slider's thickness) at 80 % of the load and found no state
        # further, at 4 elements 8.2 x the converged sink (11.9 um), each reading no penetration
        raise ConfigError(f"{p}.axial_points", "must be >= 2: one contact point along each element "
                          "holds the gap only at its middle, and the beams interpenetrate unseen "
                          f"between (give 2 or more; the default is 3); got {c.axial_points}")
    c.curve_points = integer(value.get("curve_points", 2), f"{p}.curve_points", lo=1, hi=10)
    c.search_margin = number(value.get("search_margin", 0.1), f"{p}.search_margin", positive=True, hi=1.0)
    c.scaling = number(value.get("scaling", 1.0), f"{p}.scaling", positive=True,
                       hint=" (a factor on the multipliers' unit k_s; it does not change the answer)")
    if value.get("tangential") is not None:
        c.tangential = parse_tangential(value["tangential"])
    # the normal constraints differentiate the weights, and so do the tangential laws that say so
    # (Coulomb friction, friction_blocks.py; the elastic matrix's weights settle between solves)
    law = TANGENTIAL_LAWS[c.tangential.law] if c.tangential is not None else None
    undifferentiated = law is not None and not getattr(law, "differentiates_weights", False)
    c.fade = string(value.get("fade", "settle" if undifferentiated else "newton"), f"{p}.fade", FADE_RULES)
    if c.fade == "newton" and undifferentiated:
        raise ConfigError(f"{p}.fade", "newton differentiates the fade weights of the normal "
                                       "constraints and Coulomb friction, not the "
                                       f"{c.tangential.law} law's; use settle with it")
    c.fade_forces = string(value.get("fade_forces", "auto"), f"{p}.fade_forces", FADE_FORCES)
    if law is not None and c.fade_forces == "auto":
        c.fade_forces = "pointwise"
    if law is not None and c.fade_forces == "variational":
        raise ConfigError(f"{p}.fade_forces", "a tangential law's forces are pointwise (τ_p ∇g_p); "
                                              "remove fade_forces or set it to pointwise")
    _parse_projection(c, value.get("projection"), f"{p}.projection", node_dofs, section_order, axial_order)
    inter = value.get("interfaces", "auto")
    if inter == "auto":
        c.interfaces = []
    else:
        for i, it in enumerate(sequence(inter, f"{p}.interfaces")):
            ip = f"{p}.interfaces[{i}]"
            mapping(it, ip, required=("a", "b"), optional=("curve", "curve_b"))
            a = beam_ref(it["a"], f"{ip}.a", names)
            b = beam_ref(it["b"], f"{ip}.b", names)
            if a == b:
                raise ConfigError(ip, "a beam cannot be in contact with itself here; name two beams")
            if "curve_b" in it and "curve" not in it:
                raise ConfigError(ip, "curve_b (the curve on b) needs curve (the curve on a)")
            c.interfaces.append((a, b, string(it["curve"], f"{ip}.curve") if "curve" in it else None,
                                 string(it["curve_b"], f"{ip}.curve_b") if "curve_b" in it else None))
    return c


def default_axial(c, axial_order: int = 2) -> int:
    """``contact.projection.axial`` when the config gives none: the contact points' degree along
    the beam (axial_points - 1, quadratic by default) up to the elements' own ``axial_order`` (the
    trace of their displacements; cubic along 3363, axial_points: 4's default until 2026-12-07, is
    not stable: docs/solid_contact.md), but at most linear under Coulomb friction.
    Friction's bounds μ p⁺ read the pointwise pressure, and the quadratic one oscillates along the
    beam (41 % of the pressing force cancelled within elements on the walking stride): its
    strides' strains then differ by 1-2 % and their end differences by 2-6 % from mesh to mesh
    (2, 4, 8, 16 elements), not falling; with a linear pressure by 0.1-0.2 % and 0.3-0.6 % from 8
    to 16 (docs/gait.md, "How many elements a stride needs").  Frictionless answers converge
    with either, faster with the quadratic one."""
    if bounded(c):
        return min(1, c.axial_points - 1)
    return min(c.axial_points - 1, axial_order)


def bounded(c) -> bool:
    """Whether the tangential law of ``c`` (a ContactSpec) bounds its forces by the pointwise
    pressure: Coulomb's μ p⁺ (contact/friction.py)."""
    law = TANGENTIAL_LAWS[c.tangential.law] if c.tangential is not None else None
    return bool(getattr(law, "bounded", False))


def _parse_projection(c, proj, pp: str, node_dofs: int, section_order: int = 2, axial_order: int = 2) -> None:
    """``contact.projection`` (at key path ``pp``) into ``c`` (a ContactSpec): the pressure
    space's degrees along the beam and across, its spans across, continuity and supported-end
    rule (``section_order``: the beams' lowest section degree, ``_bounded_across``; ``axial_order``
    their degree along, ``default_axial``)."""
    if proj == "pointwise":
        raise ConfigError(pp, "a multiplier per point over-constrains the quadratic "
                              "section fields; give {axial: .., curve: ..} degrees")
    axial = default_axial(c, axial_order)
    if proj is None:
        c.projection = (axial, 1)
    else:
        mapping(proj, pp, optional=("axial", "curve", "curve_spans", "per_element", "supported_ends"))
        c.projection = (integer(proj.get("axial", axial), f"{pp}.axial", lo=0),
                        integer(proj.get("curve", 1), f"{pp}.curve", lo=0, hi=8))
        if c.projection[0] > c.axial_points - 1:
            raise ConfigError(f"{pp}.axial", f"must be <= contact.axial_points - 1 = {c.axial_points - 1} "
                              "(the contact points along the beam determine no higher degree): give "
                              f"contact.axial_points: {c.projection[0] + 1} or a lower axial; "
                              f"got {c.projection[0]}")
        c.per_element = boolean(proj.get("per_element", False), f"{pp}.per_element")
        c.curve_spans = integer(proj.get("curve_spans", 1), f"{pp}.curve_spans", lo=1, hi=16)
        c.supported_ends = string(proj.get("supported_ends", c.supported_ends), f"{pp}.supported_ends",
                                  SUPPORTED_END_RULES)
    if c.per_element and c.projection[0] >= 2 and bounded(c):
        raise ConfigError(f"{pp}.per_element", "a pressure discontinuous between elements of degree "
                          f"{c.projection[0]} along the beam has arbitrary multipliers (its constraints "
                          "repeat the elements' continuity: docs/contact.md), and Coulomb's bounds "
                          "mu p+ read them (the pressed strips at 2 elements carried 28.8 x mu N, the "
                          "paper's tendon failed at its first step); give axial: 1 or 0 with it, or "
                          "leave per_element out; got true")
    if (c.projection[0] + 1) * (c.projection[1] + c.curve_spans) > node_dofs:
        raise ConfigError(pp, "(axial + 1) x (curve + curve_spans) pressure functions per "
                              f"element must not exceed {node_dofs} (one node block)")
    _bounded_across(c, pp, section_order)


def _bounded_across(c, pp: str, order: int) -> None:
    """Under Coulomb friction or the sliding law at most order + 1 pressure functions across
    (curve + curve_spans): the gap between two section fields of degree p has p + 1 modes across
    a straight strip, and more functions are not determined (docs/interface.md, "The gap's degree
    across": on 3363 the paper's tendon's inf-sup constant over the interfaces, columns scaled,
    2e-2 / 3e-3 / 1e-4 / 8e-7 with 2 / 3 / 4 / 5 functions).  Coulomb's bounds mu p+ read the
    multipliers themselves; the sliding law holds every function.  Unilateral runs keep them
    (most functions open: docs/contact.md, "Pointwise penetration")."""
    across = c.projection[1] + c.curve_spans
    held = not LAWS[c.mode].decides_activity          # the sliding law: every function held
    if across <= order + 1 or not (bounded(c) or held):
        return
    key = f"{pp}.curve_spans" if c.curve_spans > 1 else f"{pp}.curve"
    got = c.curve_spans if c.curve_spans > 1 else c.projection[1]
    if not bounded(c):
        raise ConfigError(key, _sliding_across(order, across, got))
    raise ConfigError(key, f"under Coulomb friction at most {order + 1} pressure functions across "
                      f"(curve + curve_spans) on section fields of degree {order}, here {across}: "
                      "more are not determined by the gap (inf-sup), their multipliers oscillate "
                      "and the bounds mu p+ read them (the paper's tendon failed at its first level "
                      "with curve: 3 or curve_spans: 4, and completed 57 % too stiff with "
                      f"curve_spans: 3); give curve + curve_spans <= {order + 1}, or a beam element "
                      f"with richer sections; got {got}")


def _sliding_across(order: int, across: int, got: int) -> str:
    """The refusal of more than order + 1 pressure functions across under the sliding law, with
    what they did to the paper's tendon (ψ = 45°, 4 elements, 10 and 400 N)."""
    return (f"under the sliding law (every pressure function held) at most {order + 1} pressure "
            f"functions across (curve + curve_spans) on section fields of degree {order}, here "
            f"{across}: more are not determined by the gap (inf-sup) and lock the sections (the "
            "paper's tendon: curve: 3 ended 1.3 % stiffer at 400 N with its interfaces pressed and "
            "pulled by up to 5e4 N against 1e3 N, curve_spans: 4 failed at 194 N); give curve + "
            f"curve_spans <= {order + 1}, mode: unilateral (its functions mostly open: "
            "docs/contact.md, \"Pointwise penetration\"), or a beam element with richer sections; "
            f"got {got}")
