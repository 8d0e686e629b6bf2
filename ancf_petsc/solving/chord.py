"""Chord steps near convergence (``solver.reuse_tangent``): a Newton step that reuses the tangent
factored at the previous iterate when that is predicted to converge.

Near a solution a Newton step leaves the residual of the tangent's curvature, ‖F_{k+1}‖ ≈ ½ L ‖δ_k‖²
(δ the step, ‖δ_k‖ ∝ ‖F_k‖), so the last step measured L ∝ 2 ‖F_k‖ / ‖F_{k−1}‖².  A step with the
tangent factored at the previous iterate (a chord step) leaves instead the change of the tangent
along the last step times this one, L ‖δ_{k−1}‖ ‖δ_k‖: about 2 ‖F_k‖² / ‖F_{k−1}‖.  When that
estimate is below ``CHORD_MARGIN`` of the convergence tolerance the step reuses the factored
tangent: one assembly and factorisation less, typically on the last step of a load level.  Never
twice in a row, and only from the third iterate of a solve on: ‖F_0‖ is the load increment's
residual, whose first Newton step removes it almost linearly, so ‖F_1‖ / ‖F_0‖ says nothing of the
curvature (measured: 115 of 295 chord steps taken after the first step did not converge, 3 of 155
after later ones).  Nor after a step that raised the residual (‖F_{k−1}‖ ≥ ‖F_{k−2}‖): ‖δ_{k−1}‖ is
then not ∝ ‖F_{k−1}‖ (the walking stride's loading frames, ‖F‖ 24, 0.06, 0.24, 6e-6: the chord
step left 3e-7 against the estimate's 3e-10, and 7 of its 209 Newton iterations were such
misses).  Where the estimate was too hopeful a Newton step follows: one residual evaluation more.

With the fascicle Schur preconditioner (``solver.linear: fieldsplit``) a Krylov method solves the
freshly assembled Jacobian, so the preconditioner may lag where a direct solve may not: from the
third iterate on, after a step that cut the residual by ``KEEP_CONTRACTION`` or more, the fascicle
factors and the multiplier Schur factor of the previous iterate are kept (not twice in a row).  The
Newton step stays exact; on the 37-fascicle bundle FGMRES took the same 83 iterations with 2 of 9
set-ups skipped (docs/running.md).
"""
from __future__ import annotations

#: share of the convergence tolerance the chord step's estimated residual must stay below: with
#: 0.1 the Table 1 columns keep their Newton counts (the unilateral ψ = 0° one takes one more)
#: with 6-7 chord steps each when sliding (docs/running.md)
CHORD_MARGIN = 0.1
#: a step that cut the residual by this factor or more lets the next one keep the fieldsplit
#: preconditioner's factors (module docstring)
KEEP_CONTRACTION = 1e-2


class TangentReuse:
    """Per Newton iteration: may the last factored tangent serve?  The decisions use only the
    global residual norms, so they are the same on every rank.  ``preconditioner``: the fascicle
    Schur context (``keep_factors`` is set on it), or None for a direct solve."""

    def __init__(self, enabled: bool, preconditioner=None):
        self.enabled = enabled
        self.preconditioner = preconditioner
        self.count = 0                 # chord steps taken in the run
        self.kept = 0                  # fieldsplit set-ups skipped in the run
        self._reused = self._kept = False

    def start_solve(self) -> None:
        """A new SNES solve: its first two iterations factor their own tangents."""
        self._reused = self._kept = False

    def jacobian(self, snes, history: list[float], assemble) -> None:
        """The SNES Jacobian callback's work: nothing for a chord step (the untouched matrix
        keeps PCSetUp from refactoring), else ``assemble()``, telling a fieldsplit
        preconditioner whether to keep its factors."""
        rtol, atol, _, _ = snes.getTolerances()
        if self.decide(history, atol, rtol):
            return
        if self.preconditioner is not None:
            keep = (self.enabled and len(history) >= 3 and not self._kept
                    and history[-1] <= KEEP_CONTRACTION * history[-2])
            self._kept = keep
            self.kept += keep
            self.preconditioner.keep_factors = keep
        assemble()

    def decide(self, history: list[float], atol: float, rtol: float) -> bool:
        """Whether this iteration reuses the tangent; ``history`` holds ‖F_0‖ … ‖F_k‖ of the
        solve so far."""
        reuse = (self.enabled and len(history) >= 3 and not self._reused and 0.0 < history[-2] < history[-3]
                 and 2.0 * history[-1] ** 2 / history[-2] <= CHORD_MARGIN * max(atol, rtol * history[0]))
        self._reused = reuse
        self.count += reuse
        return reuse
