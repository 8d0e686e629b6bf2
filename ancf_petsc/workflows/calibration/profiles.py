"""Profiles of the objective along each parameter (identify.py): the parameter held at points
outwards from the optimum, the others fitted again from the previous point's fit.  When a side's
first point is already far above the 95 % threshold (the linearised error, which sets the
points, was too wide), one more point is put where the profile, quadratic about the optimum,
crosses it, so that the interval is resolved."""
from __future__ import annotations

import numpy as np

from .evaluate import Evaluator
from .identify import CHI2_95, Profile, close_profile, crossing, profile_grid
from .optimise import local_fit
from .spec import FitSpec


def profile(ev: Evaluator, spec: FitSpec, u_hat: np.ndarray, chi2_min: float, s2: float, i: int,
            se_u: float, say=lambda *_: None) -> Profile:
    """The profile of parameter i (Δχ² at each point; identify.py)."""
    par = spec.parameters[i]
    ident = spec.identifiability
    left, right = profile_grid(par, u_hat[i], se_u, ident.span, ident.points)
    others = [j for j in range(len(u_hat)) if j != i]
    prof = Profile()
    for side in (left, right):
        u = u_hat.copy()
        for k, x in enumerate(side):
            u = _point(ev, spec, prof, u, i, x, others, (chi2_min, s2))
            if k == 0 and prof.status[-1] == "completed" and prof.delta[-1] > 4 * CHI2_95:
                xc = u_hat[i] + crossing(0.0, prof.delta[-1]) * (x - u_hat[i])
                _point(ev, spec, prof, u_hat.copy(), i, xc, others, (chi2_min, s2))
        say(f"[fit] profile of {par.name}: {len(side)} points "
            f"{'below' if side is left else 'above'} the optimum")
    return close_profile(prof, par.from_u(u_hat[i]))


def _point(ev: Evaluator, spec: FitSpec, prof: Profile, u: np.ndarray, i: int, x: float,
           others: list[int], scale: tuple[float, float]) -> np.ndarray:
    """One profile point: u_i = x, the others re-fitted from ``u`` (or held); appends its value,
    Δχ² = (Σ r² − χ²_min) / s² (``scale``) and status; returns the full u reached."""
    par, ident = spec.parameters[i], spec.identifiability
    u = u.copy()
    u[i] = x
    if others and ident.reoptimise:
        fit = local_fit(ev, spec, u, phase=f"profile:{par.name}", free=others, budget=ident.max_evaluations)
        s, u = fit.best, fit.u.copy()
        u[i] = x
    else:
        s = ev([u], f"profile:{par.name}")[0]
    prof.values.append(par.from_u(x))
    prof.delta.append((2.0 * s.cost - scale[0]) / scale[1])
    prof.status.append(s.status)
    return u
