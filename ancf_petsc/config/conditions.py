"""Supports, loads, load steps and probes of a config, referring to beams by name and nodes."""
from __future__ import annotations

from ..physics.elements import DEFAULT_ELEMENT, ELEMENTS
from .history import HistorySpec, history_curve
from .specs import FIX_PRESETS, BCSpec, LoadSpec, ProbeSpec
from .values import ConfigError, key_path, mapping, number, sequence, shown, string, vector


DEFAULT_BLOCK = ELEMENTS[DEFAULT_ELEMENT].block


def node_ref(value, path: str, n_nodes: int) -> int:
    """A node: first, last or an index (negative counts from the end)."""
    if value == "first":
        return 0
    if value == "last":
        return n_nodes - 1
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(path, f"expected 'first', 'last' or a node index; got {shown(value)}")
    idx = value + n_nodes if value < 0 else value
    if not 0 <= idx < n_nodes:
        raise ConfigError(path, f"node {value} does not exist; this beam has nodes 0..{n_nodes - 1}")
    return idx


def beam_ref(value, path: str, names: list[str]) -> int:
    """A beam by name → its index."""
    if value not in names:
        raise ConfigError(path, f"unknown beam {shown(value)}; beams are: {', '.join(names)}")
    return names.index(value)


def _fix(value, path: str, block) -> list[tuple[int, int]]:
    """Fixed (vector, component) pairs of ``block``'s nodal vectors (physics/elements NodeBlock)."""
    if isinstance(value, str):
        if value not in FIX_PRESETS:
            raise ConfigError(path, f"unknown preset {shown(value)}; use {', '.join(FIX_PRESETS)} "
                                    "or a mapping like {r: xyz, r_y: xz}")
        return list(FIX_PRESETS[value](block))
    VECTORS = block.names
    mapping(value, path, optional=VECTORS)
    dofs = []
    for name, comps in value.items():
        cp = key_path(path, name)
        if not isinstance(comps, str) or not comps or any(c not in "xyz" for c in comps) \
                or len(set(comps)) != len(comps):
            raise ConfigError(cp, f"expected components as a string from 'xyz' (e.g. xz); "
                                  f"got {shown(comps)}")
        dofs += [(VECTORS.index(name), "xyz".index(c)) for c in comps]
    if not dofs:
        raise ConfigError(path, "fixes nothing; name at least one vector, e.g. {r: xyz}")
    return sorted(dofs)


def _curve(value, path: str) -> tuple:
    """``[[λ₀, m₀], [λ₁, m₁], ...]``: a multiplier piecewise linear in the load factor."""
    pts = []
    for i, pair in enumerate(sequence(value, path)):
        p = key_path(path, i)
        if not isinstance(pair, (list, tuple)) or len(pair) != 2:
            raise ConfigError(p, f"expected [load factor, multiplier]; got {shown(pair)}")
        pts.append((number(pair[0], key_path(p, 0), nonneg=True), number(pair[1], key_path(p, 1))))
    if len(pts) < 2 or any(b[0] <= a[0] for a, b in zip(pts, pts[1:])):
        raise ConfigError(path, "give at least two [load factor, multiplier] points with the load "
                                "factors increasing")
    # m(λ) before the first point is m₀; a load or displacement there at λ = 0 was never solved
    # for (the levels repeating it took 0 Newton iterations and reported the rest state)
    if pts[0][1] != 0.0:
        raise ConfigError(key_path(key_path(path, 0), 1), "the multiplier at load factor 0 (the first "
                          "point's) must be 0: a run starts at rest, every load and displacement zero; "
                          f"start the curve at [0, 0]; got {pts[0][1]:g}")
    return tuple(pts)


def check_curves(spec) -> None:
    """Every requested load factor lies within every curve (no extrapolation)."""
    lo, hi = min(spec.steps), max(spec.steps)
    for item in list(spec.loads) + list(spec.boundary_conditions):
        if item.curve is not None and not (item.curve[0][0] <= lo and hi <= item.curve[-1][0]):
            raise ConfigError(f"{item.path}.curve", f"covers load factors {item.curve[0][0]:g} .. "
                              f"{item.curve[-1][0]:g}, the steps run {lo:g} .. {hi:g}; extend it")


def _displacement(value, path: str, block) -> list[tuple[int, int, float]]:
    """``{r: {x: 0.006}}``: components held at their reference value plus the load factor times
    the given displacement [m for r; the slopes' values are dimensionless]."""
    VECTORS = block.names
    mapping(value, path, optional=VECTORS)
    out = []
    for name, comps in value.items():
        cp = key_path(path, name)
        mapping(comps, cp, optional=("x", "y", "z"))
        out += [(VECTORS.index(name), "xyz".index(c), number(v, key_path(cp, c)))
                for c, v in comps.items()]
    if not out:
        raise ConfigError(path, "prescribes nothing; give e.g. {r: {x: 0.006}}")
    return sorted(out)


def parse_boundary_conditions(value, names: list[str], n_nodes: list[int],
                              history: HistorySpec | None = None, blocks: list | None = None) -> list[BCSpec]:
    """``boundary_conditions``: fixed nodal vector components (presets clamped / reduced / plane)
    and prescribed displacements (``displacement``, ramped with the load factor, or following a
    ``column`` of the load ``history``).  ``blocks``: each beam's node block (physics/elements;
    default 3363's), which names its nodal vectors."""
    blocks = blocks or [DEFAULT_BLOCK] * len(names)
    bcs = []
    for i, bc in enumerate(sequence(value, "boundary_conditions", nonempty=False)):
        p = f"boundary_conditions[{i}]"
        mapping(bc, p, required=("beam", "node"), optional=("fix", "displacement", "name", "curve", "column"))
        for key in ("curve", "column"):
            if key in bc and "displacement" not in bc:
                raise ConfigError(f"{p}.{key}", f"a {key} says how a displacement follows the load "
                                                "factor; this support prescribes none")
        if "fix" not in bc and "displacement" not in bc:
            raise ConfigError(p, "give fix (components held in place), displacement (components "
                                 "moved with the load factor), or both")
        bi = beam_ref(bc["beam"], f"{p}.beam", names)
        node = node_ref(bc["node"], f"{p}.node", n_nodes[bi])
        fixed = _fix(bc["fix"], f"{p}.fix", blocks[bi]) if "fix" in bc else []
        moved = _displacement(bc["displacement"], f"{p}.displacement", blocks[bi]) if "displacement" in bc else []
        both = sorted(set(fixed) & {(v, c) for v, c, _ in moved})
        if both:
            v, c = both[0]
            raise ConfigError(f"{p}.displacement.{blocks[bi].names[v]}.{'xyz'[c]}", "this component is also in "
                              "fix; a component is either held in place or moved, remove it from one")
        name = string(bc.get("name", f"{names[bi]}.{node}"), f"{p}.name")
        if name in [b.name for b in bcs]:
            other = next(b for b in bcs if b.name == name)
            if "name" not in bc and (other.beam, other.node) == (bi, node):
                raise ConfigError(p, f"{names[bi]} node {bc['node']} already has a support ({other.path}): "
                                     "merge the two into one entry, or give both a name")
            if "name" not in bc:
                raise ConfigError(p, f"this support's default name {name!r} is the name of {other.path} "
                                     "(on another node); give this one a name")
            raise ConfigError(f"{p}.name", f"duplicate support name {name!r} (also {other.path}); "
                                           "give each support its own name")
        curve = _curve(bc["curve"], f"{p}.curve") if "curve" in bc else None
        if moved:
            curve = history_curve(bc, history, p, curve, scaled=False)
        bcs.append(BCSpec(bi, node, fixed, p, moved, name, curve, bc["node"], moved and bc.get("column") or None))
    check_one_support(bcs, names, blocks)
    return bcs


def check_one_support(bcs: list[BCSpec], names: list[str], blocks: list) -> None:
    """Each nodal component is held by one support: of two named supports on one node that both
    held r_x (a fix and a displacement, two displacements, two fixes) the later one's value, or
    the sum of two curves' moves, was applied and each reported the whole reaction."""
    holder: dict = {}
    for bc in bcs:
        names_of = blocks[bc.beam].names
        for v, c, key in [(v, c, "fix") for v, c in bc.dofs] + [(v, c, None) for v, c, _ in bc.displacement]:
            comp = f"{names_of[v]}.{'xyz'[c]}"
            other = holder.setdefault((bc.beam, bc.node, v, c), bc)
            if other is not bc:
                where = f"{bc.path}.{key or 'displacement.' + comp}"
                raise ConfigError(where, f"{names[bc.beam]} node {bc.given}: {comp} is also held by "
                                         f"{other.path} ({other.name!r}); a component has one support, "
                                         "whose value and reaction it is: remove it from one of them")


def parse_loads(value, names: list[str], n_nodes: list[int],
                history: HistorySpec | None = None) -> list[LoadSpec]:
    """``loads``: a point force on r, or a total force spread over an end section (traction);
    scaled by the load factor, a ``curve`` of it, or a ``column`` of the load ``history``."""
    loads = []
    for i, ld in enumerate(sequence(value, "loads", nonempty=False)):
        p = f"loads[{i}]"
        mapping(ld, p, required=("beam", "node"), optional=("force", "traction_force", "curve", "column"))
        if ("force" in ld) == ("traction_force" in ld):
            raise ConfigError(p, "give exactly one of 'force' (point force on r) or "
                                 "'traction_force' (total force spread over the end section)")
        bi = beam_ref(ld["beam"], f"{p}.beam", names)
        node = node_ref(ld["node"], f"{p}.node", n_nodes[bi])
        kind = "force" if "force" in ld else "traction_force"
        if kind == "traction_force" and node not in (0, n_nodes[bi] - 1):
            raise ConfigError(f"{p}.node", "a traction_force acts on an end section: use first or last")
        curve = history_curve(ld, history, p, _curve(ld["curve"], f"{p}.curve") if "curve" in ld else None)
        loads.append(LoadSpec(bi, node, kind, vector(ld[kind], f"{p}.{kind}", 3), p, curve, ld["node"],
                              ld.get("column")))
    return loads


def check_edited_conditions(spec) -> None:
    """The supports, loads and probes of a spec edited after parsing (the Python API) read as a
    config's: a beam index the model does not have (an IndexError in the build), a force of two
    components or of text (numpy's broadcast error), a load kind or probe vector the config does
    not know (kind 'foo' ran as a point force), a probe name given twice (one probe's answers
    lost), a fixed component past the node block, and beams of one name (results.h5's
    'name already exists'), or a model name that is no text (an OutputError).  A beam may be
    given by name; numpy values are taken as numbers."""
    spec.name = string(spec.name, "name")
    names = [string(b.name, f"beams[{i}].name") for i, b in enumerate(spec.beams)]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise ConfigError(f"beams[{i}].name", f"duplicate beam name {name!r}; names must be unique")
    for key in ("boundary_conditions", "loads", "probes"):
        for i, item in enumerate(getattr(spec, key)):
            item.path = item.path or f"{key}[{i}]"
            beam = as_python(item.beam)
            item.beam = beam_ref(beam, f"{item.path}.beam", names) if isinstance(beam, str) \
                else _index(beam, f"{item.path}.beam", names)
            item.node = as_python(item.node)
    blocks = [ELEMENTS[b.element].block for b in spec.beams]
    for ld in spec.loads:
        ld.kind = string(ld.kind, f"{ld.path}.kind", ("force", "traction_force"))
        ld.force = vector(as_python(ld.force), f"{ld.path}.{ld.kind}", 3)
    for i, pr in enumerate(spec.probes):
        pr.name = string(pr.name, f"{pr.path}.name")
        if pr.name in [x.name for x in spec.probes[:i]]:
            raise ConfigError(f"{pr.path}.name", f"duplicate probe name {pr.name!r}")
        pr.vector = string(pr.vector, f"{pr.path}.vector", blocks[pr.beam].names + ("mean",))
    for bc in spec.boundary_conditions:
        n = blocks[bc.beam].vectors_per_node
        bc.displacement = [(*held[:2], number(as_python(held[2]), f"{bc.path}.displacement"))
                           if isinstance(held, (tuple, list)) and len(held) == 3 else held
                           for held in as_python(bc.displacement)]
        for held in [*bc.dofs, *bc.displacement]:
            v, c = held[:2] if isinstance(held, (tuple, list)) and len(held) in (2, 3) else (held, None)
            if not (isinstance(v, int) and isinstance(c, int) and 0 <= v < n and 0 <= c < 3):
                raise ConfigError(f"{bc.path}.fix", f"(vector, component) ({v!r}, {c!r}) is not a "
                                                    f"component of a node: vectors 0..{n - 1} "
                                                    f"({', '.join(blocks[bc.beam].names)}), components 0..2")


def as_python(value):
    """A numpy value (array or scalar) as Python's (``spec.loads[0].force = np.array(...)``)."""
    return value.tolist() if hasattr(value, "tolist") else value


def _index(value, path: str, names: list[str]) -> int:
    """A beam given by its index in ``names``."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < len(names):
        raise ConfigError(path, f"unknown beam {shown(value)}; beams are: "
                                + ", ".join(f"{i} {n}" for i, n in enumerate(names)) + " (an index or a name)")
    return value


def resolve_nodes(spec) -> None:
    """The nodes of the supports, loads and probes of ``spec`` for its beams' element counts as
    they are now: a spec changed through the Python API after parsing (``spec.beams[0].elements
    = 8``) kept the nodes its config's 'last' named for the old count, so that the load, the
    support and the probe sat on an interior node and the run completed with another model's
    answers (or an IndexError).  A ``node`` edited itself is the node as given (it was put back
    to the config's: a probe edited to node 1 reported the tip).  Raises ConfigError for an
    index the beam no longer has."""
    n_nodes = [ELEMENTS[b.element].block.nodes_of(b.elements) for b in spec.beams]
    for item in [*spec.boundary_conditions, *spec.loads, *spec.probes]:
        if item.node != item.resolved or item.given is None:     # edited, or made in code
            item.given = item.node
        if item.given is None or not 0 <= item.beam < len(n_nodes):
            continue
        item.node = item.resolved = node_ref(item.given, f"{item.path}.node", n_nodes[item.beam])
    check_one_support(spec.boundary_conditions, [b.name for b in spec.beams],
                      [ELEMENTS[b.element].block for b in spec.beams])
    for ld in spec.loads:
        if ld.kind == "traction_force" and ld.given is not None and ld.node not in (0, n_nodes[ld.beam] - 1):
            raise ConfigError(f"{ld.path}.node", "a traction_force acts on an end section: use first or last")


#: the relative distance below which two load factors are one level (the stepper's and a
#: restart's resolution)
STEP_RESOLUTION = 1e-12


def parse_steps(value) -> list[float]:
    """``steps``: strictly increasing load factors."""
    steps = [number(s, f"steps[{i}]", positive=True) for i, s in enumerate(sequence(value, "steps"))]
    if any(b <= a for a, b in zip(steps, steps[1:])):
        raise ConfigError("steps", f"load factors must increase strictly; got {steps}")
    for i, (a, b) in enumerate(zip(steps, steps[1:])):
        if b <= a * (1.0 + STEP_RESOLUTION):     # the stepper would take it as reached: no record
            raise ConfigError(f"steps[{i + 1}]", f"must exceed steps[{i}] = {a!r} by more than "
                                                 f"{STEP_RESOLUTION:g} of it (closer, they are one "
                                                 f"level); got {b!r}")
    return steps


def parse_probes(value, names: list[str], n_nodes: list[int], blocks: list | None = None) -> list[ProbeSpec]:
    """``probes``: named nodal vectors reported at every level, or (``vector: mean``) the
    displacement averaged over the node's section, ∫ u dA / A.  ``blocks`` as in
    ``parse_boundary_conditions``."""
    blocks = blocks or [DEFAULT_BLOCK] * len(names)
    probes = []
    for i, pr in enumerate(sequence(value, "probes", nonempty=False)):
        p = f"probes[{i}]"
        mapping(pr, p, required=("name", "beam", "node"), optional=("vector",))
        bi = beam_ref(pr["beam"], f"{p}.beam", names)
        pname = string(pr["name"], f"{p}.name")
        if pname in [x.name for x in probes]:
            raise ConfigError(f"{p}.name", f"duplicate probe name {pname!r}")
        probes.append(ProbeSpec(pname, bi, node_ref(pr["node"], f"{p}.node", n_nodes[bi]),
                                string(pr.get("vector", "r"), f"{p}.vector", blocks[bi].names + ("mean",)),
                                pr["node"], p))
    return probes
