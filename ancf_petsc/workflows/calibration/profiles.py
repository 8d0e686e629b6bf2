"""Profiles of the objective along each parameter (identify.py): the parameter held at points
outwards from the optimum, the others fitted again from the previous point's fit."""
from __future__ import annotations

import numpy as np

from .evaluate import Evaluator
from .identify import Profile, close_profile, profile_grid
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
        for x in side:
            u[i] = x
            if others and ident.reoptimise:
                fit = local_fit(ev, spec, u, phase=f"profile:{par.name}", free=others,
                                budget=ident.max_evaluations)
                s, u = fit.best, fit.u.copy()
                u[i] = x
            else:
                s = ev([u], f"profile:{par.name}")[0]
            prof.values.append(par.from_u(x))
            prof.delta.append((2.0 * s.cost - chi2_min) / s2)
            prof.status.append(s.status)
        say(f"[fit] profile of {par.name}: {len(side)} points "
            f"{'below' if side is left else 'above'} the optimum")
    return close_profile(prof, par.from_u(u_hat[i]))
