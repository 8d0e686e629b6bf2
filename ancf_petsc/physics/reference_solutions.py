"""Exact solutions used to verify the solver (independent of the finite-element machinery)."""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, root


def uniaxial_stretches(material, nominal_stress: float) -> tuple[float, float]:
    """Homogeneous uniaxial tension: F = diag(λ, λ_t, λ_t) with P11 = s, P22 = P33 = 0.

    Uses only the material's stress function; returns (λ, λ_t).
    """
    def eqs(v):
        lam, lt = v
        P, _ = material.stress(np.diag([lam, lt, lt])[None])
        scale = max(abs(nominal_stress), 1.0)
        return [(P[0, 0, 0] - nominal_stress) / scale, P[0, 1, 1] / scale]

    guess = 1.0 + nominal_stress / (3.0 * getattr(material, "mu", 1.0))
    sol = root(eqs, [guess, 1.0 / np.sqrt(guess)], method="lm", tol=1e-15)
    if np.max(np.abs(eqs(sol.x))) > 1e-13:
        raise RuntimeError(f"uniaxial solution did not converge: {sol.message}")
    return float(sol.x[0]), float(sol.x[1])


def elastica_tip(alpha: float, rtol: float = 1e-12) -> tuple[float, float]:
    """Euler elastica of a cantilever with a dead transverse tip force, α = P L² / EI.

    Solves EI θ'' + P cos θ = 0, θ(0) = 0, θ'(L) = 0 by shooting on θ'(0).  Returns the tip
    displacements (u/L along the beam, w/L transverse), u ≤ 0.
    """
    def shoot(k0):
        sol = solve_ivp(lambda s, y: [y[1], -alpha * np.cos(y[0]), np.cos(y[0]), np.sin(y[0])],
                        (0.0, 1.0), [0.0, k0, 0.0, 0.0], rtol=rtol, atol=1e-14, method="DOP853")
        return sol.y[:, -1]

    k0 = brentq(lambda k: shoot(k)[1], 0.0, alpha * 1.0000001 + 1e-12, xtol=1e-15, rtol=1e-15)
    end = shoot(k0)
    return end[2] - 1.0, end[3]
