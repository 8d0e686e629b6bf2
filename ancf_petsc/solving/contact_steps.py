"""The contact law's part in one increment's Newton solves (solving/newton.py): its phases, the
kept status during SNES solves, the fade weights' updates and the exact rule's check of a
converged state."""
from __future__ import annotations

from petsc4py import PETSc

from ..contact import decide_kept, forget_evaluation
from ..contact.laws import NEWTON


class ContactSteps:
    """The contact law's part in one increment's solves, on the problem's contact (none: one
    plain Newton solve).  Collective where it says so."""

    def __init__(self, problem):
        self.problem, self.contact = problem, problem.contact
        self.frozen = False            # the status is kept during SNES solves (line searches)

    def begin_increment(self, from_rest: bool) -> None:
        """An increment's solves start (the fade weights' rule, contact/weights.py)."""
        if self.contact is not None:
            self.contact.weights.begin_increment(from_rest)
            forget_evaluation(self.contact)

    def phases(self, from_rest: bool) -> list:
        return [NEWTON] if self.contact is None else self.contact.law.phases(from_rest)

    def begin(self, phase, previous) -> None:
        if self.contact is not None:
            self.contact.begin_phase(phase, previous)

    def keep_status(self, phase) -> None:
        """Begin ``phase`` with the present status kept for the next SNES solve (the status
        may change only in ``update_status``)."""
        self.frozen = True
        self.contact.begin_phase(phase)
        self.contact.allow_update = False

    @property
    def bounded(self) -> bool:
        """Whether the contact has bounds that follow the state (friction's)."""
        return self.contact is not None and any(t.bounded for t in self.contact.terms)

    @property
    def decides_activity(self) -> bool:
        return self.contact is not None and self.contact.law.decides_activity

    def next_iterate(self) -> None:
        """A Newton iteration's Jacobian was taken (or reused): the next evaluation may change
        the status (Contact.allow_update), unless it is kept during solves."""
        if self.contact is not None and not self.frozen:
            self.contact.allow_update = True

    def refresh_weights(self) -> bool:
        """After a converged solve: did a contact point's weight change? (collective)"""
        return self.contact is not None and self.contact.refresh_weights()

    def differentiate_weights(self) -> bool:
        """After a converged solve that kept the weights (the first from rest, contact/weights.py):
        bring them up to date; True (collective) when one changed, the later evaluations then
        differentiating them.  False when they were not kept."""
        return self.contact is not None and self.contact.weights.kept and self.contact.refresh_weights()

    def residual_norm(self, X: PETSc.Vec) -> float:
        """|F(X)| with the contact weights as they are now (collective)."""
        F = self.problem.F.duplicate()
        self.problem.residual(None, X, F)
        norm = F.norm()
        F.destroy()
        return norm

    def status_changes(self) -> int:
        """Status changes so far, summed over the ranks (collective)."""
        n = 0 if self.contact is None else self.contact.status_changes
        return int(self.problem.comm.tompi4py().allreduce(n))

    def update_status(self, X: PETSc.Vec) -> int:
        """Let the law update the status at X: the number of changes (collective).  On the kept
        evaluation where it is X's (``contact.decide_kept``), else by evaluating the residual."""
        before = self.status_changes()
        P = self.problem
        if not decide_kept(self.contact, P.exchange.local_state(X), P.exchange.needed):
            self.contact.allow_update = True
            F = P.F.duplicate()
            P.residual(None, X, F)
            F.destroy()
        return self.status_changes() - before
