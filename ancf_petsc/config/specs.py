"""The validated config as dataclasses (ModelSpec and its parts) and the vocabularies of choices."""
from __future__ import annotations

import difflib
from dataclasses import dataclass, field
from typing import Any

from ..contact.laws import LAWS, SlidingLaw
from ..contact.tangential import TANGENTIAL_LAWS
from ..physics.elements import DEFAULT_ELEMENT
from ..physics.laws import MATERIALS

LOCKING = ("none", "ecm", "mixed")
SECTION_SHAPES = ("ellipse", "circle", "rectangle", "outline")
MATERIAL_MODELS = tuple(MATERIALS)          # the registry's names (physics/laws.py)
FIBRE_FOLLOW = ("twist", "axis")
SUPPORTED_END_RULES = ("merge", "keep")     # contact.projection.supported_ends
FADE_RULES = ("settle", "newton")           # contact.fade (contact/weights.py)
FADE_FORCES = ("auto", "variational", "pointwise")  # contact.fade_forces (weights.py, fade_switch.py)
CONTACT_MODES = tuple(LAWS)                 # the registry's names (contact/laws.py)
TANGENTIAL_LAW_NAMES = tuple(TANGENTIAL_LAWS)   # contact.tangential.law (contact/tangential.py)
DEFAULT_CONTACT_MODE = SlidingLaw.name
PARTITION_METHODS = ("blocks", "metis", "beams")
TWIST_RULES = ("centroid", "origin", "junction")
#: ``solver.tangent``: the displacement model's, or the mixed-integration-point one (petsc/mixed_tangent.py)
TANGENTS = ("standard", "mixed")
#: contact keys of the penalty formulation, gone since contact is enforced by Lagrange multipliers
REMOVED_CONTACT_KEYS = ("penalty", "penalty_scale", "augmented", "gap_tolerance", "max_augmentations",
                        "smoothing")
#: named supports → the fixed (vector, component) pairs of a node block (physics/elements), vectors
#: in the block's order (r, r_y, r_z first; 3363: then r_yy, r_zz, r_yz), components 0, 1, 2 = x, y, z
#: (README.md, "Fix presets", says what each means)
FIX_PRESETS = {
    # a built-in end: every component (the solid's u = 0 over the root face)
    "clamped": lambda block: [(v, c) for v in range(block.vectors_per_node) for c in range(3)],
    # the paper's "r fixed, cross-section free to contract": all but r_y·e_y and r_z·e_z, so the
    # section's in-plane shear (r_y·e_z, r_z·e_y) and its higher modes are clamped too
    "reduced": lambda block: [(v, c) for v in range(block.vectors_per_node) for c in range(3)
                              if (v, c) not in ((1, 1), (2, 2))],
    # a root face on a frictionless plane x = const (the solid's u_x = 0 over the face, free in
    # its plane): every x-component, r itself, and r_y·e_z (the section's rigid turn about x)
    "plane": lambda block: [(0, 0), (0, 1), (0, 2), (1, 0), (1, 2), (2, 0)]
                           + [(v, 0) for v in range(3, block.vectors_per_node)],
}


# --------------------------------------------------------------------------------- spec types
class _Fields:
    """A spec part whose attributes are its fields: one set under another name through the Python
    API (``spec.twist = 30`` for twist_deg, ``beam.n_elements = 8``) was kept and never read, and
    the run solved the unedited model; it now raises AttributeError naming the fields."""
    __slots__ = ()

    def __setattr__(self, name: str, value) -> None:
        fields = type(self).__dataclass_fields__
        if name not in fields:
            near = difflib.get_close_matches(name, list(fields), 1)
            raise AttributeError(f"{type(self).__name__} has no field {name!r}"
                                 + (f" (did you mean {near[0]!r}?)" if near else "")
                                 + f"; its fields: {', '.join(fields)}")
        object.__setattr__(self, name, value)


@dataclass
class SectionSpec(_Fields):
    shape: str
    center: tuple[float, float] = (0.0, 0.0)
    semi_axes: tuple[float, float] | None = None
    radius: float | None = None
    size: tuple[float, float] | None = None
    curves: list | None = None            # inline outline: [{name, points}]
    file: str | None = None               # sections file (Type III format)
    loop: str | None = None
    spline_degree: int = 3
    cubature_degree: int = 6
    compress: bool = True
    spline_degree_given: bool = False


# Gauss points along ξ per element.  2 (reduced integration along the beam) is the
# accurate rule: 3 (the paper's full rule) shear- and volume-locks slender or clamped beams
# (docs/verification.md, "Locking"); configs that reproduce the paper state axial_points: 3.
DEFAULT_AXIAL_POINTS = 2


@dataclass
class BeamSpec(_Fields):
    name: str
    section: SectionSpec
    material: dict
    elements: int
    axial_points: int = DEFAULT_AXIAL_POINTS
    element: str = DEFAULT_ELEMENT        # element type, see physics.elements.ELEMENTS
    locking: str = "none"                 # 'ecm' (Poisson), 'mixed' (volumetric): remedies, model.Beam.parts
    #: the volumetric term on a section rule of this degree (selective reduced integration, a
    #: locking diagnosis of ancf_verify.fibres; set in code, no config key): model.Beam.volumetric_degree
    volumetric_degree: int | None = None
    #: ``locking: mixed`` on other pressure columns (set in code, no config key): model.Beam.pressure_columns
    pressure_columns: tuple | None = None
    #: what parse_beams read from the config: (element, locking given); an element changed after
    #: parsing is judged against it (beams.check_edited_beams)
    parsed: tuple | None = None


class _Placed(_Fields):
    """A support, load or probe: ``resolved`` is its node as last resolved (parsing,
    ``conditions.resolve_nodes``), so that a ``node`` edited through the Python API is told apart."""
    resolved: int | None
    node: int

    def __post_init__(self) -> None:
        self.resolved = self.node


@dataclass
class BCSpec(_Placed):
    beam: int
    node: int
    dofs: list[tuple[int, int]]           # (vector slot 0..5, component 0..2), held at the reference
    path: str = ""
    #: prescribed displacements at load factor 1, ramped with it: (vector slot, component, value)
    displacement: list[tuple[int, int, float]] = field(default_factory=list)
    name: str = ""                        # the support's name in the reported reactions
    curve: tuple | None = None            # ((λ, m), ...): displacement × m(λ) (None: × λ)
    given: object = None                  # the node as written (first, last, an index): resolve_nodes
    column: str | None = None             # the history column its curve was made from
    resolved: int | None = field(default=None, init=False, repr=False, compare=False)  # _Placed


@dataclass
class LoadSpec(_Placed):
    beam: int
    node: int
    kind: str                             # 'force' | 'traction_force'
    force: tuple[float, float, float]
    path: str = ""
    curve: tuple | None = None            # ((λ, m), ...): force × m(λ) (None: × λ)
    given: object = None                  # the node as written: conditions.resolve_nodes
    column: str | None = None             # the history column its curve was made from
    resolved: int | None = field(default=None, init=False, repr=False, compare=False)  # _Placed


@dataclass
class ProbeSpec(_Placed):
    name: str
    beam: int
    node: int
    vector: str = "r"
    given: object = None                  # the node as written: conditions.resolve_nodes
    path: str = ""
    resolved: int | None = field(default=None, init=False, repr=False, compare=False)  # _Placed


@dataclass
class TangentialSpec(_Fields):
    """``contact.tangential``: the interface's tangential law (contact/tangential.py) and its values."""
    law: str = TANGENTIAL_LAW_NAMES[0]     # a name of TANGENTIAL_LAWS; the first is frictionless
    stiffness: float | None = None         # elastic matrix: k_t = G / thickness [Pa/m]
    friction: float | None = None          # Coulomb: the friction coefficient μ
    augmentation: float | None = None      # Coulomb: the stick test's c in units of k_s / A (None: G/E)
    # Coulomb: the end tangential functions where both bodies' positions are held, folded into
    # their neighbours (merge, as the normal ones: unique root multipliers) or kept
    # (contact/multipliers.py fold_tangential; docs/interface.md Limits)
    supported_ends: str = "merge"
    #: Coulomb: no friction on the tangential functions centred below this reference x [m] (a
    #: diagnostic of the clamped roots, set in code, no config key: ancf_verify.friction.beams)
    free_zone: float = 0.0


@dataclass
class ContactSpec(_Fields):
    mode: str = DEFAULT_CONTACT_MODE       # a name of contact/laws.py LAWS
    interfaces: list = field(default_factory=list)   # [(beam_a, beam_b, curve name or None)]
    axial_points: int = 3
    curve_points: int = 2
    search_margin: float = 0.1            # fraction of the beam length a point may slide
    # Bernstein degrees (along the beam, across the interface) of the contact pressure
    # (contact/multipliers.py).  Default: the trace of the elements along the beam
    # (axial_points − 1), linear across (1): docs/contact.md, "Which pressure space"
    projection: tuple[int, int] = (2, 1)
    per_element: bool = False             # pressure discontinuous between A elements
    curve_spans: int = 1                  # equal spans of the pressure across (B-splines; 1: Bernstein)
    # the axial pressure functions span groups of this many A elements: the space of a coarser
    # mesh on this one's displacements (a diagnosis, set in code: no config key;
    # ancf_verify/studies/contact_variants.py)
    group: int = 1
    # the end functions at supported ends (both bodies clamped): folded into their neighbours
    # (merge) or kept (docs/contact.md, "Supported ends")
    supported_ends: str = "merge"
    scaling: float = 1.0                  # factor on k_s, the multipliers' unit (no effect on answers)
    # the fade weights of points past B's ends: differentiated inside Newton's iteration (newton,
    # the default without a tangential law) or settled between solves (settle, the default with
    # one; contact/weights.py)
    fade: str = "newton"
    # the forces of points in a fade band: the weighted gaps' exact variation (variational: a
    # symmetric Jacobian, LDLᵀ and its inertia) or −Σ τ_p ∇g_p (pointwise: LU, no inertia; the
    # only choice with a tangential law); contact/weights.py
    fade_forces: str = "auto"
    tangential: TangentialSpec | None = None   # interface shear (None: frictionless)


@dataclass
class SolverSpec(_Fields):
    max_increment: float | None = None
    initial_increment: float | None = None    # first increment (default: the first level)
    min_increment: float = 1e-4
    max_cutbacks: int = 12
    growth: float = 2.0
    easy_iterations: int = 8
    predictor: str = "secant"              # none | secant | tangent (solving/predictor.py); a load
                                           # history's and a fibre law's default is tangent
                                           # (config/parse.py default_predictor)
    reuse_tangent: bool = True            # chord steps / kept fieldsplit factors (solving.chord)
    compact_factor: bool = True           # one rank: MUMPS factors J's structural nonzeros only
                                          # (linalg/compact_factor.py)
    merit: str = "energy"                 # what bt/l2 line searches decrease: energy | residual
    min_det_f: float = 0.1                # Newton steps are shortened to keep det F above this
    section_update: str = "linear"        # linear | rotation: a Newton step adds to the section
                                          # vectors or turns them (petsc/section_rotation.py)
    tangent: str = "standard"             # standard | mixed: the initial-stress part from the stress
                                          # of the linearised strain (petsc/mixed_tangent.py)
    max_newton_iterations: int | None = None   # budget for the whole run (None: no limit)
    stability_cutbacks: int = 4           # retries with smaller steps when a step lands less stable
    matrix: str = "auto"                  # Jacobian storage: auto | aij | sbaij (linalg.options.matrix_type)
    linear: str = "auto"                  # linear solver: auto | direct | fieldsplit (linalg.choice.choose)
    allow_unstable: bool = False          # True: levels with negative tangent eigenvalues are accepted
    branch_switch: bool = True            # at a give-up, switch to a stable branch from an unstable
                                          # state met ahead (solving/branch_switch.py)
    step_over_jumps: bool = True          # a level inside a band without equilibrium (a jump of the
                                          # residual) is reported just past it (solving/step_over.py)
    full_step_first: bool = True          # the l2 line search takes the whole Newton step where it
                                          # cuts |F| to a quarter (linalg/full_step_first.py)
    band_step: float = 0.0                # full Newton steps with contact carry no partner place through
                                          # more fade-band widths than this (0: no limit, the
                                          # default; contact/band_step.py)
    options_prefix: str = ""              # PETSc options prefix of this solve, e.g. left_ (-left_snes_type)
    #: the keys parse_config chose by the model (predictor, section_update: parse.MODEL_DEFAULTS)
    #: and their values then; a model edited after parsing takes its own (parse.refresh_defaults)
    defaulted: dict = field(default_factory=dict)


@dataclass
class OutputSpec(_Fields):
    dir: str
    vtk: bool = True
    vtk_samples: int = 4
    vtk_compress: bool | None = None      # zlib in the VTUs (0.4x the size, 6x the write time);
                                          # None (auto): from io.vtk.AUTO_COMPRESS_POINTS points on


@dataclass
class AccuracySpec(_Fields):
    """``accuracy:``: pick the coarsest element count whose probe is within rtol (refinement.py)."""
    probe: str
    rtol: float = 1e-3
    component: str = "norm"               # x | y | z | norm of the probe's displacement
    level: float | None = None            # load factor the probe is read at (default: last step)
    start: int = 1                        # elements of the first beam on the first rung
    max_elements: int = 64
    section_order: str = "none"           # check: the start rung again one section order up


@dataclass
class ModelSpec(_Fields):
    name: str
    length: float
    twist_deg: float
    twist_axis: tuple[float, float]
    beams: list[BeamSpec]
    boundary_conditions: list[BCSpec]
    loads: list[LoadSpec]
    steps: list[float]
    probes: list[ProbeSpec]
    output: OutputSpec
    solver: SolverSpec
    petsc: dict[str, str]
    contact: ContactSpec | None
    base_dir: str
    raw: dict = field(repr=False, default_factory=dict)
    partition: str = "blocks"              # 'blocks' (contiguous per beam), 'metis' or 'beams' (whole beams)
    accuracy: AccuracySpec | None = None
    sections: Any = None                   # geometry.sections (config.sections.SectionsSpec)
    twist_rule: tuple = ("point",)         # twist-axis rule (model.build.resolve_twist_axis); twist_axis then
    twist_default: bool = False            # holds the resolved point; True: the rule was not given
    twist_resolved: tuple | None = None    # the point the rule gave at the last build (an edit differs)
    history: Any = None                    # history: (config.history.HistorySpec): loads over frames
