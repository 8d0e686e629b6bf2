"""The layout of an ANCF continuum element as data: its node block and the vectors it interpolates.

A node carries nodal vectors r_{y^i z^j} (the section field's Taylor coefficients at the beam
axis), each paired with the section monomial m(y, z) = y^i z^j / (i! j!): r ↔ 1, r_y ↔ y, r_z ↔ z,
r_yy ↔ y²/2, r_zz ↔ z²/2, r_yz ↔ yz, and so on to any order.  A ``NodeBlock`` lists those
exponent pairs in DOF order and the element's axial nodes and their shape functions; an
``Element`` names a block and the vectors of it that it interpolates with (3333 carries 3363's
block and holds the quadratic vectors at 0).  Every other module reads these: the DOFs per node,
the slots of an element, the section monomials and their derivatives (section field, contact
surface, probes, traction loads), the vector names (supports, probes, output) and the axial
shape functions.

The monomials' derivatives are monomials of the same family:
∂^a_y ∂^b_z [y^i z^j / (i! j!)] = y^(i-a) z^(j-b) / ((i-a)! (j-b)!)  (0 if a > i or b > j).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np


def quadratic_lagrange(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quadratic Lagrange polynomials on nodes ξ = −1, 0, 1 and their ξ-derivatives, (n, 3) each."""
    xi = np.asarray(xi, dtype=float)
    L = np.stack([0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)], axis=-1)
    dL = np.stack([xi - 0.5, -2.0 * xi, xi + 0.5], axis=-1)
    return L, dL


def quadratic_lagrange_second(xi: np.ndarray) -> np.ndarray:
    """Second ξ-derivatives of ``quadratic_lagrange``, (n, 3) (constant)."""
    return np.broadcast_to(np.array([1.0, -2.0, 1.0]), (len(np.atleast_1d(xi)), 3))


def vector_name(i: int, j: int) -> str:
    """The nodal vector paired with y^i z^j / (i! j!): r, r_y, r_z, r_yy, r_yz, r_yyz, ..."""
    return "r" if i + j == 0 else "r_" + "y" * i + "z" * j


def complete_monomials(order: int) -> tuple[tuple[int, int], ...]:
    """Every (i, j) with i + j ≤ order, by degree, then y before z: (0, 0), (1, 0), (0, 1), (2, 0),
    (1, 1), (0, 2), ... (the complete polynomial field of that order; 3363 orders degree 2 its own way)."""
    return tuple((d - j, j) for d in range(order + 1) for j in range(d + 1))


@dataclass(frozen=True)
class NodeBlock:
    """What a node carries and how an element spans its nodes.

    ``monomials``: the exponent pair (i, j) of each nodal vector, in DOF order (a node's DOF of
    component c of vector k is 3 k + c); the first three are always r, r_y, r_z.  ``axial_nodes`` per element (neighbours share their end
    nodes: a beam of E elements has (axial_nodes − 1) E + 1 nodes, equally spaced), ``axial`` their
    shape functions at ξ (L, dL), ``axial_second`` the second ξ-derivatives (contact surfaces)."""
    monomials: tuple[tuple[int, int], ...]
    axial_nodes: int = 3
    axial: Callable = field(default=quadratic_lagrange, compare=False)
    axial_second: Callable = field(default=quadratic_lagrange_second, compare=False)

    def __post_init__(self):
        if tuple(self.monomials[:3]) != ((0, 0), (1, 0), (0, 1)) or len(set(self.monomials)) != len(self.monomials):
            raise ValueError("a node block starts with r, r_y, r_z ((0, 0), (1, 0), (0, 1): the position "
                             "and the section directions every reader of r takes from slots 0..2) and "
                             f"names each monomial once; got {self.monomials}")

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(vector_name(i, j) for i, j in self.monomials)

    @property
    def vectors_per_node(self) -> int:
        return len(self.monomials)

    @property
    def dofs_per_node(self) -> int:
        return 3 * len(self.monomials)

    @property
    def slots(self) -> int:
        """Shape-function slots of an element over the whole block: ``vectors_per_node * node + k``."""
        return self.axial_nodes * len(self.monomials)

    @property
    def dofs_per_element(self) -> int:
        return 3 * self.slots

    @property
    def order(self) -> int:
        """The highest degree of the section field."""
        return max(i + j for i, j in self.monomials)

    def index(self, name: str) -> int:
        return self.names.index(name)

    def units(self) -> dict[str, str]:
        """The SI unit of each nodal vector: r a position, r_y, r_z directions, then 1/m per degree."""
        def unit(d):
            return "m" if d == 0 else "1" if d == 1 else "1/m" if d == 2 else f"1/m^{d - 1}"
        return {vector_name(i, j): unit(i + j) for i, j in self.monomials}

    def nodes_of(self, n_elements: int) -> int:
        return (self.axial_nodes - 1) * n_elements + 1

    def connectivity(self, n_elements: int) -> np.ndarray:
        """Beam-local node ids (E, axial_nodes) of each element."""
        k = self.axial_nodes - 1
        return k * np.arange(n_elements)[:, None] + np.arange(self.axial_nodes)[None, :]

    def section_monomials(self, y: np.ndarray, z: np.ndarray, dy: int = 0, dz: int = 0) -> np.ndarray:
        """∂^dy_y ∂^dz_z of every nodal vector's monomial at points (y, z), (n, vectors_per_node)."""
        y = np.asarray(y, dtype=float)
        z = np.asarray(z, dtype=float)
        cols = [_monomial(i - dy, j - dz, y, z) for i, j in self.monomials]
        return np.stack(cols, axis=-1)

    def shape_functions(self, xi, y, z, vectors: tuple[int, ...] | None = None):
        """N (n, S) and dN (n, S, 3) w.r.t. (ξ, y, z) of ``vectors`` (default the whole block:
        S = ``slots``), slot ``len(vectors) * node + k``."""
        vectors = tuple(range(len(self.monomials))) if vectors is None else vectors
        L, dL = self.axial(xi)
        m, my, mz = (self.section_monomials(y, z, a, b)[:, list(vectors)] for a, b in ((0, 0), (1, 0), (0, 1)))
        n, S = L.shape[0], L.shape[1] * len(vectors)
        N = (L[:, :, None] * m[:, None, :]).reshape(n, S)
        dN = np.empty((n, S, 3))
        dN[:, :, 0] = (dL[:, :, None] * m[:, None, :]).reshape(n, S)
        dN[:, :, 1] = (L[:, :, None] * my[:, None, :]).reshape(n, S)
        dN[:, :, 2] = (L[:, :, None] * mz[:, None, :]).reshape(n, S)
        return N, dN


def _monomial(i: int, j: int, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """y^i z^j / (i! j!) (zeros for a negative exponent: the derivative of a lower monomial)."""
    if i < 0 or j < 0:
        return np.zeros_like(y)
    if i == 0 and j == 0:
        return np.ones_like(y)
    yi = _power(y, i)
    zj = _power(z, j)
    term = zj if yi is None else yi if zj is None else yi * zj
    c = 1.0 / (math.factorial(i) * math.factorial(j))
    return term if c == 1.0 else c * term


def _power(x: np.ndarray, n: int):
    """x^n by repeated products (None for n = 0)."""
    if n == 0:
        return None
    out = x
    for _ in range(n - 1):
        out = out * x
    return out


@dataclass(frozen=True)
class Element:
    """An element: its registry name, its node block, the vectors of the block it interpolates
    with (indices; the others are held at their reference value 0) and the volumetric-locking
    remedy a beam of it gets unless the config says otherwise (``none`` | ``ecm`` | ``mixed``,
    config ``beams[i].locking``; model.Beam.parts)."""
    name: str
    block: NodeBlock
    vectors: tuple[int, ...] | None = None
    default_locking: str = "none"

    def __post_init__(self):
        if self.vectors is None:
            object.__setattr__(self, "vectors", tuple(range(self.block.vectors_per_node)))

    @property
    def held(self) -> tuple[int, ...]:
        """Vectors of the block this element does not interpolate with (held at 0)."""
        return tuple(v for v in range(self.block.vectors_per_node) if v not in self.vectors)

    def section_monomials(self, y, z) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """m, ∂m/∂y, ∂m/∂z of the whole block (n, vectors_per_node) each."""
        b = self.block
        return b.section_monomials(y, z), b.section_monomials(y, z, 1, 0), b.section_monomials(y, z, 0, 1)

    def shape_functions(self, xi: np.ndarray, y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Shape functions N (n, S) and their derivatives dN (n, S, 3) w.r.t. (ξ, y, z) of the
        interpolated vectors, slot ``len(vectors) * node + k`` (S = axial nodes × vectors)."""
        return self.block.shape_functions(xi, y, z, self.vectors)
