"""Dense linear complementarity problems LCP(S, d): z ≥ 0, w = S z + d ≥ 0, z · w = 0, for the
complementarity predictor of unilateral contact (petsc/complementarity.py: S = G K⁻¹ Gᵀ, the
Schur complement of the saddle-point system, one row per contact multiplier).  For a positive
semidefinite S the LCP is the dual of a convex quadratic programme (``solve_lcp``: NNLS on a
factor of S); slightly indefinite, it may have several solutions, and the one block principal
pivoting reaches from the linearisation's status is taken first (``pivoted_from``), else its
nearest semidefinite matrix chooses the active set and the
exact S solves it (``exact_on_support``); far from semidefinite, the constraints active at the
linearisation are held as equalities (``held_lcp``), whose Schur complement is semidefinite
where the bodies' tangent is on the motions they allow."""
from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as la

#: relative regularisation of S before its Cholesky factor (redundant constraints)
REGULARISATION = 1e-12
#: an indefinite S is replaced by its nearest positive semidefinite matrix when its most negative
#: eigenvalue is at most this share of its largest (petsc/complementarity.py's docstring)
INDEFINITE_SHARE = 1e-2
#: relative tolerance (of max |d|) of the exact LCP's inequalities when the clipped S's active set
#: is solved again with the exact S (``exact_on_support``)
LCP_TOL = 1e-9
#: rounds of ``held_lcp`` at most (each releases the held constraints that came out pulling)
HELD_ROUNDS = 4
#: rounds of ``pivoted_from`` at most (each flips every constraint the last one left infeasible)
PIVOT_ROUNDS = 4


def solve_lcp(S: np.ndarray, d: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
    """z ≥ 0, S z + d ≥ 0, complementary: min ½ zᵀ S z + dᵀ z over z ≥ 0 by NNLS on a
    factor S = L Lᵀ (‖Lᵀ z + L⁻¹ d‖²): Cholesky's, or, for an indefinite S within
    INDEFINITE_SHARE of positive semidefinite (LinAlgError when it is farther: ``held_lcp``),
    first the exact solution pivoted from the active set ``start`` (``pivoted_from``), else
    L = V Λ₊^½ of its nearest positive semidefinite matrix, whose active set is then solved
    with the exact S (``exact_on_support``)."""
    M = len(d)
    if M == 0:
        return np.zeros(0)
    reg = REGULARISATION * max(float(np.max(np.diag(S))), 1e-300)
    try:
        L = la.cholesky(S + reg * np.eye(M), lower=True)
        b = -la.solve_triangular(L, d, lower=True)
        clipped = False
    except np.linalg.LinAlgError:
        lam, V = la.eigh(S)
        if -lam[0] > INDEFINITE_SHARE * lam[-1]:
            raise
        z = None if start is None else pivoted_from(S, d, start)
        if z is not None:
            return z
        L = V * np.sqrt(np.maximum(lam, reg))
        b = -la.solve(L, d)
        clipped = True
    import scipy.optimize as so          # here only: ~40 ms of every run's start-up
    z, _ = so.nnls(L.T, b, maxiter=50 * M)
    return exact_on_support(S, d, z) if clipped else z


def pivoted_from(S: np.ndarray, d: np.ndarray, start: np.ndarray) -> np.ndarray | None:
    """An exact solution of LCP(S, d) reached from the active set ``start`` by block principal
    pivoting on the exact S: z_A = −S_AA⁻¹ d_A, then every active constraint pulling (z < 0)
    released and every inactive one penetrating (w < 0) made active, to ``LCP_TOL`` of d, at
    most ``PIVOT_ROUNDS`` times; None when that does not end.  For an indefinite S the LCP may
    have several solutions (petsc/complementarity.py's docstring): this one continues the
    status the linearisation started from, where the clipped S's may be another one or none
    (the 180° soleus-biased unilateral stride at frame 18.5, docs/gait.md: the converged
    status is an exact solution with no change, the clipped S's changed 6 constraints)."""
    A, tol = start.astype(bool).copy(), LCP_TOL * float(np.max(np.abs(d)))
    for _ in range(PIVOT_ROUNDS + 1):
        z = on_active_set(S, d, A)
        if z is None:
            return None
        w = d + S @ z
        pulling, penetrating = A & (z < -tol), ~A & (w < -tol)
        if not (pulling.any() or penetrating.any()):
            return np.maximum(z, 0.0)
        A = (A & ~pulling) | penetrating
    return None


def held_lcp(S: np.ndarray, d: np.ndarray, held: np.ndarray) -> np.ndarray | None:
    """LCP(S, d) for an indefinite S with the constraints ``held`` (E) as equalities
    (w_E = 0): eliminating z_E leaves LCP(S̃, d̃) in the others (R), S̃ = S_RR − S_RE S_EE⁻¹ S_ER
    the Schur complement of the saddle-point system with E held, G_R K_E⁻¹ G_Rᵀ: positive
    semidefinite where the bodies' tangent is positive definite on the motions E allows,
    though K alone is not (a subtendon pressed by its neighbours and free of them buckles).
    A z_E that comes out negative leaves E (at most ``HELD_ROUNDS`` times).  The result is
    returned only where it solves the exact LCP(S, d) (to ``LCP_TOL``); else None."""
    E, tol = held.copy(), LCP_TOL * float(np.max(np.abs(d)))
    for _ in range(HELD_ROUNDS):
        R = ~E
        if not E.any() or not R.any():
            return None
        try:
            lu = la.lu_factor(S[np.ix_(E, E)], check_finite=False)
            T, t = la.lu_solve(lu, S[np.ix_(E, R)]), la.lu_solve(lu, d[E])
            St = S[np.ix_(R, R)] - S[np.ix_(R, E)] @ T
            zR = solve_lcp(0.5 * (St + St.T), d[R] - S[np.ix_(R, E)] @ t)
        except (np.linalg.LinAlgError, ValueError, RuntimeError):      # RuntimeError: NNLS past its limit
            return None
        zE = -(t + T @ zR)
        if zE.min() < 0.0:
            E[np.flatnonzero(E)[zE < 0.0]] = False
            continue
        z = np.zeros_like(d)
        z[E], z[R] = zE, zR
        w = d + S @ z
        ok = np.all(np.isfinite(z)) and w.min() >= -tol and abs(z @ w) <= tol * max(z.sum(), 1.0)
        return z if ok else None
    return None


def exact_on_support(S: np.ndarray, d: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The solution of LCP(S, d) on the active set {z > 0} that the clipped S chose, with the
    exact S (S_AA z_A = −d_A: the Newton step of the saddle-point system of that active set),
    where it solves the exact LCP (z_A ≥ 0, w ≥ 0 off A, to ``LCP_TOL`` of d); else ``z``
    (petsc/complementarity.py's docstring)."""
    A = z > 0.0
    if not A.any():
        return z
    out = on_active_set(S, d, A)
    if out is None:
        return z
    w = d + S @ out
    tol = LCP_TOL * float(np.max(np.abs(d)))
    if out[A].min() < 0.0 or w[~A].min(initial=0.0) < -tol:
        return z
    return out


def on_active_set(S: np.ndarray, d: np.ndarray, A: np.ndarray) -> np.ndarray | None:
    """z with S_AA z_A = −d_A and 0 off the active set ``A`` (the saddle-point Newton step of
    that active set), None where S_AA is singular or the answer not finite.  An ill-conditioned
    S_AA (scipy's LinAlgWarning on stderr, mid-run) is solved quietly: the callers judge its
    answer like any other (``exact_on_support``, ``pivoted_from``)."""
    z = np.zeros_like(d)
    if A.any():
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", la.LinAlgWarning)
                z[A] = la.solve(S[np.ix_(A, A)], -d[A])
        except np.linalg.LinAlgError:
            return None
    return z if np.all(np.isfinite(z)) else None
