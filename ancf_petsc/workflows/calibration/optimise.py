"""The optimisers, all scipy's: ``least_squares`` (trust-region reflective, bounds) for the local
fit, ``differential_evolution`` for a global search, multi-start local fits.

The local fit's Jacobian is by forward differences of the solves, one step ``fd_step`` along each
coordinate u (a linear one's: ``fd_step`` of the value, ``Parameter.fd_step_u``; backwards at an
upper bound), its n samples evaluated as one batch, i.e. in
parallel over the ranks.  With more than one rank a trial point is evaluated together with its n
finite-difference neighbours (speculatively: when the step is accepted, least_squares asks for
exactly those), so a Newton-like iteration costs one batch instead of two.  A neighbour that fails
where the point did not is tried backwards; failing both ways its column is zero for that step.
Differential evolution evaluates each generation as one batch (``vectorized``, ``deferred``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import differential_evolution, least_squares
from scipy.stats import qmc

from .evaluate import Evaluator
from .parameters import bounds_u, to_u
from .sample import Sample
from .spec import FitSpec


class BudgetExhausted(Exception):
    """A phase asked for more samples than its budget."""


@dataclass
class LocalFit:
    u: np.ndarray                  # the full coordinates at the end
    best: Sample                   # its sample
    jac: np.ndarray | None         # weighted-residual Jacobian in the free coordinates at u
    status: str                    # converged | budget
    message: str
    samples: int                   # parameter sets asked for (logged ones included)


class _Problem:
    """The residual function of the free coordinates (the others held at ``u0``)."""

    def __init__(self, ev: Evaluator, spec: FitSpec, u0, free, phase: str, budget: int):
        self.ev, self.spec, self.phase, self.budget = ev, spec, phase, budget
        self.u0 = np.asarray(u0, dtype=float)
        self.free = list(free)
        self.params = [spec.parameters[j] for j in self.free]
        lo, hi = bounds_u(spec.parameters)
        self.lo, self.hi = lo[self.free], hi[self.free]
        self.h = spec.optimizer.fd_step
        self.asked = 0
        self.seen: list[Sample] = []

    def full(self, x) -> np.ndarray:
        u = self.u0.copy()
        u[self.free] = x
        return u

    def batch(self, X: list) -> list[Sample]:
        if self.asked + len(X) > self.budget and self.asked > 0:
            raise BudgetExhausted
        self.asked += len(X)
        out = self.ev([self.full(x) for x in X], self.phase)
        self.seen += out
        return out

    def steps(self, x) -> np.ndarray:
        h = np.array([par.fd_step_u(xi, self.h) for par, xi in zip(self.params, x)])
        return np.where(x + h <= self.hi, h, -h)

    def neighbours(self, x, steps) -> list:
        return [x + s * e for s, e in zip(steps, np.eye(len(x)))]

    def fun(self, x) -> np.ndarray:
        pts = [x] + (self.neighbours(x, self.steps(x)) if self.ev.size > 1 else [])
        return self.batch(pts)[0].r

    def jac(self, x) -> np.ndarray:
        base = self.batch([x])[0]
        steps = self.steps(x)
        cols = self.batch(self.neighbours(x, steps))
        J = np.empty((len(base.r), len(x)))
        for j, (s, h) in enumerate(zip(cols, steps)):
            if base.ok and not s.ok:               # failed one way: the other way, else no column
                s, h = self.batch(self.neighbours(x, -steps)[j:j + 1])[0], -h
            J[:, j] = (s.r - base.r) / h if (s.ok or not base.ok) else 0.0
        return J


def local_fit(ev: Evaluator, spec: FitSpec, u0, phase: str = "fit", free=None,
              budget: int | None = None) -> LocalFit:
    """least_squares (trf) from ``u0`` over the coordinates ``free`` (default: all)."""
    opt = spec.optimizer
    free = list(range(len(u0))) if free is None else list(free)
    prob = _Problem(ev, spec, u0, free, phase, budget or opt.max_evaluations)
    x0 = np.clip(np.asarray(u0, dtype=float)[free], prob.lo, prob.hi)
    try:
        res = least_squares(prob.fun, x0, jac=prob.jac, bounds=(prob.lo, prob.hi), method="trf",
                            x_scale=1.0, loss=spec.loss, xtol=opt.xtol, ftol=opt.ftol, gtol=opt.gtol)
        x, status, message = res.x, "converged", str(res.message)
    except BudgetExhausted:
        best = min(prob.seen, key=lambda s: s.cost)
        x, status = np.asarray(best.u)[free], "budget"
        message = f"stopped after {prob.asked} samples (the budget); the best one is kept"
    best = prob.batch([x])[0] if status == "converged" else min(prob.seen, key=lambda s: s.cost)
    prob.budget = np.inf                      # the Jacobian at the end is always taken
    jac = prob.jac(np.asarray(best.u)[free]) if best.ok else None
    return LocalFit(np.asarray(best.u, dtype=float), best, jac, status, message, prob.asked)


def start_points(spec: FitSpec) -> list[np.ndarray]:
    """The fit's start, then ``starts − 1`` Latin-hypercube points inside the bounds (seeded)."""
    params = spec.parameters
    first = to_u(params, [p.start for p in params])
    k = spec.optimizer.starts
    if k == 1:
        return [first]
    lo, hi = bounds_u(params)
    unit = qmc.LatinHypercube(d=len(params), seed=spec.optimizer.seed).random(k - 1)
    return [first] + [lo + (hi - lo) * row for row in unit]


def global_fit(ev: Evaluator, spec: FitSpec, say=lambda *_: None) -> LocalFit:
    """Differential evolution over the bounds (each generation one batch), polished by trf."""
    opt = spec.optimizer
    params = spec.parameters
    lo, hi = bounds_u(params)
    generation, asked = [0], [0]           # batches; parameter sets (scipy counts a batch as 1)

    def costs(X: np.ndarray) -> np.ndarray:
        out = np.array([s.cost for s in ev([X[:, k] for k in range(X.shape[1])], "de")])
        generation[0] += 1
        asked[0] += X.shape[1]
        say(f"[fit] differential evolution batch {generation[0]}: {X.shape[1]} samples, "
            f"best cost {out.min():.6g}")
        return out

    res = differential_evolution(costs, list(zip(lo, hi)), vectorized=True, updating="deferred",
                                 popsize=opt.popsize, maxiter=opt.generations, seed=opt.seed,
                                 polish=False, init="latinhypercube",
                                 x0=to_u(params, [p.start for p in params]))
    say(f"[fit] differential evolution: {res.message.strip()} (cost {res.fun:.6g}, {asked[0]} samples)")
    if opt.polish:
        return local_fit(ev, spec, res.x, "fit")
    best = ev([res.x], "de")[0]
    return LocalFit(np.asarray(res.x), best, None, "converged", str(res.message), asked[0] + 1)
