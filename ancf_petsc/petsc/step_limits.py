"""Limits on a Newton step before the line search takes it (SNES line-search pre-check): a step
that moves a node by more than a few section sizes is scaled down (a near-singular tangent gives
absurd steps; with contact the closest-point pairing holds only for steps small beside a
section, nor one that carries partner places across a fade band: ``contact/band_step.py``), a
step whose sections are turned (``section_rotation.py``) to a turn of about ``MAX_STEP_TURN``,
then halved until no Gauss point has det F below a floor (inverted elements) and no fibre law's
exponent k2 Ē² grows by more than ``MAX_EXPONENT_GROWTH`` (a strongly stiffening law: Newton's
linear step overshoots on the exponential).  The load predictor of an increment is
held to the same exponent growth (``limit_predictor``)."""
from __future__ import annotations

from contextlib import contextmanager

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from ..contact.band_step import band_moves
from ..physics import kernels
from ..physics.materials import determinant
from .section_rotation import SectionTurns

#: largest node move of one Newton step, in section sizes; full Newton steps with contact are
#: held to fewer (solving/stepper.py): a step of several sections makes the closest-point pairing
#: meaningless (the paper's tendon in fixed steps of 100 N from rest wandered to |F| ~ 1e8 and
#: failed with 10)
MAX_STEP_SECTIONS = 10.0
MAX_STEP_SECTIONS_CONTACT = 2.0
#: largest growth of a fibre law's exponent k2 Ē² at any Gauss point in one Newton step or load
#: predictor: the fibres' stiffness e^(k2 Ē²) grows by at most e^8 ≈ 3e3 per step.  With k2 =
#: 524.6 (the GOH set solver_default_2025) the first Newton step from rest stretched fibres to
#: Ē = 0.83, e^(k2 Ē²) ~ 1e157 (|F| overflow), and a secant predictor to |F| ~ 1e21 N, from which
#: Newton removes ~1 from the exponent per iteration (docs/fibres.md, "The published parameter
#: sets"); 2 and 8 both ran that lone soleus to 400 N, 8 with fewer Newton iterations
MAX_EXPONENT_GROWTH = 8.0
#: largest change of a direction vector r_y, r_z of any node in one turned Newton step
#: (``solver.section_update: rotation``), about the section's turn in radians: a larger linear
#: step leaves its fitted rotation unturned (``section_rotation.ROTATION_MAX``), and one
#: near-singular step asked for a 1.01 rad turn at |F| 0.2 N (soft GOH, docs/gait.md, thirty-fourth
#: session); held to 0.1, every step of the soft sets' first levels is turned
MAX_STEP_TURN = 0.1
#: a band-limited step's scale is rounded to the grid 2^(k / BAND_GRID) (a 4.4 % spacing): each
#: rank's rounding of the same Newton step moved the band ratio by ~1e-10, and the 3-rank run of
#: the second subject's 90° stride left the serial path in frame 1 (states 1.2e-8 m apart); on the
#: grid frames 1-13 equal serial to 1e-17 m on 2 and 3 ranks (tests/parallel/test_mpi.py)
BAND_GRID = 16


def min_jacobian(problem, X: PETSc.Vec) -> float:
    """Smallest det F over every Gauss point of every rank (collective)."""
    xl = problem.exchange.local_state(X)
    local = np.inf
    for blk in problem.blocks:
        F = kernels.deformation_gradient(blk.element_vectors(xl), blk.G)
        local = min(local, float(np.min(determinant(F))))
    val = problem.comm.tompi4py().allreduce(local, op=MPI.MIN)
    return val if np.isfinite(val) else -np.inf


def _stiff_fibres(law) -> bool:
    """A law whose fibres carry stress (GOH, also under ``locking: mixed``), not one with k1 = 0
    (fibres off: its model ran 5x the matrix's Newton iterations under the fibres' limits)."""
    return hasattr(law, "fibre_exponent") and getattr(getattr(law, "law", law), "k1", 0.0) != 0.0


def fibre_exponents(problem, X: PETSc.Vec) -> np.ndarray:
    """k2 Ē² at every Gauss point of this rank's parts with a fibre law (``fibre_exponent``), in a
    fixed order (empty without fibres)."""
    xl = problem.exchange.local_state(X)
    out = [np.zeros(0)]
    for blk in problem.blocks:
        for G, _, material in blk.parts:
            if hasattr(material, "fibre_exponent"):
                F = kernels.deformation_gradient(blk.element_vectors(xl), G)
                out.append(material.fibre_exponent(F).ravel())
    return np.concatenate(out)


def quantised(ratio: float) -> float:
    """A positive ``ratio`` rounded up to the grid 2^(k / ``BAND_GRID``), so that the ranks'
    rounding of one step (band moves ~1e-10 apart) scales it alike; 0 stays 0."""
    if ratio <= 0.0:
        return ratio
    return float(2.0 ** (np.ceil(np.log2(ratio) * BAND_GRID) / BAND_GRID))


class StepLimits:
    """The pre-check of ``problem``'s Newton steps: at most ``sections`` section sizes per node,
    det F ≥ ``j_min`` and fibre exponents growing by at most ``MAX_EXPONENT_GROWTH`` (halved up
    to ``halvings`` times)."""

    def __init__(self, problem, j_min: float = 0.1, halvings: int = 12):
        self.problem, self.j_min, self.halvings = problem, j_min, halvings
        self.sections = MAX_STEP_SECTIONS
        self.turns: SectionTurns | None = None      # Newton steps turn the sections (section_rotation.py)
        self.band_step = 0.0               # fade-band widths a full Newton step with contact may carry a
                                           # partner place (``solver.band_step``; 0: no limit)
        self._local: PETSc.Vec | None = None
        self.size = min(np.sqrt(b.section.area) for b in problem.model.beams)
        self.fibres = False                # a law whose fibres carry stress, on some rank
        self.find_fibres()

    def find_fibres(self) -> None:
        """Whether some rank's laws have fibres that carry stress (collective); again after the
        laws changed in place (a calibration's samples: k1 from 0 to > 0)."""
        local = any(_stiff_fibres(m) for blk in self.problem.blocks for _, _, m in blk.parts)
        self.fibres = bool(self.problem.comm.tompi4py().allreduce(int(local), op=MPI.MAX))

    def configure(self, min_det_f: float, section_update: str, linesearch: str,
                  band_step: float = 0.0) -> bool:
        """Set the det F floor (0: none), whether Newton steps turn the sections
        (``solver.min_det_f``, ``solver.section_update``) and, with contact and full Newton steps
        (``linesearch`` basic), the tighter section-size limit; returns whether the pre-check has
        anything to do.  Steps are turned only where the line search takes them whole: the turn
        adds the second-order part of the step's rotation, which a line search's step λ·Y would
        scale by λ instead of λ² (friction's l2 line search, measured: the columns at ψ ≤ 90°
        over 60 Newton iterations rose from 4 to 11 with turned steps)."""
        full = linesearch == "basic"
        self.turns = SectionTurns(self.problem) if section_update == "rotation" and full else None
        self.j_min = min_det_f if min_det_f > 0.0 else -np.inf
        contact_full = self.problem.contact is not None and full
        if contact_full:
            # full Newton steps with contact: the pairing holds for steps small beside a section
            self.sections = MAX_STEP_SECTIONS_CONTACT
        self.band_step = band_step if contact_full else 0.0
        return min_det_f > 0.0 or self.turns is not None or self.band_step > 0.0

    def turned(self, X: PETSc.Vec, Y: PETSc.Vec) -> bool:
        """Turn the sections of the whole update X − Y of a model with a fibre law where Newton
        steps turn them (``section_rotation.py``): the tangent load predictor's and the
        complementarity predictor's steps, neither line-searched nor scaled to ``MAX_STEP_TURN``
        (a step that turns a node by more than ``ROTATION_MAX`` stays linear).  Their linear turns
        stretched the soft GOH sets' directors as Newton's did (docs/gait.md, thirty-fifth
        session).  Not without fibres: the paper's neo-Hookean column with turned Newton steps
        (opt-in) took 39 → 41 Newton iterations with turned predictions.  Whether Y changed
        (collective)."""
        return self.fibres and self.turns is not None and self.turns(X, Y)

    @contextmanager
    def straight(self):
        """Newton steps taken straight (not turned, no turn limit) within the block: for solves
        from states far from equilibrium, outside the asymptotic regime the turn is made for
        (branch_switch.py)."""
        turns, self.turns = self.turns, None
        try:
            yield
        finally:
            self.turns = turns

    def exponents(self, X: PETSc.Vec) -> np.ndarray | None:
        """``fibre_exponents`` at X, the start ``exponent_growth`` measures from (None without
        fibres: no growth to hold)."""
        return fibre_exponents(self.problem, X) if self.fibres else None

    def exponent_growth(self, start: np.ndarray | None, trial: PETSc.Vec) -> float:
        """Largest growth of k2 Ē² from ``start`` (``fibre_exponents`` at the step's start) to
        the state ``trial``, over every rank (collective; 0 without fibres)."""
        if start is None:
            return 0.0
        with np.errstate(invalid="ignore"):
            local = float(np.max(fibre_exponents(self.problem, trial) - start, initial=0.0))
        local = local if not np.isnan(local) else np.inf
        return self.problem.comm.tompi4py().allreduce(local, op=MPI.MAX)

    def precheck(self, X: PETSc.Vec, Y: PETSc.Vec) -> bool:
        """Line-search pre-check (collective): scale the step X − Y down to ``sections``
        section sizes (a turned step also to direction-vector changes of ``MAX_STEP_TURN``),
        then halve it until no Gauss point has det F below ``j_min`` and no fibre exponent grows
        by more than ``MAX_EXPONENT_GROWTH``; if that fails, Y is filled with NaN so that SNES
        reports a domain failure and the load step is cut back.  Returns whether Y was changed."""
        P = self.problem
        y = Y.getArray(readonly=True).reshape(-1, P.model.block.vectors_per_node, 3)[P.owned_physical]
        move = np.abs(y[:, 0]).max(initial=0.0) / (self.sections * self.size)
        turn = 0.0                          # and a turned step to MAX_STEP_TURN
        if self.turns is not None:
            turn = np.linalg.norm(y[:, 1:3], axis=2).max(initial=0.0) / MAX_STEP_TURN
        local = np.array([move, turn, self.band_moves(X, Y)])      # one reduction for all
        P.comm.tompi4py().Allreduce(MPI.IN_PLACE, local, op=MPI.MAX)
        big = float(local.max())
        changed = False
        if big > 1.0:
            Y.scale(1.0 / big)
            changed = True
        if self.turns is not None and self.turns(X, Y):
            changed = True
        start = self.exponents(X)
        trial = X.duplicate()
        try:
            for _ in range(self.halvings):
                X.copy(trial)
                trial.axpy(-1.0, Y)
                if ((self.j_min == -np.inf or min_jacobian(P, trial) >= self.j_min)
                        and self.exponent_growth(start, trial) <= MAX_EXPONENT_GROWTH):
                    return changed
                Y.scale(0.5)
                changed = True
            Y.set(np.nan)
            return True
        finally:
            trial.destroy()

    def band_moves(self, X: PETSc.Vec, Y: PETSc.Vec) -> float:
        """This rank's largest move of a partner place through a fade band by the step X − Y, over
        ``band_step`` band widths (contact/band_step.py); 0 without the limit, or where the
        contact's last evaluation was not at X."""
        c = self.problem.contact
        if self.band_step <= 0.0:
            return 0.0
        ex = self.problem.exchange
        if self._local is None or self._local.getSize() != ex.xloc.getSize():
            if self._local is not None:             # the exchange was rebuilt for new contact pairs
                self._local.destroy()
            self._local = ex.xloc.duplicate()
        free = np.ones(self._local.getLocalSize(), dtype=bool)
        free[ex.held_local] = False
        ex.scatter.scatter(X, self._local, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
        st = c.last_evaluation
        if st is None or not np.array_equal(self._local.getArray()[free], st.xl.reshape(-1)[free]):
            return 0.0
        ex.scatter.scatter(Y, self._local, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
        step = np.where(free, -self._local.getArray(), 0.0)
        return quantised(band_moves(c, step.reshape(st.xl.shape)) / self.band_step)

    def limit_predictor(self, X0: PETSc.Vec, X: PETSc.Vec) -> int:
        """Halve the load predictor's move X − X0 (X0 the converged state) until no fibre exponent
        grows by more than ``MAX_EXPONENT_GROWTH`` (at most ``halvings`` times; collective).
        Returns the number of halvings."""
        if not self.fibres:
            return 0
        start = fibre_exponents(self.problem, X0)
        n = 0
        while n < self.halvings and self.exponent_growth(start, X) > MAX_EXPONENT_GROWTH:
            X.axpy(1.0, X0)
            X.scale(0.5)                # X0 + (X − X0)/2
            n += 1
        return n
