"""ANCF continuum beam elements 3363 (paper §2.1, eqs. 1–8) and 3333.

Three nodes at ξ = −1, 0, +1; each node carries six nodal vectors (18 DOFs).  The shape
functions N1..N18 of eq. (6) factor as ``L_i(ξ) · m_k(y, z)`` with the quadratic Lagrange
polynomials ``L_i`` and the section monomials ``m_k``, once η = 2y/l_y and ζ = 2z/l_z are
substituted (e.g. N5 = l_y²/16 ξη²(ξ−1) = L_1(ξ) · y²/2).

The pairing of nodal vectors with monomials — stated here once and used everywhere:

=====  ========  =========  ==========================================
slot   vector    monomial   paper's function at node 1 (2, 3: +6, +12)
=====  ========  =========  ==========================================
0      r         1          N1
1      r_y       y          N2
2      r_z       z          N3
3      r_yy      y²/2       N5
4      r_zz      z²/2       N6
5      r_yz      yz         N4
=====  ========  =========  ==========================================

Eq. (3) orders the nodal vectors r, r_y, r_z, r_yy, r_zz, r_yz (kept as the DOF order), while
the paper's N4..N6 multiply yz, y²/2, z²/2: the table above is that permutation.

Within an element a shape-function *slot* is ``6 * node + vector`` (node 0..2), and the DOF of
component ``c`` (x, y, z) of slot ``s`` is ``3 * s + c``; this is also the order of a node's
18-DOF block in the global vectors.

The layout itself is data (``physics/elements``: the nodal vectors as monomials y^i z^j, the DOFs
per node, the axial nodes and their shape functions, one module per element); this module keeps
the paper's element for verification (eq. 6 literally, the paper's numbering) and the functions
of 3363's block under their old names.  The model reads its own block (``Model.block``), never
the constants below, which are 3363's.

Element 3333 (Nachbagauer et al. 2013, Ebel et al. 2017): ``physics/elements/ancf3333.py``.
"""
from __future__ import annotations

import numpy as np

from .elements import DEFAULT_ELEMENT, ELEMENTS, Element, element_names, quadratic_lagrange
from .elements.ancf3363 import BLOCK

NODES_PER_ELEMENT = BLOCK.axial_nodes
VECTORS = BLOCK.names
#: the SI unit of each nodal vector (a position, section directions, their derivatives)
VECTOR_UNITS = BLOCK.units()
VECTORS_PER_NODE = BLOCK.vectors_per_node
DOFS_PER_NODE = BLOCK.dofs_per_node           # 18
SLOTS = BLOCK.slots                           # 18 shape functions per element
DOFS_PER_ELEMENT = BLOCK.dofs_per_element     # 54
VECTOR_INDEX = {name: k for k, name in enumerate(VECTORS)}
#: index of the paper's N-function (1-based, node 1) carried by each slot of a node
PAPER_FUNCTION = (1, 2, 3, 5, 6, 4)

#: the element registry (``physics/elements``), re-exported: every reader of element names reads it
ElementType = Element
#: nodal vectors (slots of a node) each element type interpolates with
ELEMENT_VECTORS = {name: e.vectors for name, e in ELEMENTS.items()}
ELEMENT_TYPES = element_names()
lagrange = quadratic_lagrange


def section_monomials(y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Section monomials m_k(y, z) of 3363's block in slot order and their y- and z-derivatives, (n, 6) each."""
    return ELEMENTS[DEFAULT_ELEMENT].section_monomials(y, z)


def shape_functions(xi: np.ndarray, y: np.ndarray, z: np.ndarray,
                    vectors: tuple[int, ...] = ELEMENT_VECTORS[DEFAULT_ELEMENT]) -> tuple[np.ndarray, np.ndarray]:
    """Shape functions N (n, S) and their derivatives dN (n, S, 3) w.r.t. (ξ, y, z) (eq. 6).

    Points are given pointwise (xi, y, z of equal length n).  ``vectors`` selects the nodal
    vectors of 3363's block (default all six: 3363, S = 18; ``ELEMENT_VECTORS["3333"]``: S = 9);
    slot order is node-major, ``len(vectors) * node + k``.  ``Element.shape_functions`` is the
    same for any element.
    """
    return Element("", BLOCK, tuple(vectors)).shape_functions(xi, y, z)


def tensor_points(xi: np.ndarray, yz: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All (ξ, y, z) combinations of axial points ``xi`` (na,) and section points ``yz`` (ns, 2).

    Ordered axial-major: point ``ia * ns + is``.
    """
    na, ns = len(xi), len(yz)
    return np.repeat(xi, ns), np.tile(yz[:, 0], na), np.tile(yz[:, 1], na)


def paper_shape_functions(xi, eta, zeta, ly: float, lz: float) -> np.ndarray:
    """The paper's N1..N18 of eq. (6) literally, (n, 18) in the paper's order (for verification)."""
    xi, eta, zeta = (np.asarray(a, dtype=float) for a in (xi, eta, zeta))
    cols = []
    for lag in (0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)):
        cols += [lag,
                 lag * 0.5 * ly * eta,
                 lag * 0.5 * lz * zeta,
                 lag * 0.25 * ly * lz * eta * zeta,
                 lag * 0.125 * ly * ly * eta * eta,
                 lag * 0.125 * lz * lz * zeta * zeta]
    return np.stack(cols, axis=-1)


def slot_of_paper_function(k: int) -> int:
    """Slot (0..17) carrying the paper's N_k (1-based)."""
    node, local = divmod(k - 1, 6)
    return 6 * node + PAPER_FUNCTION.index(local + 1)


def reference_gradients(q0e: np.ndarray, dN: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Material gradients ∇₀N_a = J0⁻ᵀ ∂N_a/∂(ξ,y,z) and det J0 at the points of each element.

    ``q0e`` (E, S, 3) reference nodal vectors per slot, ``dN`` (P, S, 3) derivatives at P points
    (or (E, P, S, 3): points of each element's own, e.g. sections varying along the beam).
    Returns G (E, P, S, 3) with F = Σ_a q_a ⊗ G_a (eq. 7), and detJ0 (E, P).
    """
    per_element = dN.ndim == 4
    J0 = np.einsum("eai,epaj->epij" if per_element else "eai,paj->epij", q0e, dN)
    det = np.linalg.det(J0)                   # columns of J0: ∂X/∂ξ, ∂X/∂y, ∂X/∂z
    if np.any(det <= 0.0):
        raise ValueError("reference element is inverted or degenerate (det ∂X/∂(ξ,y,z) <= 0)")
    G = np.matmul(dN if per_element else dN[None, :, :, :], np.linalg.inv(J0))
    return G, det
