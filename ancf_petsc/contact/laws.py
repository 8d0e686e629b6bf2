"""Contact laws: the constraint rows of the multipliers and, for unilateral contact, which
constraints are active.

Both laws act on the weighted gaps ḡ_k and the scaled multipliers z_k of multipliers.py.  The
residual row of multiplier k is k_s R_k with

    active:   R = −ḡ_k   (the constraint ḡ_k = 0; z_k acts on the bodies)
    inactive: R = −z_k   (z_k = 0: no pressure; z_k leaves the forces)

(``Rows``: R, its derivatives, and the weights of z_k in the forces and in the Jacobian).

``SlidingLaw`` — the paper's (§5): the bodies stay together and slide without friction; every
multiplier is active and may have either sign (a pull holds the interface closed).

``UnilateralLaw`` — touching, free to separate: ḡ ≥ 0, z ≥ 0, z ḡ = 0 by an active-set strategy
inside Newton's iteration (a primal–dual active set, i.e. semismooth Newton on min(ḡ, z)); the
status is kept from one evaluation to the next: an active constraint is released when its
multiplier pulls, an inactive one activated when it penetrates.  Inactive multipliers leave the
forces, so the Jacobian stays symmetric.  The status is state of the law: the caller checkpoints
it with the converged load levels.

What makes the plain rule fail from 6–8 elements on (measured on the paper's tendon, docs/contact.md):

* **the first increment** from the exactly touching, pressure-free reference has to find the
  contact state of a scale-free problem whose Schur complement on the constraints has condition
  1e10–1e12 (the unloaded neighbours are compliant cantilevers); the rule needs 12–38 exact
  iterations at any scale constant and cycles on bundle_hex7, so halving the increment never
  helped.  The complementarity predictor (petsc/complementarity.py) solves that linearised
  problem exactly instead;
* **small violations far from the contact zone's edge** flip in early iterates, and the
  penetrations the first converged state leaves are then corrected all at once, with steps
  that wreck the state (residual 8 → 6 500 at 400 N, 12 elements).

So a Newton solve runs in ``phases`` (solving/stepper.py): status changes only for violations
beyond a band of 1e-2 × the largest |ḡ| (|z|), then 1e-3 … 1e-6 from each converged state, and
finally the exact rule (beyond the tie tolerance), each phase one SNES solve of up to
``snes_max_it`` (the law's default 60) Newton iterations while |F| still finds new lows.  In the exact phase the status changes by block
principal pivoting (Júdice & Pires 1994): every violated constraint flips while their number
falls, and after ``PATIENCE`` flips without a new least number only the violated constraint of
lowest index (Murty's rule, finite for the P-matrix problem of a stable tangent).  The answer
satisfies the exact conditions: the bands only choose the path to it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: the bands of the phases before the exact one: a status changes only for a penetration beyond
#: band · max|ḡ| or a pull beyond band · max|z| (scripts/bench_contact.py --grid measured 1e-2
#: alone, and 1e-2, 1e-4, 1e-6: this ladder takes the fewest Newton iterations)
BANDS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
#: block pivots without a new least number of violated constraints before a single pivot
PATIENCE = 3


@dataclass(frozen=True)
class Phase:
    """One SNES solve of a load increment: ``hold`` every constraint active (the sliding
    problem), ``probe`` no constraint row and every multiplier acting on the bodies (the tangent
    of the bodies alone, for petsc/complementarity.py), status changes beyond ``band``
    (relative), block principal pivoting."""
    name: str
    hold: bool = False
    probe: bool = False
    band: float = 0.0
    pivoting: bool = False


NEWTON = Phase("newton")
HELD = Phase("held", hold=True)
PROBE = Phase("probe", probe=True)


@dataclass
class Rows:
    """Per multiplier: the row function R (the residual row is k_s R), its derivatives, the
    weight ``load`` of the multiplier in the contact forces (and their curvature) and the weight
    ω of its column in the Jacobian (∂ forces / ∂z; ω = load but for a probe)."""
    R: np.ndarray
    dR_dg: np.ndarray
    dR_dz: np.ndarray
    omega: np.ndarray
    load: np.ndarray


def violated(gbar: np.ndarray, z: np.ndarray, active: np.ndarray, tol_g: float, tol_z: float) -> np.ndarray:
    """The constraints whose status the rule changes: an active one whose multiplier pulls
    (z < −tol_z), an inactive one that penetrates (ḡ < −tol_g)."""
    return (active & (z < -tol_z)) | (~active & (gbar < -tol_g))


def active_set_rows(gbar: np.ndarray, z: np.ndarray, active: np.ndarray, probe: bool = False) -> Rows:
    """Rows of an active set: ḡ = 0 where active, z = 0 elsewhere; a probe has z = 0 rows only
    and every multiplier acting on the bodies, without a column."""
    if probe:
        one, zero = np.ones(len(z)), np.zeros(len(z))
        return Rows(R=-z, dR_dg=zero, dR_dz=-one, omega=zero, load=one)
    w = active.astype(float)
    return Rows(R=np.where(active, -gbar, -z), dR_dg=np.where(active, -1.0, 0.0),
                dR_dz=np.where(active, 0.0, -1.0), omega=w, load=w)


class SlidingLaw:
    name = "sliding"
    decides_activity = False
    options: dict = {}                    # PETSc option defaults (solver's general ones)
    wander_window = None                  # PETSc's own convergence test (solving/cycle_stop.py)
    #: the first load increment from rest as a share of the first level (None: the level)
    first_increment = None

    def __init__(self):
        self.phase = NEWTON

    def phases(self, from_rest: bool) -> list[Phase]:
        return [NEWTON]

    def begin(self, phase: Phase) -> None:
        self.phase = phase

    def update(self, gbar, z, previous, tol, ids, owned, reduce) -> np.ndarray:
        return np.ones(len(gbar), dtype=bool)

    def memory(self) -> tuple:
        """What ``update`` remembers between calls (none), for ``recall``."""
        return ()

    def recall(self, memory: tuple) -> None:
        pass

    @staticmethod
    def describe() -> str:
        return "sliding (normal gap held at zero)"


class UnilateralLaw:
    name = "unilateral"
    decides_activity = True
    #: PETSc option defaults: an increment whose active set settles late needs more than the
    #: general 15 Newton iterations at any increment (halving it does not shorten the search, and
    #: the cut-backs creep into states no budget leaves).  Measured with the window below
    #: (docs/gait.md, 2026-11-29): the 4-element unilateral columns 39 of 39 complete (38 with
    #: 15), the traced second subject's 32 of 39 (30), 6 % and 13 % fewer Newton iterations
    options = {"snes_max_it": "60"}
    #: … while |F| finds new lows: a solve with none in this many iterations ends (the general
    #: budget of 15 before; solving/cycle_stop.py)
    wander_window = 15
    #: without the complementarity predictor (above its size: the held start) the contact state
    #: is found in a quarter of the first level (the soleus untwists and lifts off by 0.9 mm at
    #: 10 N at ψ = 45°: the full level failed at 8–16 elements); with it, in the whole first
    #: level but at most a quarter of the last (solving/stepper.py ``initial_path``)
    first_increment = 0.25

    def __init__(self):
        self.phase = NEWTON
        self.single_pivots = 0            # Murty steps taken in the run
        self._best = self._patience = 0
        self._flips: dict[int, int] = {}  # status changes per multiplier in this phase

    def phases(self, from_rest: bool) -> list[Phase]:
        return [Phase(f"band {b:g}", band=b) for b in BANDS] + [Phase("exact", pivoting=True)]

    def begin(self, phase: Phase) -> None:
        self.phase = phase
        self._best, self._patience = np.iinfo(np.int64).max, PATIENCE
        self._flips: dict[int, int] = {}

    def memory(self) -> tuple:
        """What ``update`` remembers between calls (the pivoting rule's patience, the banded
        phases' flips), for ``recall``: an update tried and taken back leaves no trace."""
        return self._best, self._patience, dict(self._flips), self.single_pivots

    def recall(self, memory: tuple) -> None:
        self._best, self._patience, flips, self.single_pivots = memory
        self._flips = dict(flips)

    def update(self, gbar: np.ndarray, z: np.ndarray, previous: np.ndarray, tol: float,
               ids: np.ndarray, owned: np.ndarray, reduce) -> np.ndarray:
        """The new status from the previous one: release on a pull, activate on a penetration
        (beyond the phase's band).  ``ids`` the multipliers' global ids, ``owned`` those this
        rank counts, ``reduce(values, op)`` combines values over the ranks ('max', 'min',
        'sum'; collective: every rank calls it in the same order)."""
        ph = self.phase
        if ph.hold:
            return np.ones(len(gbar), dtype=bool)
        if ph.probe:
            return previous.copy()
        scale = reduce(np.array([np.abs(gbar).max(initial=0.0), np.abs(z).max(initial=0.0)]), "max")
        tg, tz = max(tol, ph.band * scale[0]), max(tol, ph.band * scale[1])
        flip = violated(gbar, z, previous, tg, tz)
        if not ph.pivoting:
            # a banded phase only prepares the exact one: a constraint that would change its
            # status a third time (a cycle at the band's edge) keeps it for this phase
            again = np.array([self._flips.get(int(i), 0) >= 2 for i in ids[flip]], dtype=bool)
            flip[np.flatnonzero(flip)[again]] = False
            for i in ids[flip]:
                self._flips[int(i)] = self._flips.get(int(i), 0) + 1
        else:
            count = int(reduce(np.array([np.count_nonzero(flip & owned)]), "sum")[0])
            if count < self._best:
                self._best, self._patience = count, PATIENCE
            elif self._patience > 0:
                self._patience -= 1
            elif count > 0:
                mine = ids[flip].min() if np.any(flip) else np.iinfo(np.int64).max
                first = reduce(np.array([mine], dtype=np.int64), "min")[0]
                flip &= ids == first
                self.single_pivots += 1
        return previous ^ flip

    @staticmethod
    def describe() -> str:
        return "unilateral (gap >= 0, pressure >= 0; active set in Newton)"


LAWS = {"sliding": SlidingLaw, "unilateral": UnilateralLaw}


def make_law(mode: str):
    return LAWS[mode]()
