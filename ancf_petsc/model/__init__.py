"""The discretised model: ``beams`` (Beam, Model: elements, nodes, numbering, quadrature data) and
``build`` (a validated ModelSpec → Model: sections, materials, pretwisted reference nodal
coordinates, supports and loads)."""
