"""``contact:`` of a config: the law, the interfaces and the pressure space (docs/contact.md)."""
from __future__ import annotations

from ..physics.element3363 import DOFS_PER_NODE
from .conditions import beam_ref
from .specs import CONTACT_MODES, DEFAULT_CONTACT_MODE, REMOVED_CONTACT_KEYS, ContactSpec
from .values import ConfigError, boolean, integer, mapping, number, sequence, string


def parse_contact(value, names: list[str]) -> ContactSpec:
    """The contact law (sliding | unilateral), Gauss points, pressure space and interfaces."""
    p = "contact"
    if isinstance(value, dict):
        for key in REMOVED_CONTACT_KEYS:
            if key in value:
                raise ConfigError(f"{p}.{key}", "contact is enforced exactly by Lagrange multipliers "
                                                "(no penalty, nothing to tune); remove this key")
    mapping(value, p, optional=("mode", "interfaces", "axial_points", "curve_points", "search_margin",
                                "projection", "scaling"))
    c = ContactSpec()
    c.mode = string(value.get("mode", DEFAULT_CONTACT_MODE), f"{p}.mode", CONTACT_MODES)
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
    if (c.projection[0] + 1) * (c.projection[1] + 1) > DOFS_PER_NODE:
        raise ConfigError(f"{p}.projection", "(axial + 1) x (curve + 1) pressure functions per element "
                                             "must not exceed 18 (one node block)")
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
