"""The whole partner beam as every contact point's search window, where a level cannot be
reached because a point slid out of its window at every increment.

A contact point's closest point may move ``contact.search_margin`` of the partner beam per load
step (contact/projection.py, a window of B elements centred on its converged partner element); an
iterate that carries it farther fails the solve (``DIVERGED_FNORM_NAN``, "contact projection
lost") and the step is cut back.  The window is a guard against Newton's wild iterates, not part of
the model: the projection descends from the point's last place whatever the window, and the
window only decides whether its result is accepted.  Near a limit or bifurcation point the
Newton steps from the last converged state are large at every increment, and the guard then stops
the run (docs/gait.md: the unilateral soleus-biased stride at 165°, the 8-element columns at
165°/180°).  There, after a pending branch switch and before the snap past a critical point
(stepper.last_resorts: the window changes no equation, so it comes before a jump), the window
becomes the whole partner beam (``WHOLE``) for the rest of the run, and the level is started
again with the increment of its first attempt; the accepted states are judged as every other
(residual, conditions, stability).  Logged, in summary.json (``search_window_whole_from``), the
final message, results.h5 and the restart data (a restart widens again).
"""
from __future__ import annotations

#: a search margin whose window is every element of the partner beam (projection.window_width)
WHOLE = 1.0


def whole_windows(projector) -> bool:
    """Whether every point's window is its whole partner beam (contact/projection.py)."""
    return all(projector.window_width(i) >= i.b.n_elements for i in projector.interfaces)


def widen(projector, margin: float) -> None:
    """Every point's window ``margin`` of the partner beam from now on, centred on its partner
    element at the last converged state (where the projector's places are at a give-up and after
    a restart's ``restore_state``); later checkpoints keep the margin."""
    projector.search_margin = margin
    projector.lo, projector.hi = projector.window_around(projector.eB, projector.points.itf)


class WindowWidening:
    """The stepper's one widening of the contact points' search windows (``at``: the last
    converged load factor when it was made, None before)."""

    def __init__(self, problem):
        self.contact = problem.contact
        self.at: float | None = None

    def take(self, stepper, path, tally, lost: bool) -> bool:
        """At a give-up whose last attempt lost a contact point from its window (``lost``, the
        same on every rank): widen (logged) and start the level again from ``path`` with the
        increment of its first attempt; False when widened already or nothing to widen."""
        c = self.contact
        if not lost or c is None or self.at is not None or whole_windows(c.projector):
            return False
        before = c.projector.search_margin
        self.widen_from(path.lam)
        stepper.log(f"  load factor {path.lam:.6g}: a contact point slid out of its search window "
                    f"({before:g} of the partner beam per load step) at every increment; on with the "
                    "whole partner beam as every point's window (the Newton steps from the last converged "
                    "state are large, as near a limit or bifurcation point)")
        tally.consecutive = 0
        path.dlam = tally.first_failed or path.dlam
        return True

    def widen_from(self, at: float) -> None:
        """The whole partner beam as every window from the load factor ``at`` on."""
        widen(self.contact.projector, WHOLE)
        self.at = at

    def resume(self, at: float | None) -> None:
        """A restart of a run that widened at ``at`` (None: it did not) widens again."""
        if at is not None and self.contact is not None:
            self.widen_from(at)

    def summary(self) -> dict:
        """summary.json's record of the widening (nothing without one)."""
        return {} if self.at is None else {"search_window_whole_from": self.at}

    def note(self) -> str:
        """What the final message adds after a widening."""
        return "" if self.at is None else (f" (contact search windows the whole partner beam from load "
                                           f"factor {self.at:g})")
