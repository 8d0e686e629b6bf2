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

import functools
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
        return self.monomial_derivatives(y, z, ((dy, dz),))[0]

    def monomial_derivatives(self, y: np.ndarray, z: np.ndarray, pairs: tuple) -> np.ndarray:
        """∂^a_y ∂^b_z of every nodal vector's monomial for each (a, b) of ``pairs``, at points
        (y, z): (len(pairs), n, vectors_per_node), each y^p z^q / (p! q!) formed as (y·y·…)(z·z·…)
        times 1/(p! q!) (0 where a derivative order exceeds the exponent), in a few array
        operations for all pairs at once: the contact surface asks for six at every step of its
        closest-point descent (one call per pair and monomial cost 0.6 ms a residual)."""
        y = np.asarray(y, dtype=float)
        z = np.asarray(z, dtype=float)
        ey, ez, coef, live = derivative_table(self.monomials, tuple(pairs))
        Y, Z = _powers(y, self.order), _powers(z, self.order)
        out = np.where(live, coef * (Y[..., ey] * Z[..., ez]), 0.0)
        # C-contiguous (n, vectors) per pair, as the stacked columns were: products and sums over
        # them take the same paths (a strided view changed the traction loads' sums by 1e-20)
        return np.ascontiguousarray(np.moveaxis(out.reshape(y.shape + (len(pairs), len(self.monomials))), -2, 0))

    def shape_functions(self, xi, y, z, vectors: tuple[int, ...] | None = None):
        """N (n, S) and dN (n, S, 3) w.r.t. (ξ, y, z) of ``vectors`` (default the whole block:
        S = ``slots``), slot ``len(vectors) * node + k``."""
        vectors = tuple(range(len(self.monomials))) if vectors is None else vectors
        L, dL = self.axial(xi)
        m, my, mz = self.monomial_derivatives(y, z, ((0, 0), (1, 0), (0, 1)))[:, :, list(vectors)]
        n, S = L.shape[0], L.shape[1] * len(vectors)
        N = (L[:, :, None] * m[:, None, :]).reshape(n, S)
        dN = np.empty((n, S, 3))
        dN[:, :, 0] = (dL[:, :, None] * m[:, None, :]).reshape(n, S)
        dN[:, :, 1] = (L[:, :, None] * my[:, None, :]).reshape(n, S)
        dN[:, :, 2] = (L[:, :, None] * mz[:, None, :]).reshape(n, S)
        return N, dN


@functools.lru_cache(maxsize=None)
def derivative_table(monomials: tuple, pairs: tuple) -> tuple[np.ndarray, ...]:
    """For each (a, b) of ``pairs`` and each monomial (i, j): the exponents (i − a, j − b) (0 where
    negative), 1/((i − a)! (j − b)!) and whether the derivative is a monomial at all (not 0)."""
    rows = [(i - a, j - b) for a, b in pairs for i, j in monomials]
    ey = np.array([max(p, 0) for p, _ in rows])
    ez = np.array([max(q, 0) for _, q in rows])
    coef = np.array([1.0 / (math.factorial(p) * math.factorial(q)) for p, q in zip(ey, ez)])
    live = np.array([p >= 0 and q >= 0 for p, q in rows])
    return ey, ez, coef, live


def _powers(x: np.ndarray, order: int) -> np.ndarray:
    """[1, x, x², …, x^order] along a new last axis, x^n by repeated products ((x·x)·x …)."""
    out = np.empty(x.shape + (order + 1,))
    out[..., 0] = 1.0
    for n in range(1, order + 1):
        out[..., n] = x if n == 1 else out[..., n - 1] * x
    return out


@dataclass(frozen=True)
class Element:
    """An element: its registry name, its node block, the vectors of the block it interpolates
    with (indices; the others are held at their reference value 0) and the volumetric-locking
    remedy a beam of it gets unless the config says otherwise (``none`` | ``ecm`` | ``mixed``,
    config ``beams[i].locking``; model.Beam.parts).

    ``section_degree``: the least polynomial degree of the section rule the element needs; a
    beam's ``cubature_degree`` below it is raised to it (config/beams.py).  The higher orders
    set 2 × order: the stiffness integrates products of two monomials of the field (degree
    2·order) and the tractions and section means their single monomials.  0 (3363, 3333): the
    configured degree as given (the speed–accuracy study under-integrates 3363 on purpose,
    docs/studies.md)."""
    name: str
    block: NodeBlock
    vectors: tuple[int, ...] | None = None
    default_locking: str = "none"
    section_degree: int = 0
    #: the ``locking`` values a beam of it accepts (33103, 33153: not ``ecm``, whose ν = 0 part
    #: does work on the cubic modes in a homogeneous state: docs/locking.md, "Orders 3 and 4")
    remedies: tuple[str, ...] = ("none", "ecm", "mixed")
    #: why the others are refused (the config error says it)
    refused_because: str = ""

    def __post_init__(self):
        if self.vectors is None:
            object.__setattr__(self, "vectors", tuple(range(self.block.vectors_per_node)))

    @property
    def order(self) -> int:
        """The degree of the section field it interpolates (3333: 1, 3363: 2)."""
        return max(sum(self.block.monomials[v]) for v in self.vectors)

    def raise_section_rule(self, section):
        """``section`` (a SectionSpec) with its ``cubature_degree`` raised to ``section_degree``."""
        section.cubature_degree = max(section.cubature_degree, self.section_degree)
        return section

    @property
    def held(self) -> tuple[int, ...]:
        """Vectors of the block this element does not interpolate with (held at 0)."""
        return tuple(v for v in range(self.block.vectors_per_node) if v not in self.vectors)

    def section_monomials(self, y, z) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """m, ∂m/∂y, ∂m/∂z of the whole block (n, vectors_per_node) each."""
        return tuple(self.block.monomial_derivatives(y, z, ((0, 0), (1, 0), (0, 1))))

    def shape_functions(self, xi: np.ndarray, y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Shape functions N (n, S) and their derivatives dN (n, S, 3) w.r.t. (ξ, y, z) of the
        interpolated vectors, slot ``len(vectors) * node + k`` (S = axial nodes × vectors)."""
        return self.block.shape_functions(xi, y, z, self.vectors)
