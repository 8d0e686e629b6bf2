"""The element registry: one module per element, each binding ``ELEMENT`` (an :class:`Element`:
its name, its node block — the nodal vectors as section monomials y^i z^j, the axial nodes and
their shape functions — the vectors it interpolates with and its default locking remedy).  The
package finds them itself, so adding an element is one new module here (and its test); config
validation, the model, supports, probes, contact, output and restart read the layout from it.

The node block is a model's: every beam of one model uses elements of one block (3333 and 3363
share 3363's).  ``register`` adds an element at run time (tests)."""
from __future__ import annotations

from ...registry import discover
from .base import Element, NodeBlock, complete_monomials, quadratic_lagrange, vector_name

__all__ = ["DEFAULT_ELEMENT", "ELEMENTS", "Element", "NodeBlock", "complete_monomials", "element",
           "element_names", "quadratic_lagrange", "register", "richer", "vector_name"]


DEFAULT_ELEMENT = "3363"


def _discover() -> dict[str, Element]:
    """name → element of every module of this package that binds ``ELEMENT``, the default first."""
    found = {name: e for name, (_, e) in discover(__path__, __name__, "ELEMENT", "elements").items()}
    return dict(sorted(found.items(), key=lambda kv: (kv[0] != DEFAULT_ELEMENT, kv[0])))


#: every element, by registry name (config ``beams[i].element``); the default (3363) first
ELEMENTS = _discover()


def element_names() -> tuple[str, ...]:
    """The registered names now (``register`` may have added some)."""
    return tuple(ELEMENTS)


def element(name: str) -> Element:
    """The element registered as ``name`` (KeyError naming the registered ones)."""
    try:
        return ELEMENTS[name]
    except KeyError:
        raise KeyError(f"unknown element {name!r}; registered: {', '.join(ELEMENTS)}") from None


def richer(names) -> Element | None:
    """The next rung of the section ladder above the elements ``names``: of the registered
    elements with their axial nodes and a section field of higher degree than the richest of
    them, one of the lowest such degree (ties: the complete field, then the name); None at the
    top of the ladder."""
    have = [element(n) for n in names]
    top, nodes = max(e.order for e in have), have[0].block.axial_nodes
    up = [e for e in ELEMENTS.values() if e.order > top and e.block.axial_nodes == nodes]
    return min(up, key=lambda e: (e.order, len(e.held), e.name)) if up else None


def register(e: Element) -> Element:
    """Add an element to the registry (tests; a module in this package is the permanent way)."""
    if e.name in ELEMENTS and ELEMENTS[e.name] != e:
        raise ValueError(f"element {e.name!r} is already registered")
    ELEMENTS[e.name] = e
    return e
