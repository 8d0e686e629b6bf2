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

Element 3333 (Nachbagauer et al. 2013, Ebel et al. 2017) keeps the same quadratic axial
interpolation but only the section monomials 1, y, z: its nodes carry r, r_y, r_z (9 DOFs).  In
this code a 3333 beam keeps the 18-DOF node block and holds r_yy, r_zz, r_yz at their reference
value 0, so its kinematics are exactly 3333's while contact, output and the DOF layout stay
one code path; its element kernels run on the 27 active DOFs only (``ELEMENT_VECTORS``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

NODES_PER_ELEMENT = 3
VECTORS = ("r", "r_y", "r_z", "r_yy", "r_zz", "r_yz")
#: the SI unit of each nodal vector (a position, section directions, their derivatives)
VECTOR_UNITS = {"r": "m", "r_y": "1", "r_z": "1", "r_yy": "1/m", "r_zz": "1/m", "r_yz": "1/m"}
VECTORS_PER_NODE = len(VECTORS)
DOFS_PER_NODE = 3 * VECTORS_PER_NODE          # 18
SLOTS = NODES_PER_ELEMENT * VECTORS_PER_NODE  # 18 shape functions per element
DOFS_PER_ELEMENT = 3 * SLOTS                  # 54
VECTOR_INDEX = {name: k for k, name in enumerate(VECTORS)}
#: index of the paper's N-function (1-based, node 1) carried by each slot of a node
PAPER_FUNCTION = (1, 2, 3, 5, 6, 4)


@dataclass(frozen=True)
class ElementType:
    """One element of the three-node family: the nodal vectors (slots of a node) it interpolates
    with and the volumetric-locking remedy a beam of it gets unless the config says otherwise
    (``none`` | ``ecm`` | ``mixed``, config ``beams[i].locking``; model.Beam.parts)."""
    name: str
    vectors: tuple[int, ...]
    default_locking: str = "none"


#: the element registry: every reader of element names (config, workflows, charts) reads it
ELEMENTS = {e.name: e for e in (ElementType("3363", (0, 1, 2, 3, 4, 5)),
                                ElementType("3333", (0, 1, 2), default_locking="ecm"))}
DEFAULT_ELEMENT = "3363"
#: nodal vectors (slots of a node) each element type interpolates with
ELEMENT_VECTORS = {name: e.vectors for name, e in ELEMENTS.items()}
ELEMENT_TYPES = tuple(ELEMENTS)


def lagrange(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quadratic Lagrange polynomials on nodes ξ = −1, 0, 1 and their ξ-derivatives, (n, 3) each."""
    xi = np.asarray(xi, dtype=float)
    L = np.stack([0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)], axis=-1)
    dL = np.stack([xi - 0.5, -2.0 * xi, xi + 0.5], axis=-1)
    return L, dL


def section_monomials(y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Section monomials m_k(y, z) in slot order and their y- and z-derivatives, (n, 6) each."""
    y = np.asarray(y, dtype=float)
    z = np.asarray(z, dtype=float)
    one, zero = np.ones_like(y), np.zeros_like(y)
    m = np.stack([one, y, z, 0.5 * y * y, 0.5 * z * z, y * z], axis=-1)
    my = np.stack([zero, one, zero, y, zero, z], axis=-1)
    mz = np.stack([zero, zero, one, zero, z, y], axis=-1)
    return m, my, mz


def shape_functions(xi: np.ndarray, y: np.ndarray, z: np.ndarray,
                    vectors: tuple[int, ...] = ELEMENT_VECTORS[DEFAULT_ELEMENT]) -> tuple[np.ndarray, np.ndarray]:
    """Shape functions N (n, S) and their derivatives dN (n, S, 3) w.r.t. (ξ, y, z) (eq. 6).

    Points are given pointwise (xi, y, z of equal length n).  ``vectors`` selects the nodal
    vectors (default all six: 3363, S = 18; ``ELEMENT_VECTORS["3333"]``: S = 9); slot order is
    node-major, ``len(vectors) * node + k``.
    """
    L, dL = lagrange(xi)
    m, my, mz = (a[:, list(vectors)] for a in section_monomials(y, z))
    n, S = L.shape[0], 3 * len(vectors)
    N = (L[:, :, None] * m[:, None, :]).reshape(n, S)
    dN = np.empty((n, S, 3))
    dN[:, :, 0] = (dL[:, :, None] * m[:, None, :]).reshape(n, S)
    dN[:, :, 1] = (L[:, :, None] * my[:, None, :]).reshape(n, S)
    dN[:, :, 2] = (L[:, :, None] * mz[:, None, :]).reshape(n, S)
    return N, dN


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
