"""A branch switch taken while the cut-backs still creep towards the branch point, not after
every halving (issue 38; docs/running.md, "Branch switching").

A sub-step that converges on a less stable state (a bifurcation was passed within it) is cut
back: smaller steps may stay on a stable path.  Where they do not, each halving creeps nearer the
critical point, where the tangent is nearly singular and Newton converges only linearly, and
fails there; the switch from the branch point (branch_switch.py) was tried only when the
increments reached ``solver.min_increment``.  Measured on the second subject's sliding 90°
gastrocnemius-biased column (4 elements, the outlines started at their farthest vertex): the
step 1000 → 1200 N converged on a saddle, and the cut-backs crept to 1034.02 N in 31 failures
(480 Newton iterations) before the switch from the 1200 N state took 15; with this rule the
level takes 238 (14 cut-backs: the last converged state reads as critical from the 14th).

From the level's ``CREEP_FAILURES``-th failed attempt after the saddle was met on, where the
last converged state is at or near a critical point (critical_point.py: the scaled tangent's
smallest eigenvalue below ``ISOLATED`` of the next; the cut-backs creep towards the bifurcation,
not through a hard stretch of a stable path), the switch is tried at once, from the same branch
point and so to the same state; where it finds no stable state the cut-backs go on as before
(the point is then tried, and not tried again).
"""
from __future__ import annotations

from .critical_point import critical_point
from .step_over import CREEP_FAILURES


def switch_early(stepper, path, X_prev, target: float, tally) -> bool:
    """Count a failed sub-step after the level's first less stable state (``tally.unstable_at``);
    from the ``CREEP_FAILURES``-th on, where the last converged state (in ``problem.X``) is near a
    critical point, switch from the pending branch point (``BranchSwitch.take``) and return True
    when the path goes on from the stable state it reached.  Collective; the same on every rank."""
    if tally.unstable_at is None:
        return False
    tally.after_unstable += 1
    if tally.after_unstable < CREEP_FAILURES or stepper.branches.pending(path.lam) is None:
        return False
    critical = critical_point(stepper, path.lam)
    if critical is None:
        return False
    critical.destroy()
    return stepper.branches.take(stepper, path, X_prev, target, tally, resume=False)
