"""Contact interfaces: a section curve shared by two beams' outlines, swept along both beams.

Quadrature points live on body A's side of the interface and are projected onto body B's; by
default A is the later of the two beams in config order (whatever is loaded).  Outputs name an
interface "curve (first|second)" in config order, whichever side carries the points.
``find_interfaces`` takes them from explicit pairs in the contact spec or finds every curve two
outlines share.  Errors are ``ContactSetupError``s; the model layer names their config keys.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np



class ContactSetupError(ValueError):
    """Contact cannot be set up as given; ``interface`` is the index of the interface concerned
    (``contact.interfaces[k]``) or None for the contact as a whole."""

    def __init__(self, message: str, interface: int | None = None, key: str | None = None):
        super().__init__(message)
        self.interface, self.key = interface, key        # key: the config key to name, if not contact's


@dataclass
class Interface:
    name: str
    a: object              # Beam carrying the quadrature points
    b: object              # Beam they are projected onto
    curve: object          # the SplineCurve on A carrying the points (shared interfaces: also B's)
    flip_b: bool           # B traverses curve_b backwards in its CCW loop (normal sign)
    curve_b: object = None  # the SplineCurve on B (defaults to the shared curve)
    n_points: int = field(default=0)

    def __post_init__(self):
        if self.curve_b is None:
            self.curve_b = self.curve

    @property
    def first(self):
        """The earlier of the two beams in config order (outputs are "first|second")."""
        return self.a if self.a.index < self.b.index else self.b

    @property
    def second(self):
        """The later of the two beams in config order."""
        return self.b if self.a.index < self.b.index else self.a

    @property
    def sides(self) -> str:
        """"curve (A|B)": the curve and the beam carrying the points first, what the
        discretisation depends on (a restart's fingerprint)."""
        return f"{self.curve.name} ({self.a.name}|{self.b.name})"

    @property
    def sign(self) -> float:
        """+1 where A (the beam carrying the points) is the first beam in config order, −1 where
        it is the second: turns A − B into the outputs' first − second."""
        return 1.0 if self.a.index < self.b.index else -1.0


def _shared(a, b) -> list:
    """(curve, B's flip) of every curve object both outlines use."""
    la, lb = a.section.loop or [], b.section.loop or []
    return [(ca, fb) for ca, _ in la for cb, fb in lb if ca is cb]


def _explicit_pairs(model, spec) -> list:
    pairs = []
    for k, (ia, ib, cname, cname_b) in enumerate(spec.interfaces):
        a, b = model.beams[ia], model.beams[ib]
        if cname_b is not None:            # two curves: one on each body (non-matching)
            ca = [c for c, _ in (a.section.loop or []) if c.name == cname]
            cb = [(c, f) for c, f in (b.section.loop or []) if c.name == cname_b]
            for found, beam, name, key in ((ca, a, cname, "curve"), (cb, b, cname_b, "curve_b")):
                if not found:
                    names = ", ".join(c.name for c, _ in (beam.section.loop or [])) or "none"
                    raise ContactSetupError(f"no curve {name!r} in {beam.name}'s outline (its curves: "
                                            f"{names}); got {name!r}", k, f"contact.interfaces[{k}].{key}")
            pairs.append((a, b, ca[0], cb[0][1], cb[0][0], k))
            continue
        found = [(c, f) for c, f in _shared(a, b) if cname is None or c.name == cname]
        if not found:
            shared = ", ".join(c.name for c, _ in _shared(a, b)) or "none"
            raise ContactSetupError(f"beams {a.name} and {b.name} share no outline curve"
                                    + (f" named {cname!r} (they share: {shared})" if cname else "")
                                    + "; interfaces are curves used by both section outlines"
                                    + (f"; got {cname!r}" if cname else ""), k,
                                    f"contact.interfaces[{k}].curve" if cname else None)
        pairs += [(a, b, c, f, None, k) for c, f in found]
    return pairs


def _automatic_pairs(model) -> list:
    # the sides do not depend on the loads (issue 39): of two beams sharing a curve the later
    # in config order carries the points (A), the earlier is the target (B); an explicit
    # contact.interfaces list chooses otherwise
    pairs = []
    for i, first in enumerate(model.beams):
        for second in model.beams[i + 1:]:
            pairs += [(second, first, c, f, None, None) for c, f in _shared(second, first)]
    if not pairs:
        raise ContactSetupError("no two beam outlines share a curve; give the neighbours a "
                                    "common named curve or remove contact")
    return pairs


def unlisted_warnings(beams, spec) -> list[str]:
    """One warning line if an explicit ``contact.interfaces`` list (``spec``: the ContactSpec or
    None) leaves out curves two of ``beams`` share: those carry no contact, and the beams pass
    through each other there (the paper's tendon with only mg_sol listed, to choose its side:
    the soleus 0.97 % longer at 400 N, the lateral gastrocnemius left unloaded, with no word)."""
    if spec is None or not spec.interfaces:
        return []
    listed = {}
    for a, b, curve, curve_b in spec.interfaces:
        names = listed.setdefault(frozenset((a, b)), set())
        names.update({None} if curve is None else {curve, curve_b})
    missing = []
    for i, first in enumerate(beams):
        for second in beams[i + 1:]:
            given = listed.get(frozenset((first.index, second.index)), set())
            missing += [f"{c.name} ({first.name}|{second.name})" for c, _ in _shared(second, first)
                        if None not in given and c.name not in given]
    if not missing:
        return []
    return [f"warning: contact.interfaces: the shared curve(s) {', '.join(missing)} are not listed, so "
            "they carry no contact and their beams pass through each other there; list them too "
            "(each entry chooses its side), or give interfaces: auto"]


def find_interfaces(model, spec) -> list[Interface]:
    """Interfaces from the contact spec (explicit pairs) or every curve shared by two outlines."""
    pairs = _explicit_pairs(model, spec) if spec.interfaces else _automatic_pairs(model)
    out, entry = [], {}
    for a, b, c, fb, cb, k in pairs:
        if a.n_elements != b.n_elements:
            more = max(a.n_elements, b.n_elements)
            raise ContactSetupError(
                f"{a.n_elements} element(s) against {b.n_elements} of {b.name} (beams[{b.index}]."
                f"elements), its contact partner across curve {c.name}: the beams of an interface need "
                f"the same number of elements (a conforming interface); give both {more}",
                key=f"beams[{a.index}].elements")
        first, second = (a, b) if a.index < b.index else (b, a)
        # named by the first beam's curve, whichever carries the points (two curves: curve_b)
        name = f"{(c if a is first or cb is None else cb).name} ({first.name}|{second.name})"
        if name in entry and k is not None:
            _listed_twice(name, entry[name], k, a, b, c, cb)
        entry[name] = k
        out.append(Interface(name, a, b, c, fb, cb))
    return out


def _listed_twice(name: str, before: int, k: int, a, b, curve, curve_b=None) -> None:
    """Refuse an interface listed twice in ``contact.interfaces`` (entries ``before`` and ``k``,
    in either order of a and b): its constraints would repeat (sliding: multipliers not unique,
    the tendon at 2 elements failed at 312 of 400 N with points on both sides) and its outputs,
    keyed by name, would keep one copy's arbitrary share of the force."""
    raise ContactSetupError(
        f"interface {name} is listed twice (also contact.interfaces[{before}]): list each shared curve of two beams "
        f"once, in either order of a and b; got {{a: {a.name}, b: {b.name}, curve: {curve.name}"
        + ("" if curve_b is None else f", curve_b: {curve_b.name}") + "}", k)


def supported_ends(model, interfaces, rule: str = "merge", held_slots: int | None = None) -> np.ndarray:
    """(n_interfaces, 2) bool, all False for ``rule`` keep (``contact.projection.supported_ends``);
    for merge True where the interface's first / last end lies at nodes of A and
    B whose every DOF is held or prescribed (``fix: clamped``): the gap there is the supports',
    and a pressure function of its own would repeat them (multipliers.py).  Not where a section
    may stretch (``fix: reduced``): that end's constraint still holds the two bodies' different
    contraction (docs/contact.md, "Supported ends": folding it there moves Table 1 by 1.7 %).
    ``held_slots`` 3: where the nodes' positions r are held (``fix: reduced`` too; the tangential
    functions' rule, ``contact.tangential.supported_ends``); default every DOF of a node."""
    D = model.dofs_per_node
    held = np.zeros(D * model.n_nodes, dtype=bool)
    held[model.fixed_dofs] = True
    node_held = held.reshape(-1, D)[:, :D if held_slots is None else held_slots].all(axis=1)
    out = np.zeros((len(interfaces), 2), dtype=bool)
    for k, itf in enumerate(interfaces if rule == "merge" else ()):
        for j, end in enumerate((0, -1)):
            a, b = itf.a, itf.b
            na, nb = a.node_offset + np.arange(a.n_nodes)[end], b.node_offset + np.arange(b.n_nodes)[end]
            out[k, j] = (node_held[na] and node_held[nb]
                         and np.isclose(a.x_nodes[end], b.x_nodes[end], rtol=0, atol=1e-12))
    return out


def held_ends(model, interfaces, tangential) -> np.ndarray:
    """(n_interfaces, 2) bool: the ends whose tangential functions are folded
    (``contact.tangential.supported_ends: merge``, ``tangential`` its spec or None): where the
    positions r of both bodies' end nodes are held (``fix: clamped`` or ``reduced``)."""
    return supported_ends(model, interfaces, getattr(tangential, "supported_ends", "keep"), 3)
