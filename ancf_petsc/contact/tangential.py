"""The tangential (shear) laws of an interface, by their config name (``contact.tangential.law``),
on top of either normal law: each is a contact term (partners.py) that owns its forces, Jacobian
blocks, couplings, history and reported fields.  "none" is frictionless (no term)."""
from __future__ import annotations

from .elastic_interface import ElasticMatrix
from .friction import CoulombFriction
from .partners import reference_scale

TANGENTIAL_LAWS = {"none": None, ElasticMatrix.law: ElasticMatrix, CoulombFriction.law: CoulombFriction}


def make_terms(model, spec, interfaces, points, projector, scaling: float = 1.0) -> list:
    """The contact terms of ``contact.tangential`` (``spec``; None or law "none": no term);
    ``scaling``: ``contact.scaling``, the factor of the multipliers' k_s."""
    cls = TANGENTIAL_LAWS[spec.law] if spec is not None else None
    if cls is None:
        return []
    return [cls.from_spec(spec, model, points, projector, reference_scale(interfaces), scaling)]
