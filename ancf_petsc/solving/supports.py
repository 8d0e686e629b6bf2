"""Rigid-body motions the supports and the contact leave free (checked before solving).

A model in which some beam, or some group of beams tied only by frictionless contact, can move
as a rigid body has no unique equilibrium: Newton wanders or fails "at load factor 0.0002".
Here the six rigid modes of every beam (translations of r; an infinitesimal rotation ω× acting
on all six nodal vectors) are tested against the constraints at the reference state: the held
DOFs (their rows of the Jacobian are unit rows) and the contact constraints (their rows are the
constraint gradients), both read off J·v at zero load.  Rigid modes give no strain, so J·v is
exactly the constraint violation of v; combinations of modes with J·v = 0 (the null space of the
Gram matrix of J·R) are the free motions.  Unilateral contact is counted as holding (it stops a
beam from moving into its neighbour, not from lifting off): its constraints are evaluated held
(every one active, laws.HELD), as at rest, pressure-free, the law's status leaves them all out.
An elastic interface matrix holds too (its stiffness ties the beams at rest: ``_layer_rows``);
Coulomb friction does not (at rest nothing presses).
"""
from __future__ import annotations

from contextlib import contextmanager

import numpy as np
import scipy.sparse as sp
from petsc4py import PETSc

from ..contact.laws import HELD
from ..errors import InputError
from ..physics.rigid import rigid_modes

#: a combination of unit modes is free when its constraint violation (held DOFs in metres or
#: slope units, contact rows divided by k_s) is below this.  Measured: a supported beam ≈ 0.33;
#: a strand held only by sliding contact in a twisted hexagonal bundle: its screw motion 5e-8
#: (the interpolated helicoid is nearly screw-symmetric), the next mode 3.6e-3
FREE_TOLERANCE = 1e-4
AXES = ("x", "y", "z")


def beam_colours(n_beams: int, pairs) -> np.ndarray:
    """A colour per beam such that the two beams of every contact interface ``pairs`` ((a, b)
    beam indices) differ (greedy; a hexagonal bundle takes 3-4 colours)."""
    neighbours: list[set[int]] = [set() for _ in range(n_beams)]
    for a, b in pairs:
        neighbours[a].add(b)
        neighbours[b].add(a)
    colours = np.full(n_beams, -1)
    for b in range(n_beams):
        taken = {colours[o] for o in neighbours[b]}
        colours[b] = next(c for c in range(n_beams) if c not in taken)
    return colours


def _row_beams(P) -> tuple[np.ndarray, np.ndarray]:
    """The beam of each owned row's node (n_local,), −1 for a multiplier; and (n_local, 2) the
    beams each owned row belongs to, −1 for none: a node's DOFs belong to its beam, a multiplier
    to both beams of its interface."""
    lo, hi = P.layout.owned_nodes
    model_block = np.argsort(P.layout.perm)[lo:hi]
    physical = model_block < P.model.n_nodes              # the rest are multiplier nodes
    node_beam = np.full(len(model_block), -1)
    node_beam[physical] = P.model.node_beam()[model_block[physical]]
    D = P.model.dofs_per_node
    owner = np.repeat(node_beam, D)
    out = np.full((len(owner), 2), -1)
    out[:, 0] = owner
    if P.contact is not None and P.contact.n_multipliers:
        c = P.contact
        dofs = P.layout.petsc_dofs(c.multiplier_dofs()) - D * lo
        ends = np.array([[i.a.index, i.b.index] for i in c.interfaces], dtype=np.int64)[c.space.interface]
        mine = (dofs >= 0) & (dofs < len(out))
        out[dofs[mine]] = ends[mine]
    return owner, out


def check_supports(problem) -> list[str]:
    """One input error naming the beams and motions the supports and contact leave free; else
    the warning of ``lift_off_warnings`` (collective)."""
    gram, supported, labels = rigid_mode_grams(problem)
    free = _free(gram, labels)
    if free:
        held = f" ({_what_contact_holds(problem.contact)})" if problem.contact else ""
        raise InputError("boundary_conditions", "nothing holds " + "; ".join(free) + held
                         + "; add supports so that no beam can move as a rigid body")
    return lift_off_warnings(problem, _free(supported, labels))


def lift_off_warnings(problem, lifted: list[str]) -> list[str]:
    """One warning line for the motions ``lifted`` that only the unilateral law's constraints
    hold (counted as holding above, as at rest): a beam that lifts off there has nothing holding
    it (two strips, the upper held along z by contact alone and pulled off: the run failed at its
    first increment, Newton stalling at |F| 5e28 N, with no word of why)."""
    c = problem.contact
    if not lifted or c is None or not c.law.decides_activity:
        return []
    return ["warning: only unilateral contact holds " + "; ".join(lifted) + ": where it lifts off "
            "its neighbours nothing holds it, and a load that pulls it off fails the run (Newton "
            "stalls); support it, or hold the interface with contact.mode: sliding"]


def _what_contact_holds(c) -> str:
    """What the contact ``c`` leaves free, by its tangential law (an elastic matrix holds)."""
    if any(t.bounded for t in c.terms):
        return ("contact lets beams slide along each other at rest: Coulomb friction holds only "
                "where the bodies are pressed")
    if any(t.couples_beams for t in c.terms):
        return "contact and its elastic matrix tie beams only to their neighbours"
    return "frictionless contact lets beams slide along each other"


def free_rigid_motions(problem) -> list[str]:
    """Descriptions of the rigid motions nothing holds (collective; empty when supported)."""
    return _free(*rigid_mode_gram(problem))


def _free(gram: np.ndarray, labels: list) -> list[str]:
    """Descriptions of the free motions of a Gram matrix of ``rigid_mode_grams``."""
    w, V = np.linalg.eigh(gram)
    N = canonical_basis(V[:, w <= FREE_TOLERANCE ** 2])
    return _summary([_describe(N[:, i], labels) for i in range(N.shape[1])])


def canonical_basis(N: np.ndarray) -> np.ndarray:
    """The free motions ``N`` (columns, orthonormal) as the basis that is 1 on one unit mode each
    and 0 on the others' (pivoted QR picks the modes; in the modes' order): a free translation
    along x and y and a turn about z read so, not as any mixtures of them that eigh returns for a
    multiple zero eigenvalue."""
    if N.shape[1] == 0:
        return N
    import scipy.linalg
    _, _, pivots = scipy.linalg.qr(N.T, pivoting=True)
    return N @ np.linalg.inv(N[np.sort(pivots[:N.shape[1]]), :])


def length_scale(model) -> float:
    """ℓ [m], the unit of length of the check: the beams' length.  A nodal vector of section
    degree d is measured in ℓ^(1−d) (r in ℓ, r_y and r_z as they are, r_yy in 1/ℓ), a gap in ℓ,
    so that the check does not depend on the model's size (in metres, the pressed strips'
    slider turned about x, held by supports of r_y and by the contact, violated them by 6.2e-4
    at 20 mm long and by 6.2e-5 at 2 mm, and was refused as free there)."""
    return max(float(np.ptp(beam.x_nodes)) for beam in model.beams)


def rigid_mode_gram(problem) -> tuple[np.ndarray, list[tuple[str, str, int]]]:
    """``rigid_mode_grams`` without the supports' own Gram matrix (collective)."""
    gram, _, labels = rigid_mode_grams(problem)
    return gram, labels


def rigid_mode_grams(problem) -> tuple[np.ndarray, np.ndarray, list[tuple[str, str, int]]]:
    """Gram matrix (6 n_beams)² of the constraint violations J·v of every beam's unit rigid modes
    (held rows, constraint rows divided by k_s; lengths in ℓ, ``length_scale``), and (beam,
    kind, axis) per mode, and the same without the contact constraints' rows (what the supports
    and a tangential layer hold).  Collective.

    J is applied to the modes of all beams of one colour at once (``beam_colours``: beams that
    share an interface differ): a held or constraint row belongs to at most one beam of a
    colour, so each beam's J·v is read off the colour's product.  Six products per colour
    instead of six per beam (the 37-fascicle bundle: 24 columns instead of 222)."""
    P = problem
    comm = P.comm.tompi4py()
    model, D = P.model, P.model.dofs_per_node
    nb = len(model.beams)
    pairs = [(i.a.index, i.b.index) for i in P.contact.interfaces] if P.contact else []
    colours = beam_colours(nb, pairs)
    n_col = int(colours.max()) + 1
    owner, rows = _row_beams(P)
    ell = length_scale(model)
    unit = np.tile(np.repeat([ell ** (i + j - 1.0) for i, j in model.block.monomials], 3), len(owner) // D)
    modes, norms = _unit_modes(P, owner, unit)
    V = np.zeros((len(owner), 6 * n_col))
    r = np.flatnonzero(owner >= 0)
    for m in range(6):                                   # unit modes, summed per colour
        V[r, 6 * colours[owner[r]] + m] = modes[r, m] / norms[owner[r], m]
    P.load_factor = 0.0
    X = P.q0.copy()
    lo, hi = P.layout.owned_nodes
    held = P.fixed_mask[D * lo:D * hi]
    constraint = np.repeat(~P.owned_physical, D) & ~held
    k_s = P.contact.stiffness if P.contact else 1.0
    scale = np.where(held, unit, 0.0) + np.where(constraint, 1.0 / (k_s * ell), 0.0)
    Vf = np.asfortranarray(V)                        # PETSc's dense storage; kept alive below
    Vmat = PETSc.Mat().createDense(((len(V), None), (None, V.shape[1])), array=Vf, comm=P.comm)
    Vmat.assemble()
    with _held_jacobian(P, X):
        JV = P.J.matMult(Vmat)
        layer = _layer_rows(P, norms) / ell
    # rigid modes give no strain: only the held and constraint rows are nonzero
    nz = np.flatnonzero(scale)
    JVs = JV.getDenseArray()[nz] * scale[nz, None]
    for obj in (X, Vmat, JV):
        obj.destroy()
    del Vf
    # Y: per row its beams' (at most two) six entries, sparse (rows × 6 n_beams)
    i_list, j_list, v_list = [], [], []
    for k in range(2):                                   # each beam a row belongs to
        b = rows[nz, k]
        i = np.flatnonzero(b >= 0)
        for m in range(6):
            i_list.append(i)
            j_list.append(6 * b[i] + m)
            v_list.append(JVs[i, 6 * colours[b[i]] + m])
    Y = sp.csr_matrix((np.concatenate(v_list), (np.concatenate(i_list), np.concatenate(j_list))),
                      shape=(len(nz), 6 * nb))
    Y_held = sp.vstack([Y[np.flatnonzero(held[nz])], layer])
    Y = sp.vstack([Y, layer])
    labels = [(beam.name, "translation" if m < 3 else "rotation", m % 3)
              for beam in model.beams for m in range(6)]
    return comm.allreduce((Y.T @ Y).toarray()), comm.allreduce((Y_held.T @ Y_held).toarray()), labels


def _unit_modes(P, owner: np.ndarray, unit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The six rigid modes of every owned row (n_local, 6), 0 on multiplier rows, and the norm of
    each beam's modes (n_beams, 6) in units of ℓ (``unit``: ℓ^(d−1) per DOF).  Collective."""
    x = P.q0.getArray(readonly=True).reshape(-1, P.model.dofs_per_node // 3, 3)
    modes = np.stack([v.ravel() for v in rigid_modes(x)], axis=1)
    modes[owner < 0] = 0.0
    norms = np.zeros((len(P.model.beams), 6))
    np.add.at(norms, owner[owner >= 0], (modes[owner >= 0] * unit[owner >= 0, None]) ** 2)
    norms = np.sqrt(P.comm.tompi4py().allreduce(norms))
    norms[norms == 0.0] = 1.0
    return modes, norms


def _layer_rows(P, norms: np.ndarray) -> sp.csr_matrix:
    """(3 P, 6 n_beams) sparse: per local contact point of a tangential law that ties the two
    beams by a stiffness at rest (the elastic matrix, ``couples_beams``) the tangential relative
    motion (I − n nᵀ)(u_A − u_B) of every unit rigid mode (``norms`` (n_beams, 6)), times
    sqrt(ω_p / A) (A the interface's area): its root mean square over the interface, like the
    weighted mean gaps of the contact rows, whatever k_t > 0 (the layer's stiffness on a mode
    compares with the beams', not with k_s: at k_t = 1e3 Pa/m the core's turn about z is held as
    stiffly by the layer as by its own bending).  Such a layer holds a beam pulled along its
    neighbour (the shear-lag core held only by it was refused as free).  Rigid modes move the
    touching points alike on both bodies: u = e_k (translation) or e_k × X_p (rotation) at the
    point's reference position X_p."""
    c = P.contact
    nb = len(P.model.beams)
    st = c.last_evaluation if c is not None else None
    terms = [t for t in (c.terms if c is not None else []) if t.couples_beams]
    if not terms or st is None or len(c.local) == 0:
        return sp.csr_matrix((0, 6 * nb))
    X = st.xA
    itf = c.points.itf[c.local]
    ends = np.array([[i.a.index, i.b.index] for i in c.interfaces])[itf]
    area = np.bincount(c.points.itf, c.points.w, minlength=len(c.interfaces))[itf]
    rows = np.arange(3 * len(X)).reshape(-1, 3)
    E = np.eye(3)
    blocks = []
    for t in terms:
        ev = st.terms[t.name]
        tangent = E[None] - ev.n[:, :, None] * ev.n[:, None, :]                # (P, 3, 3)
        scale = np.sqrt(ev.omega / area)
        i_list, j_list, v_list = [], [], []
        for m in range(6):
            u = np.broadcast_to(E[m], X.shape) if m < 3 else np.cross(E[m - 3], X)
            s = scale[:, None] * np.einsum("pij,pj->pi", tangent, u)
            for side, sign in ((0, 1.0), (1, -1.0)):
                b = ends[:, side]
                i_list.append(rows.ravel())
                j_list.append(np.repeat(6 * b + m, 3))
                v_list.append((sign * s / norms[b, m][:, None]).ravel())
        blocks.append(sp.csr_matrix((np.concatenate(v_list), (np.concatenate(i_list), np.concatenate(j_list))),
                                    shape=(3 * len(X), 6 * nb)))
    return sp.vstack(blocks).tocsr()


@contextmanager
def _held_jacobian(P, X):
    """P.J at X with every contact constraint active within the block, the unilateral law's too
    (at rest, pressure-free, its status has none active, and the check found the pressed strips'
    slider free along z).  After it the law's phase and status are as they were, and X is
    evaluated again under them (the state the solve starts from)."""
    c = P.contact
    held = c is not None and c.law.decides_activity
    kept = (c.law.phase, c.status.copy(), c.status_changes, c.law.memory()) if held else None
    if held:
        c.begin_phase(HELD)
    P.residual(None, X, P.F)                 # the contact projections of the reference state
    P.jacobian(None, X, P.J, P.J)
    try:
        yield
    finally:
        if held:
            c.begin_phase(kept[0])
            c.status[:], c.status_changes = kept[1], kept[2]
            c.law.recall(kept[3])
            P.residual(None, X, P.F)
            P.jacobian(None, X, P.J, P.J)


def _summary(motions: list[tuple[tuple[str, ...], str]]) -> list[str]:
    """One entry per group of beams: 'bar (free: translation along x, rotation about z)'."""
    groups: dict[tuple[str, ...], list[str]] = {}
    for beams, motion in motions:
        groups.setdefault(beams, []).append(motion)
    return [f"{' + '.join(beams)} (free: {', '.join(m)})" for beams, m in groups.items()]


def _describe(c: np.ndarray, labels: list) -> tuple[tuple[str, ...], str]:
    """(the beams that move, 'translation along x with rotation about x') of a null vector."""
    beams: dict[str, np.ndarray] = {}
    for coef, (name, kind, k) in zip(c, labels):
        beams.setdefault(name, np.zeros(6))[(3 if kind == "rotation" else 0) + k] = coef
    biggest = max(np.linalg.norm(b) for b in beams.values())
    moving = [name for name, b in beams.items() if np.linalg.norm(b) >= 0.2 * biggest]
    total = sum(beams[name] for name in moving)
    t, w = total[:3], total[3:]
    motion = []
    if np.linalg.norm(t) > 0.05 * np.linalg.norm(total):
        motion.append("translation along " + _direction(t))
    if np.linalg.norm(w) > 0.05 * np.linalg.norm(total):
        motion.append("rotation about " + _direction(w))
    return tuple(moving), " with ".join(motion) or "a rigid motion"


def _direction(d: np.ndarray) -> str:
    d = d / np.linalg.norm(d)
    k = int(np.argmax(np.abs(d)))
    if abs(d[k]) > 0.99:
        return AXES[k]
    return "(" + ", ".join(f"{x:+.2f}" for x in d) + ")"
