"""The load predictor of an increment: where Newton starts from at the next load factor.

From a converged state X(λ₀) the increment to λ₁ changes the loads by Δf = Σ_g Δm_g f_g and the
prescribed displacements by Δq̄ = Σ_g Δm_g ū_g (load groups, model/loading.py).  Two predictors
(``solver.predictor``):

* ``secant``: X + (Δλ / Δλ_last) ΔX_last, the last increment's change scaled (stepper.py).  Good
  for a proportional load, where the loads of the next increment grow along the same direction;
  on a load history it extrapolates the last frame's response to loads that no longer change
  that way (a muscle unloading while another loads), and where the loads stop changing it keeps
  moving the state (each frame's unchanged residual below the tolerance accepted it).
* ``tangent``: one Newton step at λ₁ from X with its held DOFs moved to q̄(λ₁), with the tangent
  the last converged solve factored (a chord step: no assembly or factorisation of its own, one
  residual evaluation and one back-substitution): the first-order response to the increment's own
  load change (non-proportional, unloading included, nothing when nothing changes).  J includes
  the contact constraints, so the multipliers are predicted with the state.  After a cut-back (the
  factor belongs to a failed attempt) or from rest there is no prediction.  Where Newton steps
  turn the sections (``solver.section_update: rotation``) a fibre model's prediction is turned too
  (``StepLimits.turned``): on the soft GOH sets' first levels (turns of 0.1–0.2 rad a sub-step)
  the linear step stretched the directors (alex 45° unilateral: 75 → 45 Newton iterations to
  200 N with the complementarity step turned as well).
The default (config/parse.py ``default_predictor``) is ``tangent`` for a load history (config
history:), whose frames change the loads' direction; for a model with a fibre-reinforced law, whose
path stiffens (the untwist of a soft matrix saturates, the fibres stiffen exponentially) so that
the secant of the last increment, scaled to a grown one, overshoots it (the GOH grid at twist
0/45/90°: 6899 → 5189 Newton iterations to 1.2 kN over 54 columns, docs/gait.md); and for a model
with contact (frictionless since 2026-12-02, with a tangential law since 2026-12-03): from the
secant's state the complementarity prediction changed constraints the level's answer did not (the
unilateral 90° column at 600 N: 4 changed, 3 of them back at the check, after 9 Newton iterations
on a state whose medial gastrocnemius was turned 8.7° from the answer). Over the envelope's
proportional grids the tangent took 13 and 22 % fewer Newton iterations (the paper's outlines at 4
and 8 elements; the second subject 5 % more), the columns over the target at twist ≤ 90° fell from
28 to 10, and as many cells fail (10; different ones where unilateral, docs/gait.md); Table 1's
sliding columns 45/45/47 → 40/38/40, answers equal to 7e-15 m. The Coulomb grid (μ 0.1–0.5) took
21 % fewer, the interface study's 52 friction and elastic-interface columns 17 % fewer (one
soleus-loaded μ = 3 column 7.7 times more, creeping toward a breakaway the secant jumps over,
docs/interface.md). Without contact ``secant`` (its direction is the path's, and it carries the
path's curvature from the last increment). A path the tangent follows continuously may stop at a
limit point a secant step jumps over (the lone soleus of the stiffest published GOH set stops at
its limit point near 99.5 N, where the secant path lands on a second stable branch and reaches
400 N: tests/solving/test_step_limits.py; the second subject's 120° gastrocnemius-biased sliding column
goes the other way: the secant met a fold at 2567 N, the tangent passed it, with the outlines as
traced before 2026-12-08), and a cold column
with it is about as cheap as a warm start from a sample 2 % away (37 against 39 Newton iterations,
tests/solving/test_samples.py).

**Unilateral contact** (the complementarity predictor of petsc/complementarity.py predicts each
increment's contact state): the increment after the first one from rest starts at the converged
state when that first increment formed the contact state (a constraint became active): it is no
step along the load path (the soleus lifts off in the first newtons), and extrapolating it lost
projections and cut back the second level on the gait envelope at twist 75-90 deg
(stepper.LoadStepper._contact_formed); the Josephy-Newton step from the converged state is then
the predictor.  A Josephy-Newton iteration that started from a predictor's state and loses its
predictions starts again from the converged state (solving/newton.py).
"""

from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from ..contact import forget_evaluation
from ..contact.partners import HISTORY


class TangentPredictor:
    """J⁻¹ of the load increment with the SNES's last factored tangent (module docstring);
    ``valid`` while that factor belongs to a converged state."""
    _valid: bool
    _growths: int                     # the contact pattern's growths when ``valid`` was set

    def __init__(self, problem, snes: PETSc.SNES):
        self.problem, self.snes = problem, snes
        self.valid = False

    @property
    def valid(self) -> bool:
        """The SNES's factor is a converged state's and still there.  The complementarity
        predictor assembles the Jacobian with the SNES, and where the contact pattern grows then
        (a point onto another B element) the SBAIJ preconditioner is reset (problem.py
        ``_contact_jacobian``); if the increment then converged with no Newton iteration, nothing
        factored again.  So no prediction after a growth until a converged state's factor
        (seen with a trial second-order predictor on the unilateral walking stride at twist 0°:
        PETSc's 'Preconditioner number of local rows -1', a traceback; an AIJ factor would
        survive a growth, but its prediction is given up too, in that rare frame).  Nor where the
        preconditioner holds no operators (reset and not set up since): a failed sub-step that grew
        the pattern, then a retry that converged with no Newton iteration, is accepted with the
        growth already counted (seen with a test law whose rest state was off equilibrium by the
        tolerance: the same PETSc error)."""
        return (self._valid and self._growths == self.problem.pattern_growths
                and self.snes.getKSP().getPC().getOperators()[0].getSize() == self.problem.J.getSize())

    @valid.setter
    def valid(self, value: bool) -> None:
        self._valid, self._growths = value, self.problem.pattern_growths

    def prime(self, X: PETSc.Vec, lam: float, previous_history: dict | None) -> None:
        """A restart: factor the tangent the interrupted run's last solve left, that of the
        increment which reached the restored state X at load factor ``lam``.  Its contact terms'
        history is the level before's (``previous_history``, the written fields; None: from rest,
        every history zero), not the restored level's own, to which the terms then return.
        Without it the first increment after a restart had no prediction, and a friction
        history went on along another path (a 13-frame μ = 0.3 stride cut back a later frame
        the uninterrupted run did not: the final probes up to 6 % apart).  X is the last iterate
        rather than the one before it, so the prediction agrees with the uninterrupted run's to
        the last Newton step's size (tests/solving/test_load_history.py).  Collective."""
        P = self.problem
        c = P.contact
        P.load_factor = lam
        terms = [] if c is None else c.terms
        kept = [{k: v.copy() for k, v in t.state.items()} for t in terms]
        for t in terms:
            t.set_state(previous_history if previous_history is not None else
                        {HISTORY + k: np.zeros_like(v) for k, v in t.state.items()})
        if c is not None:
            forget_evaluation(c)
            c.allow_update = False                # the restored active set (unilateral)
        J, Pmat, _ = self.snes.getJacobian()
        P.jacobian(self.snes, X, J, Pmat)
        ksp = self.snes.getKSP()
        ksp.setOperators(J, Pmat)
        ksp.setUp()
        for t, state in zip(terms, kept):
            t.state = state
            t.checkpoint()
        if c is not None:
            forget_evaluation(c)
        self.valid = True

    def predict(self, X: PETSc.Vec, lam1: float) -> bool:
        """X ← X − J⁻¹ F(X; λ₁) with the held DOFs of X at q̄(λ₁) first; False (X unchanged but
        for the held DOFs) without a valid factor, or when the residual or the step is not
        finite.  Collective (the decisions use global norms)."""
        if not self.valid:
            return False
        P = self.problem
        P.load_factor = lam1
        P.impose(X)
        if P.contact is not None:
            P.contact.allow_update = False        # the factor's active set (unilateral)
        F, dX = X.duplicate(), X.duplicate()
        try:
            P.residual(None, X, F)
            if not F.norm() < float("inf"):
                return False
            ksp = self.snes.getKSP()
            pc = ksp.getPC()
            pc.setReusePreconditioner(True)       # the SNES's factor, whatever the matrix holds now
            try:
                ksp.solve(F, dX)
            finally:
                pc.setReusePreconditioner(False)
            if ksp.getConvergedReason() <= 0 or not dX.norm() < float("inf"):
                return False
            P.limits.turned(X, dX)                # turned sections (solver.section_update)
            X.axpy(-1.0, dX)
            return True
        finally:
            F.destroy()
            dX.destroy()
