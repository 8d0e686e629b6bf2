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
after later ones).  Where the estimate was too hopeful a Newton step follows: one residual
evaluation more.
"""
from __future__ import annotations

#: share of the convergence tolerance the chord step's estimated residual must stay below: with
#: 0.1 the Table 1 columns keep their Newton counts (the unilateral ψ = 0° one takes one more)
#: with 6-7 chord steps each when sliding (docs/running.md)
CHORD_MARGIN = 0.1


class TangentReuse:
    """Per Newton iteration: may the last factored tangent serve?  The decision uses only the
    global residual norms, so it is the same on every rank."""

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self.count = 0                 # chord steps taken in the run
        self._reused = False

    def start_solve(self) -> None:
        """A new SNES solve: its first two iterations factor their own tangents."""
        self._reused = False

    def decide(self, history: list[float], atol: float, rtol: float) -> bool:
        """Whether this iteration reuses the tangent; ``history`` holds ‖F_0‖ … ‖F_k‖ of the
        solve so far."""
        reuse = (self.enabled and len(history) >= 3 and not self._reused and history[-2] > 0.0
                 and 2.0 * history[-1] ** 2 / history[-2] <= CHORD_MARGIN * max(atol, rtol * history[0]))
        self._reused = reuse
        self.count += reuse
        return reuse
