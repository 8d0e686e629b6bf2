"""What the data say about the parameters: standard errors and correlations from the Jacobian at
the optimum, profiles of the objective along each parameter, and a verdict per parameter.

With weighted residuals r (in σ) and their Jacobian J in the optimiser's coordinates u, the
covariance of the estimate is  Cov(u) = s² (Jᵀ J)⁻¹ = s² (Jᵀ W J)⁻¹ in unweighted terms, with
s² = max(Σ r² / (m − n), 1) (m data, n parameters: the misfit the σ did not explain scales the
errors up; a fit better than its σ does not scale them down: with few data Σ r² / (m − n) is
itself uncertain, and 3 points fitting to 0.08 σ would shrink the errors 13-fold), or s² = 1
with ``objective.absolute_sigma`` (the σ are the data's known errors, as scipy's
curve_fit(absolute_sigma=True); needed when there are no more data than parameters).
It is taken through the singular values of J: a direction J does not see (a singular value below
``RCOND`` of the largest) has infinite variance, and every parameter with a part in it an
infinite standard error.  Standard errors of p follow to first order (dp/du).

The profile of parameter i: u_i fixed at points out to ``span`` standard errors on each side (the
whole bounds when the error is infinite), the other parameters fitted again (``reoptimise``), and
Δχ² = (Σ r²(u_i) − Σ r²_min) / s².  Its 95 % interval is where Δχ² < 3.84 (χ² with one degree of
freedom); a side is *closed* when the profile crosses 3.84 inside the bounds.

The linearised 95 % interval is u ± t SE_u, t the 97.5 % quantile of Student's t with m − n
degrees of freedom where s² is estimated from the m − n residuals (t → 1.96 for many data), and
1.96 where s² = 1 (absolute σ, or the floor).

The verdict uses w, the relative half-width of the 95 % interval: the profile's when there is one
(it follows the model's curvature and the bounds of the other parameters, which the linearisation
does not: a parameter correlated with an undetermined one gets a large linearised error but may
be pinned within the bounds), else the linearised one (t SE_p / |p|); for a log-scaled parameter
the larger factor − 1:
  * determined        w ≤ 0.25 and the profile (when computed) closed on both sides;
  * not determined    the profile open on both sides (flat: it never reaches 3.84 inside the
                      bounds), or w > 1 (infinite included);
  * weakly determined otherwise.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.stats import t as student_t

from .parameters import Parameter, bounds_u, pow10

RCOND = 1e-8
CHI2_95 = 3.841458820694124                  # χ²₁ quantile at 0.95
DETERMINED, WEAK, NOT = "determined", "weakly determined", "not determined"


@dataclass
class Uncertainty:
    s2: float                                # the errors' variance factor max(Σ r² / (m − n), 1)
    dof: int
    cov_u: np.ndarray                        # (n, n); inf where not determined
    corr: np.ndarray                         # (n, n) correlations (regularised where singular)
    se_u: np.ndarray
    singular_values: np.ndarray

    absolute: bool = False                   # s² = 1: the σ are the data's errors
    chi2_dof: float = 1.0                    # Σ r² / (m − n), before the floor

    @property
    def floored(self) -> bool:
        """Whether the fit is better than its σ (Σ r² / (m − n) < 1) and s² is the floor, 1."""
        return not self.absolute and self.chi2_dof < 1.0

    @property
    def t95(self) -> float:
        """The 97.5 % quantile of Student's t with ``dof`` degrees of freedom (normal where
        s² = 1: absolute σ or the floor)."""
        return float(student_t.ppf(0.975, np.inf if self.absolute or self.floored else self.dof))


def uncertainty(J: np.ndarray, r: np.ndarray, absolute: bool = False) -> Uncertainty:
    """Cov(u) = s² (JᵀJ)⁻¹ through the SVD of J (module docstring)."""
    m, n = J.shape
    dof = max(m - n, 1)
    chi2_dof = float(np.sum(r ** 2)) / dof
    s2 = 1.0 if absolute else max(chi2_dof, 1.0)
    _, S, Vt = np.linalg.svd(J, full_matrices=False)
    V = Vt.T
    null = S <= RCOND * (S[0] if len(S) and S[0] > 0 else 1.0)
    inv = np.where(null, 0.0, 1.0 / np.where(null, 1.0, S) ** 2)
    cov = s2 * (V * inv) @ V.T
    seen = np.abs(V[:, null]).max(axis=1, initial=0.0) > 1e-6
    var = np.where(seen, np.inf, np.diag(cov))
    cov = cov.copy()
    cov[seen, :] = np.inf
    cov[:, seen] = np.inf
    eps2 = (RCOND * (S[0] if len(S) else 1.0)) ** 2
    reg = (V / (S ** 2 + eps2)) @ V.T
    d = np.sqrt(np.diag(reg))
    corr = reg / np.outer(d, d)
    return Uncertainty(s2, dof, cov, corr, np.sqrt(var), S, absolute, chi2_dof)


def relative_width(par: Parameter, p: float, se_u: float, t95: float) -> float:
    """w: the relative half-width of the linearised 95 % interval (module docstring)."""
    if not np.isfinite(se_u):
        return np.inf
    if par.log:
        return pow10(t95 * se_u) - 1.0
    return t95 * se_u * par.scale / abs(p) if p != 0 else np.inf


def interval(par: Parameter, u: float, se_u: float, t95: float) -> tuple[float, float]:
    """The linearised 95 % interval of p (in u, so a log-scaled one stays positive)."""
    if not np.isfinite(se_u):
        return -np.inf if not par.log else 0.0, np.inf
    return par.from_u(u - t95 * se_u), par.from_u(u + t95 * se_u)


@dataclass
class Profile:
    values: list[float] = field(default_factory=list)    # p at the profile points
    delta: list[float] = field(default_factory=list)     # Δχ²
    status: list[str] = field(default_factory=list)      # the point's sample status
    closed: tuple[bool, bool] = (False, False)           # crosses 3.84 below / above the optimum
    interval: tuple[float, float] = (np.nan, np.nan)     # where Δχ² < 3.84 (edge of the profile if open)


def profile_grid(par: Parameter, u: float, se_u: float, span: float, points: int) -> tuple[list, list]:
    """Points below and above the optimum (each side ordered outwards), in u."""
    lo, hi = par.bounds_u
    w = span * se_u if np.isfinite(se_u) and se_u > 0 else np.inf
    k = max(1, points // 2)
    left = np.linspace(u, max(lo, u - w), k + 1)[1:]
    right = np.linspace(u, min(hi, u + w), k + 1)[1:]
    return [x for x in left if x < u], [x for x in right if x > u]


def crossing(d0: float, d1: float) -> float:
    """Where between two profile points (Δχ² = d0 < 3.84 <= d1) the profile crosses 3.84, as a
    fraction of the way: linear in √Δχ², exact for a profile quadratic about the optimum."""
    a, b = np.sqrt(max(d0, 0.0)), np.sqrt(d1)
    return float((np.sqrt(CHI2_95) - a) / (b - a)) if b > a else 1.0


def _side(v: np.ndarray, d: np.ndarray, ok: np.ndarray) -> tuple[float | None, float]:
    """Going outwards along (v, d) from the optimum (v[0]): where Δχ² first reaches 3.84
    (``crossing``; None if it does not) and the last point reached.  A sample that failed says
    nothing about the data: the side ends, open, before it."""
    for k in range(1, len(v)):
        if not ok[k]:
            return None, float(v[k - 1])
        if d[k] >= CHI2_95:
            return float(v[k - 1] + crossing(d[k - 1], d[k]) * (v[k] - v[k - 1])), float(v[k])
    return None, float(v[-1])


def close_profile(prof: Profile, p_hat: float) -> Profile:
    """Which sides cross 3.84, and the 95 % interval where the profile stays below it (to the
    last point of a side that does not cross: the bounds, the span, or a failed sample)."""
    v, d = np.array(prof.values), np.array(prof.delta)
    ok = np.array([s == "completed" for s in prof.status], dtype=bool)
    sides = []
    for sel, order in ((v < p_hat, -1), (v > p_hat, 1)):
        k = np.argsort(order * v[sel])
        sides.append(_side(np.concatenate([[p_hat], v[sel][k]]), np.concatenate([[0.0], d[sel][k]]),
                           np.concatenate([[True], ok[sel][k]])))
    prof.closed = (sides[0][0] is not None, sides[1][0] is not None)
    prof.interval = tuple(c if c is not None else edge for c, edge in sides)
    return prof


def profile_width(par: Parameter, p_hat: float, prof: Profile) -> float:
    """w from the profile's 95 % interval: its larger relative half-width (log-scaled: the
    larger factor − 1); infinite when it reaches p = 0."""
    lo, hi = prof.interval
    if par.log:
        return max(hi / p_hat, p_hat / lo) - 1.0 if lo > 0 else np.inf
    return max(p_hat - lo, hi - p_hat) / abs(p_hat) if p_hat != 0 else np.inf


def verdict(w: float, prof: Profile | None) -> tuple[str, str]:
    """The verdict and its reason (module docstring); ``w`` from the profile when there is one."""
    if prof is not None and not any(prof.closed):
        return NOT, "the profile stays below Δχ² = 3.84 on both sides within the bounds"
    if not np.isfinite(w):
        return NOT, "the Jacobian does not see it (infinite standard error)"
    how = "profile" if prof is not None else "linearised"
    if w > 1.0:
        return NOT, f"{how} 95 % interval ±{100 * w:.3g} %"
    if w <= 0.25 and (prof is None or all(prof.closed)):
        return DETERMINED, f"{how} 95 % interval ±{100 * w:.2g} %"
    side = "" if prof is None or all(prof.closed) else "; the profile is open on one side"
    return WEAK, f"{how} 95 % interval ±{100 * w:.2g} %{side}"


def at_bounds(params: list[Parameter], u: np.ndarray, tol: float = 1e-6) -> list[bool]:
    lo, hi = bounds_u(params)
    return [bool(x - a < tol or b - x < tol) for x, a, b in zip(u, lo, hi)]
