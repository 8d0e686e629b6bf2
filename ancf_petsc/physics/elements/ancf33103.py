"""ANCF 33103: three axial nodes, ten nodal vectors per node (30 DOFs), the complete cubic
section field (issue 42, item 2).

The name follows the ANCF convention dimension–nodes–vectors–components (3D, 3 nodes, 10
vectors, 3 components), as 3333 (order 1) and 3363 (order 2).  The family — Lagrange along the
beam times a complete Taylor polynomial of order N across the section — is the TE (Taylor
expansion) class of Carrera's unified formulation of higher-order 1D models (Carrera, Giunta &
Petrolo, *Beam Structures: Classical and Advanced Theories*, Wiley 2011; Carrera & Petrolo 2012,
"Refined beam elements with only displacement variables and plate/shell capabilities"): order 1
and 2 there are 3333's and 3363's kinematics, and order 3 adds the cubic in-plane and warping
modes (y³/6, y²z/2, yz²/2, z³/6) that let a nearly incompressible section stay isochoric where
its axial strain varies with ρ² (the untwist of a pretwisted bar, docs/locking.md).

Nodal vectors in DOF order: r, r_y, r_z, r_yy, r_yz, r_zz, r_yyy, r_yyz, r_yzz, r_zzz, each
paired with y^i z^j / (i! j!) (``base.complete_monomials(3)``).  The section rule is raised to
degree 6 (products of two cubic monomials; ``Element.section_degree``).  Locking remedies:
``none`` (the default, measured: the helical-fibre bar's untwist within 0.1 % of the solid where
3363 is 6.6 % short) or ``mixed``; ``ecm`` is refused (its ν = 0 part loads the cubic modes:
uniaxial tension 65 % off; docs/locking.md, "Orders 3 and 4")."""
from .base import Element, NodeBlock, complete_monomials

BLOCK = NodeBlock(monomials=complete_monomials(3))

ELEMENT = Element("33103", BLOCK, section_degree=2 * BLOCK.order, remedies=("none", "mixed"),
                  refused_because="its ν = 0 part loads the section's cubic modes")
