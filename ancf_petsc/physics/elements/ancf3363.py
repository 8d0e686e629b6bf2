"""ANCF 3363 (paper §2.1, eqs. 1–8): three nodes, six nodal vectors per node (18 DOFs), the
quadratic section field.

Eq. (3) orders the nodal vectors r, r_y, r_z, r_yy, r_zz, r_yz (the DOF order), while the paper's
N4..N6 multiply yz, y²/2, z²/2: each vector here carries its own monomial (r_yy ↔ y²/2,
r_zz ↔ z²/2, r_yz ↔ yz), see ``element3363.PAPER_FUNCTION`` for the paper's numbering."""
from .base import Element, NodeBlock

#: the quadratic section field in eq. (3)'s order
BLOCK = NodeBlock(monomials=((0, 0), (1, 0), (0, 1), (2, 0), (0, 2), (1, 1)))

ELEMENT = Element("3363", BLOCK)
