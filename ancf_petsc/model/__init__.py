"""The discretised model: ``beams`` (Beam, Model: elements, nodes, numbering, quadrature data) and
``build`` (a validated ModelSpec → Model: sections, materials, pretwisted reference nodal
coordinates, supports and loads)."""

#: the sub-modules (imported on use: a plain import of the package loads none of them)
__all__ = ["beams", "build", "contact_setup", "fibre_setup", "plausibility"]
