"""ANCF 33153: three axial nodes, fifteen nodal vectors per node (45 DOFs), the complete quartic
section field (issue 42, item 2).

Named in the ANCF convention dimension–nodes–vectors–components (3D, 3 nodes, 15 vectors, 3
components).  Order 4 of the family of 3333 (order 1), 3363 (order 2) and 33103 (order 3): the
TE class of Carrera's unified formulation of higher-order 1D models (Carrera, Giunta & Petrolo,
*Beam Structures: Classical and Advanced Theories*, Wiley 2011), whose refined orders capture
section warping and in-plane distortion of 3D-solid accuracy for compact sections.

Nodal vectors in DOF order: those of 33103, then r_yyyy, r_yyyz, r_yyzz, r_yzzz, r_zzzz, each
paired with y^i z^j / (i! j!) (``base.complete_monomials(4)``).  The section rule is raised to
degree 8 (``Element.section_degree``).  Locking remedies: ``none`` (the default, measured: the
clamped nearly incompressible cantilever within 0.011 % of the 3D solid, the helical-fibre bar's
untwist within 0.14 %) or ``mixed``; ``ecm`` is refused as for 33103 (docs/locking.md, "Orders 3
and 4")."""
from .base import Element, NodeBlock, complete_monomials

BLOCK = NodeBlock(monomials=complete_monomials(4))

ELEMENT = Element("33153", BLOCK, section_degree=2 * BLOCK.order, remedies=("none", "mixed"),
                  refused_because="its ν = 0 part loads the section's cubic and quartic modes")
