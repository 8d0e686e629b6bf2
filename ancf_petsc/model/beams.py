"""The discretised model: beams (elements, nodes, section, material, quadrature) and their numbering.

Global numbering (before any partitioning): beams in config order, nodes of a beam consecutive
((k − 1) n_el + 1 per beam for elements of k axial nodes), ``Model.block.dofs_per_node`` DOFs per
node in the order of the block's nodal vectors (``physics/elements``: 18 in eq. (3) order for
3363 and 3333).  Element e of a beam of three-node elements has nodes (2e, 2e+1, 2e+2).  The model is replicated on every rank; only the per-element
quadrature data (``element_data``) is built for the elements a rank owns."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..config.specs import ModelSpec
from ..physics import element3363 as el
from ..physics.axial_shear import axial_shear_for
from ..physics.cubature import ellipse_rule, gauss_legendre
from ..physics.elements import Element, NodeBlock, element as registered_element
from ..physics.goh import GOH
from ..physics.materials import NeoHookean
from ..physics.mixed import ProjectedDilatation, grouped_basis, pressure_basis
from ..physics.section import Section


@dataclass
class Beam:
    index: int
    name: str
    section: Section
    material: object
    n_elements: int
    node_offset: int
    element_offset: int
    x_nodes: np.ndarray
    axial_points: int
    element: str = el.DEFAULT_ELEMENT                      # a name of physics.elements.ELEMENTS
    locking: str = "none"                                  # 'none' | 'ecm' | 'mixed' (see ``parts``)
    xi: np.ndarray = field(repr=False, default=None)      # (P,) ξ of the element's Gauss points
    yz: np.ndarray = field(repr=False, default=None)      # (P, 2) section coordinates
    wq: np.ndarray = field(repr=False, default=None)      # (P,) axial × section weights
    dN: np.ndarray = field(repr=False, default=None)      # (P, S, 3), S = 3 × active vectors
    dN_axis: np.ndarray = field(repr=False, default=None)  # (na, S, 3) on the beam axis y = z = 0
    wq_axis: np.ndarray = field(repr=False, default=None)  # (na,) axial weights × section area
    # sections that vary along x (geometry.sections with stations): dN (E, P, S, 3), wq (E, P),
    # yz (E, P, 2), wq_axis (E, na) per element; ``ring_at(x)`` the outline (beam coordinates)
    ring_at: object = field(repr=False, default=None)
    # fibre directions of a fibre-reinforced law (GOH), (families, E, P, 3) at the Gauss points
    # and (families, E, na, 3) on the axis (``locking: ecm``); set once (model/fibre_setup.py)
    fibres: np.ndarray = field(repr=False, default=None)
    fibres_axis: np.ndarray = field(repr=False, default=None)
    #: selective reduced integration of the volumetric term (a locking diagnosis, set in code,
    #: no config key: BeamSpec.volumetric_degree): the section rule's degree, None = the full rule
    volumetric_degree: int | None = None
    #: ``locking: mixed`` on another pressure space per station: groups of columns of the complete
    #: quadratic basis (physics/mixed.py grouped_basis; a diagnosis, set in code, no config key:
    #: BeamSpec.pressure_columns); None: {1, y, z}
    pressure_columns: tuple | None = None

    @property
    def layout(self) -> Element:
        """This beam's element (the registry's entry for ``element``)."""
        return registered_element(self.element)

    @property
    def vectors(self) -> tuple[int, ...]:
        """The nodal vectors this beam's element interpolates (all six for 3363)."""
        return self.layout.vectors

    def parts(self) -> list[tuple[np.ndarray, np.ndarray, object]]:
        """(dN, weights, material) of each integrated part of the strain energy.

        ``locking: ecm`` is the enhanced continuum mechanics approach of Gerstmayr, Matikainen &
        Mikkola (2008) against Poisson locking of the linear section (3333), which cannot contract
        linearly in y, z under bending:  Π = ∫ Ψ₀ dV + ∫ A [Ψ − Ψ₀]_axis dx, with Ψ₀ the same
        material at ν = 0 (``material.poisson_free()``) over the full section rule and the
        difference Ψ − Ψ₀ on the beam axis (one point per axial station, weight = area), Ψ₀'s
        shear modulus μ₀ = E/2 in the axial planes brought back to μ (physics/axial_shear.py).  A
        homogeneous state keeps Ψ exactly; bending sees E instead of the locked E(1−ν)/((1+ν)(1−2ν)),
        torsion μ instead of μ₀.
        A fibre-reinforced law comes bound to its fibre directions at each part's points (all
        elements; ``Model.element_data`` takes a rank's).

        ``locking: mixed`` (volumetric locking of the quadratic section, 3363): the law's
        K/2 (J − 1)² on the dilatation projected per axial station onto {1, y, z}, the condensed
        three-field functional of physics/mixed.py; one part, whose law ``element_data`` binds to
        the elements' weights."""
        if self.volumetric_degree is not None:
            return self._selective_parts()
        mat = self._bound(self.material, self.fibres)
        if self.locking == "mixed":
            basis = pressure_basis(self.yz, self.wq, self.axial_points) if self.pressure_columns is None \
                else grouped_basis(self.yz, self.wq, self.axial_points, self.pressure_columns)
            return [(self.dN, self.wq, ProjectedDilatation(mat, basis))]
        on_axis = self._bound(self.material, self.fibres_axis)
        if self.locking == "ecm":
            free = self.material.poisson_free()
            parts = [(self.dN, self.wq, self._bound(free, self.fibres)), (self.dN_axis, self.wq_axis, on_axis),
                     (self.dN_axis, -self.wq_axis, self._bound(free, self.fibres_axis))]
            shear = axial_shear_for(self.material, free)      # ν = 0's μ₀ = E/2 back to μ (torsion)
            return parts + ([] if shear is None else [(self.dN, self.wq, shear), (self.dN_axis, -self.wq_axis, shear)])
        return [(self.dN, self.wq, mat)]

    def _selective_parts(self) -> list[tuple[np.ndarray, np.ndarray, object]]:
        """The law without its volumetric term on the full rule, plus K/2 (J − 1)² on the
        elliptic section rule of degree ``volumetric_degree`` (same axial points): selective
        reduced integration over the section.  Neo-Hookean and GOH laws, elliptic sections."""
        m, semi = self.material, self.section.shape_params.get("semi_axes")
        if semi is None or not isinstance(m, (NeoHookean, GOH)):
            raise ValueError(f"beam {self.name}: volumetric_degree needs an elliptic section and a "
                             "neo-Hookean or GOH law")
        pts, w = ellipse_rule(*semi, self.volumetric_degree)
        xa, wa = gauss_legendre(self.axial_points)
        _, dN = self.layout.shape_functions(*el.tensor_points(xa, pts))
        matrix = GOH(m.mu, 0.0, m.k1, m.k2, m.kappa, m.fibres) if isinstance(m, GOH) else NeoHookean(m.mu, 0.0)
        return [(self.dN, self.wq, self._bound(matrix, self.fibres)),
                (dN, np.repeat(wa, len(w)) * np.tile(w, len(xa)), NeoHookean(0.0, m.K))]

    @staticmethod
    def _bound(material, directions):
        return material if directions is None else material.with_directions(directions)

    @property
    def n_nodes(self) -> int:
        return self.layout.block.nodes_of(self.n_elements)

    @property
    def connectivity(self) -> np.ndarray:
        """Global node ids (n_el, axial nodes)."""
        return self.node_offset + self.layout.block.connectivity(self.n_elements)

    @property
    def points_per_element(self) -> int:
        return self.wq.shape[-1]


@dataclass
class Support:
    """A boundary condition: its name, node and held DOFs (global ids), for its reaction."""
    name: str
    node: int
    dofs: np.ndarray


@dataclass
class Model:
    spec: ModelSpec
    beams: list[Beam]
    q0: np.ndarray                 # (n_nodes, vectors per node, 3) reference nodal vectors
    fixed_dofs: np.ndarray         # sorted global DOF ids held at their reference value
    loading: list                  # LoadGroups (loading.py): forces and prescribed displacements
    probes: dict[str, tuple[int, np.ndarray]]   # name → (global node, weights of its vectors)
    geometry_report: list = field(default_factory=list)   # measured sections, twist axis (printed)
    warnings: list = field(default_factory=list)          # implausible sizes (plausibility.py)
    supports: list = field(default_factory=list)         # the boundary conditions (Support)
    #: per beam, the section-mean weights m̄_k = ∫ m_k dA / A of its last node (elongations)
    end_means: list = field(default_factory=list)
    #: the same of its first node (an elongation is last minus first)
    root_means: list = field(default_factory=list)

    @property
    def f_ext(self) -> np.ndarray:
        """(n_dofs,) every external generalised force at multiplier 1 (its curve's)."""
        return sum(g.forces for g in self.loading)

    @property
    def prescribed(self) -> np.ndarray:
        """(n_dofs,) every prescribed displacement at multiplier 1 (0: held in place)."""
        return sum(g.moves for g in self.loading)

    def probe_values(self, q: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """name → (displacement, value) of every probe at the nodal vectors q (n_nodes, V, 3):
        one nodal vector, or a section mean Σ_k m̄_k q_k (m̄_k = ∫ m_k dA / A)."""
        return {name: (w @ (q[node] - self.q0[node]), w @ q[node]) for name, (node, w) in self.probes.items()}

    @property
    def block(self) -> NodeBlock:
        """The node block every beam's element shares (DOFs per node, vector names, monomials)."""
        return self.beams[0].layout.block

    @property
    def dofs_per_node(self) -> int:
        return self.block.dofs_per_node

    @property
    def n_nodes(self) -> int:
        return self.q0.shape[0]

    @property
    def n_dofs(self) -> int:
        return self.dofs_per_node * self.n_nodes

    @property
    def n_elements(self) -> int:
        return sum(b.n_elements for b in self.beams)

    def element_beam(self) -> np.ndarray:
        """Beam index of every global element (n_elements,)."""
        return np.concatenate([np.full(b.n_elements, b.index) for b in self.beams])

    def node_beam(self) -> np.ndarray:
        """Beam index of every global node (n_nodes,)."""
        return np.concatenate([np.full(b.n_nodes, b.index) for b in self.beams])

    def connectivity(self) -> np.ndarray:
        """Global node ids of every element (n_elements, 3)."""
        return np.concatenate([b.connectivity for b in self.beams])

    def element_data(self, beam: Beam, local: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, object]]:
        """Per energy part (``Beam.parts``): material gradients G (E, P, S, 3), weights w (E, P)
        and material, for elements ``local`` of a beam (S = axial nodes × interpolated vectors:
        18 for 3363, 9 for 3333)."""
        conn = beam.connectivity[local]
        q0e = self.q0[conn][:, :, list(beam.vectors)].reshape(len(local), -1, 3)
        out = []
        for dN, wq, material in beam.parts():
            # per-element rules (sections varying along x) carry a leading element axis
            G, det = el.reference_gradients(q0e, dN[local] if dN.ndim == 4 else dN)
            # stored shape-function-major, (E, S, P, 3) in memory: the kernels' stacked view
            # (E, S, 3P) of the force and tangent products is then free (kernels._stack)
            G = np.ascontiguousarray(G.transpose(0, 2, 1, 3)).transpose(0, 2, 1, 3)
            w = det * (wq[local] if wq.ndim == 2 else wq[None, :])
            law = material.take(local)
            out.append((G, w, law.on(w) if isinstance(law, ProjectedDilatation) else law))
        return out

    def describe(self) -> list[str]:
        lines = list(self.geometry_report) + list(self.warnings)
        for b in self.beams:
            lock = {"ecm": ", Poisson part on the axis (ecm)",
                    "mixed": ", volumetric term on the dilatation projected on {1, y, z} per axial point (mixed)"
                    }.get(b.locking, "")
            per = (f"up to {b.points_per_element // b.axial_points} section points, varying along x"
                   if b.ring_at is not None else f"{len(b.section.weights)} section")
            lines.append(f"beam {b.name}: {b.n_elements} elements {b.element} x {b.points_per_element} "
                         f"Gauss points ({b.axial_points} axial x {per}{lock})")
            lines.append("  section " + b.section.describe()
                         + (" at x = 0 (varies along x)" if b.ring_at is not None else ""))
            lines.append("  material " + b.material.describe())
        return lines
