"""``contact`` of a spec edited after parsing (the Python API), read again as the config's.

Only the pressure space's bound across was checked again: an edited ``mode: 'bonded'`` raised a
KeyError, ``axial_points: 1``, ``search_margin: -1``, ``fade: 'foo'`` or a Coulomb ``friction:
-1`` ran (their config refuses each), and a tangential law given as a dict raised an
AttributeError.  The edited contact is written out as a config's ``contact:`` and parsed again.
"""
from __future__ import annotations

from .contact import TANGENTIAL_PARSERS, parse_contact
from .specs import ContactSpec, TangentialSpec
from .values import ConfigError

#: ContactSpec fields that are not config keys (set in code), kept through the edit
_CODE_FIELDS = ("group",)
_PROJECTION = ("axial", "curve", "curve_spans", "per_element", "supported_ends")


def check_edited_contact(spec) -> dict | None:
    """Replace ``spec.contact`` (a ContactSpec, a config's ``contact:`` mapping, or None) by
    itself parsed as a config's; keys the config left out and the edit did not change are left
    out again, so that their defaults follow the edited model (a tangential law added, elements
    of another degree).  Returns the contact as written (None: no contact).  Raises ConfigError
    naming the key, as the config would."""
    from ..physics.elements import ELEMENTS
    c = spec.contact
    if c is None:
        return None
    if not isinstance(c, (ContactSpec, dict)):
        raise ConfigError("contact", "expected a ContactSpec (or a config's contact: mapping), or None "
                                     f"for no contact; got {type(c).__name__}")
    blocks = [ELEMENTS[b.element].block for b in spec.beams]
    names = [b.name for b in spec.beams]
    args = (names, blocks[0].dofs_per_node, min(ELEMENTS[b.element].order for b in spec.beams),
            min(blk.axial_nodes for blk in blocks) - 1)
    if isinstance(c, dict):
        spec.contact = parse_contact(c, *args)
        return c
    given = spec.raw.get("contact") if isinstance(spec.raw, dict) else None
    given = given if isinstance(given, dict) else {}
    written = contact_as_written(c, names)
    try:
        defaults = contact_as_written(parse_contact(given, *args), names)
    except ConfigError:
        defaults = {}               # the config's own contact no longer fits: every value as edited
    _drop_defaults(written, defaults, given)
    edited = parse_contact(written, *args)
    for key in _CODE_FIELDS:
        setattr(edited, key, getattr(c, key))
    if isinstance(c.tangential, TangentialSpec) and edited.tangential is not None:
        edited.tangential.free_zone = c.tangential.free_zone
    spec.contact = edited
    return written


def contact_as_written(c: ContactSpec, names: list[str]) -> dict:
    """A ContactSpec as a config's ``contact:`` (beams by name; a tangential law given as a
    mapping is kept as given)."""
    out = {"mode": c.mode, "axial_points": c.axial_points, "curve_points": c.curve_points,
           "search_margin": c.search_margin, "scaling": c.scaling, "fade": c.fade,
           "fade_forces": c.fade_forces,
           "projection": dict(zip(_PROJECTION, (*_pair(c.projection), c.curve_spans, c.per_element,
                                                c.supported_ends)))}
    t = c.tangential
    if isinstance(t, TangentialSpec):
        own = TANGENTIAL_PARSERS.get(t.law, ((), None))[0]
        out["tangential"] = {"law": t.law} | {k: getattr(t, k) for k in own
                                              if getattr(t, k, None) is not None}
    elif t is not None:
        out["tangential"] = t
    if c.interfaces:
        out["interfaces"] = [_interface_as_written(it, names) for it in c.interfaces]
    return out


def _pair(projection) -> tuple:
    """(axial, curve) of an edited ``projection`` (two values; anything else is left for the
    config's reader to refuse)."""
    return tuple(projection) if isinstance(projection, (tuple, list)) and len(projection) == 2 \
        else (projection, None)


def _interface_as_written(it, names: list[str]):
    """One interface (a, b, curve, curve_b) as a config's mapping, beam indices by name."""
    if not isinstance(it, (tuple, list)) or not 2 <= len(it) <= 4:
        return it                                 # the reader says what is wrong with it
    out = {k: names[v] if isinstance(v, int) and 0 <= v < len(names) else v for k, v in zip("ab", it)}
    return out | {k: v for k, v in zip(("curve", "curve_b"), it[2:]) if v is not None}


def _drop_defaults(written: dict, defaults: dict, given: dict) -> None:
    """Leave out of ``written`` what the config left out and the edit did not change."""
    for key in list(written):
        if key == "projection":
            sub, base = written[key], defaults.get(key, {})
            own = given.get(key) if isinstance(given.get(key), dict) else {}
            for k in list(sub):
                if k not in own and k in base and sub[k] == base[k]:
                    del sub[k]
            if not sub:
                del written[key]
        elif key not in given and key in defaults and written[key] == defaults[key]:
            del written[key]
