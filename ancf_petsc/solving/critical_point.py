"""Why load control stopped: a critical point of the load path (issue 38; docs/gait.md).

Load control follows the equilibria F(q, λ) = 0 as λ grows.  At a limit point λ_f the path
turns back: beyond it there is no equilibrium near the last one, and Newton fails at every
increment down to the smallest whatever the solver does (a load-controlled structure snaps
there).  At a bifurcation point the tangent is singular as well.  Both show in the tangent at
the last converged states: one eigenvalue of a mode of the beams falls to zero while the others
stay.  Measured on the soft-matrix GOH set ``alex``, twist 120°, soleus-biased, unilateral (the
fibre grid of scripts/bench_envelope.py): the smallest eigenvalue of the diagonally scaled
tangent was 5.4e-6 at 7.2418 N, 1.35e-6 at 7.2701 N and 3.6e-7 at 7.2715 N against 1.1e-4 for
the next at all three, its square falling linearly to zero at 7.2717 N (a fold: μ ∝ √(λ_f − λ));
the run stopped at 7.27168 N with "Newton found no |F| below 1.06e-06 N in its last 15
iterations".

``critical_point`` reads the tangent at the last converged state when a run gives up.  It is
scaled by its diagonal (|diag|^−1/2 on both sides, 1 on the multipliers' empty diagonal: the
nodal vectors' units, m for r against 1 for r_y, would otherwise decide which eigenvalue is
small); where its smallest eigenvalue in magnitude (singular value for an unsymmetric tangent,
``contact.fade_forces: pointwise`` or friction) is below ``ISOLATED`` of the next and its mode
lies on the beams' nodes (``NODE_SHARE``: not a redundant contact constraint's), that state is
at or near a critical point.  The stepper then snaps as a load-controlled structure does: the
branch switch from that state along the mode to load factors just beyond it
(branch_switch.py ``BranchSwitch.snap``, ``SNAP_STEPS``, ``SNAP_AMPLITUDES``), keeping a stable
state it reaches; where there is none the failure message names the critical point
(``CriticalPoint.sentence``).  Over the gait envelope (docs/gait.md, sixteenth session) the snap
took the second subject's sliding columns at 105°, 120° and 180° past critical points at
1.9–2.7 kN to stable states 0.24–0.63 mm away and on to 3 kN; none of the 21 soft-matrix columns
that stop found a stable state beyond theirs.  Dense, on rank 0, up to ``DENSE_LIMIT`` free DOFs
(one Jacobian and one eigendecomposition per give-up: 0.2 s at 630 rows); larger models are not
examined.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc

from ..linalg.options import DEFAULT_OPTIONS
from .branch_switch import DENSE_LIMIT, NODE_SHARE, matrix_on_zero, node_rows, oriented_mode, scattered
from .snes_solver import absolute_tolerance

#: run tolerances this many times the defaults' or looser leave a state whose rise in negative
#: eigenvalues is polished before it is believed (``verdict_count``)
LOOSE = 10.0

#: the smallest scaled eigenvalue counts as a critical point's below this share of the next
#: (0.0033 at the alex fold above, 0.05 there 0.03 N before it; 0.9 far from it): at or near one
ISOLATED = 0.1


@dataclass
class CriticalPoint:
    """A converged state at a critical point: its load factor, the scaled tangent's smallest
    eigenvalue over the next (``share``), that eigenvalue and its mode over every DOF (unscaled,
    oriented as branch_switch's modes)."""
    load_factor: float
    share: float
    eigenvalue: float
    mode: PETSc.Vec

    def sentence(self, tried: bool) -> str:
        """The failure message's addition where no snap passed it (``tried``: one was tried)."""
        return (f"; the tangent at the last converged state (load factor {self.load_factor:.6g}) is nearly "
                f"singular: its smallest eigenvalue, diagonally scaled, is {self.share:.1e} of the next, "
                "an isolated mode of the beams, so the load path is at or near a critical point there (a "
                "limit point, where it turns back, or a bifurcation), which load control cannot pass"
                + ("; no stable state was found just beyond it along that mode" if tried else ""))

    def destroy(self) -> None:
        self.mode.destroy()


def singular_mode(A: np.ndarray, mechanical: np.ndarray) -> tuple[float, float, np.ndarray] | None:
    """(share, eigenvalue, mode) of the diagonally scaled ``A``: its smallest eigenvalue
    magnitude (singular value where ``A`` is not symmetric) over the next smallest, that
    eigenvalue and its vector in ``A``'s own unknowns; None where the vector has less than
    ``NODE_SHARE`` of its squared norm on the ``mechanical`` rows."""
    d = np.abs(np.diag(A))
    scale = 1.0 / np.sqrt(np.where(d > 0.0, d, 1.0))
    S = A * scale[:, None] * scale[None, :]
    if np.max(np.abs(S - S.T), initial=0.0) <= 1e-12 * np.max(np.abs(S), initial=0.0):
        w, V = np.linalg.eigh(S)
        magnitude = np.abs(w)
    else:
        _, w, Vt = np.linalg.svd(S)
        magnitude, V = w, Vt.T
    order = np.argsort(magnitude)
    first = order[0] if len(order) else 0
    if len(order) < 2 or magnitude[order[1]] <= 0.0 or np.sum(V[mechanical, first] ** 2) < NODE_SHARE:
        return None
    return float(magnitude[first] / magnitude[order[1]]), float(w[first]), scale * V[:, first]


def critical_point(stepper, lam: float) -> CriticalPoint | None:
    """The converged state in ``problem.X`` (load factor ``lam``) as a critical point (module
    docstring), or None.  Collective; the same on every rank."""
    P = stepper.problem
    tangent = stepper.solver.tangent_at(P.X)
    if tangent is None:                             # -snes_mf: no matrix to read
        return None
    A = matrix_on_zero(tangent)
    P.restore()                 # the contact state the evaluation moved to rounding: the checkpoint's
    found = None
    if P.comm.rank == 0:
        free = ~P.fixed_mask
        if 2 <= int(free.sum()) <= DENSE_LIMIT:
            found = singular_mode(A[free][:, free].toarray(), node_rows(P, free))
            if found is not None and found[0] < ISOLATED:
                found = (found[0], found[1], oriented_mode(P, free, found[2]))
            else:
                found = None
    found = P.comm.tompi4py().bcast(found, root=0)
    return None if found is None else CriticalPoint(lam, found[0], found[1], scattered(P, found[2]))


def verdict_count(stepper, path, step: float, tally, converged: bool) -> int | None:
    """The negative tangent eigenvalues of a sub-step's state (None unless ``converged``).  Where
    they rose above the last accepted state's and the run's ``-snes_atol`` or ``-snes_rtol`` is
    ``LOOSE`` times the default or looser, the state is first polished by Newton at the same load
    to the default tolerances (its iterations and |F| in ``tally``) and counted again: off
    equilibrium by a loose tolerance, the unbalanced load on a nearly singular mode reads as a
    negative eigenvalue (configs/uniaxial_neohookean.yaml, whose free end's warping is a null
    pivot, at -snes_atol 1e-3: 38 cut-backs and 10 branch switches 'at a bifurcation' in a tension
    test, 1 236 Newton iterations against the default's 31).  At the default tolerances a rise
    without contact is counted again on the state's own tangent: the last factor is an earlier
    iterate's (chord steps near convergence), and a neo-Hookean bar of radius 2 mm and L = 1 m,
    stretched 23 % in one step, read 1-2 negative eigenvalues there (−5e-5 against +4.5e-7 at the
    state) and was cut back 4 times: 35 Newton iterations against 10.  With contact the last
    factor's count stands (not re-checked on the tendon runs).  A state a loose ``-snes_rtol``
    accepted with |F| above that share of the loads is polished first (``loose_relative``).
    Collective."""
    S, P = stepper.solver, stepper.problem
    tally.polished = None
    rtol, atol, _, _ = S.snes.getTolerances()
    default_rtol, default_atol = float(DEFAULT_OPTIONS["snes_rtol"]), absolute_tolerance(S.load_norm, S.rounding_floor)
    if converged and loose_relative(S, rtol, atol):
        _polish(stepper, path, step, tally, default_rtol, max(atol, rtol * S.load_norm))
    neg = S.negative_eigenvalues(P.X) if converged else None
    if not neg or neg <= path.accepted_negative:
        return neg
    if atol < LOOSE * default_atol and rtol < LOOSE * default_rtol:   # on the state's own tangent
        return neg if P.contact is not None else S.negative_eigenvalues(P.X, own=True)
    if not _polish(stepper, path, step, tally, min(rtol, default_rtol), min(atol, default_atol)):
        return neg                                  # the loose state and its count stand
    polished = S.negative_eigenvalues(P.X)
    return neg if polished is None else polished


def loose_relative(S, rtol: float, atol: float) -> bool:
    """Whether the solve just ended on a -snes_rtol looser than the default with |F| above ``rtol``
    times the loads' size: PETSc's relative test is against the solve's first |F|, which a
    predictor far off inflates (configs/elastica_svk.yaml at -snes_rtol 1e-2: the last level
    accepted with |F| 511 N on a 5 N load, the tip at (-0.652, 0.837) m against (-0.388, 0.713),
    'completed').  Under displacement control alone (no loads to measure against: the tip held
    at 0.7 m, reaction 142 N against 4.64 N) the run's absolute tolerance is the share."""
    return (S.snes.getConvergedReason() == PETSc.SNES.ConvergedReason.CONVERGED_FNORM_RELATIVE
            and rtol > float(DEFAULT_OPTIONS["snes_rtol"])
            and S.snes.getFunctionNorm() > max(atol, rtol * S.load_norm))


def _polish(stepper, path, step: float, tally, rtol: float, atol: float) -> bool:
    """Newton again at the sub-step's load from its state, at ``rtol`` and ``atol`` (its iterations
    and |F| into ``tally``); False, the state restored, where it does not converge.  Collective."""
    S, P = stepper.solver, stepper.problem
    old_rtol, old_atol, _, _ = S.snes.getTolerances()
    S.snes.setTolerances(rtol=rtol, atol=atol)
    loose, kept = P.X.copy(), stepper.history       # the level's residual norms (newton_history)
    try:
        reason, its, fnorm = stepper.solve_at(path.lam + step, P.X, path.lam + step, path.lam, unchanged=True)
        kept.extend(stepper.history)
        stepper.history = kept
        tally.its += its
        if reason <= 0:
            loose.copy(P.X)
            return False
    finally:
        S.snes.setTolerances(rtol=old_rtol, atol=old_atol)
        loose.destroy()
    tally.polished = fnorm                          # the level reports the polished state's |F|
    return True
