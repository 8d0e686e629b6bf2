"""Exact solutions used to verify the solver (independent of the finite-element machinery)."""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, root


def uniaxial_stretches(material, nominal_stress: float) -> tuple[float, float]:
    """Homogeneous uniaxial tension: F = diag(λ, λ_t, λ_t) with P11 = s, P22 = P33 = 0.

    Uses only the material's stress function; returns (λ, λ_t).  The residual is measured
    against the material's Young's modulus (or the stress, if larger): the lateral equation
    P22 = 0 is only met to the rounding of stresses of that size.
    """
    scale = max(abs(nominal_stress), material.young)

    def eqs(v):
        lam, lt = v
        P, _ = material.stress(np.diag([lam, lt, lt])[None])
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


def shear_lag_transfer(x: np.ndarray, length: float, ea_core: float, ea_outer: float,
                       k_line: float, force: float) -> np.ndarray:
    """Axial force in each outer bar of a symmetric sandwich (shear-lag theory, small strain).

    A core bar (axial stiffness ``ea_core``) between two outer bars (``ea_outer`` each), all
    held at x = 0, joined along their length by two interfaces that carry k_line (u_core −
    u_outer) per unit length [N/m²]; the core is pulled by ``force`` at x = L, the outer ends
    are free.  The slip s = u_core − u_outer solves s'' = s/ℓ², ℓ = (k_line (2/EA_c + 1/EA_o))^(−1/2),
    s(0) = 0, s'(L) = F/EA_c, and the outer bar carries

        N_o(x) = k_line ℓ² F/EA_c (cosh(L/ℓ) − cosh(x/ℓ)) / cosh(L/ℓ),

    which tends to the bonded share F EA_o / (EA_c + 2 EA_o) at the root as k_line → ∞.
    """
    ell = 1.0 / np.sqrt(k_line * (2.0 / ea_core + 1.0 / ea_outer))
    x = np.asarray(x, dtype=float)
    # cosh(x/ℓ) / cosh(L/ℓ) with exponentials of non-positive arguments (no overflow for L ≫ ℓ)
    ratio = np.exp((x - length) / ell) * (1.0 + np.exp(-2.0 * x / ell)) / (1.0 + np.exp(-2.0 * length / ell))
    return k_line * ell ** 2 * force / ea_core * (1.0 - ratio)
