"""The linearised contact complementarity problem solved exactly: a predictor of the active set
and of the Newton step for unilateral contact (a Josephy–Newton step).

At a state X the unilateral conditions linearise to a complementarity problem in the new scaled
multipliers z⁺ (contact/multipliers.py):

    K Δq − Gᵀ Δz = −F_q,     w = c + G Δq ≥ 0,   z⁺ = z + Δz ≥ 0,   w · z⁺ = 0,

with K the tangent of the bodies (every multiplier acting, no constraint), G = k_s ∂ḡ/∂q the
constraint gradients and c = k_s ḡ.  Eliminating Δq gives LCP(S, d): w = d + S z⁺ with the
Schur complement S = G K⁻¹ Gᵀ (symmetric, positive definite for a stable tangent and independent
constraints) and d = c + G K⁻¹(−F_q) − S z.  It is the dual of a strictly convex quadratic
programme, solved here with non-negative least squares (Lawson–Hanson, finite) on a Cholesky
factor of S, so that no active-set guessing inside Newton's iteration is needed where the
guessing is hard: from the exactly touching, pressure-free reference, S is ill-conditioned
(condition 1e10–1e12 on the paper's tendon: the unloaded neighbours are compliant cantilevers)
and the primal–dual active set rule needs 12–38 exact iterations at any constant, and cycles on
bundle_hex7 (scripts/bench_contact.py --lcp).

The predictor is solved at the start of every load increment (at the load predictor's state;
not where the active set has settled: solving/newton.py, "A settled active set") and again at a
converged state whose status the exact rule would change: a Josephy–Newton iteration whose inner
solves keep the status.  Away from rest the tangent of the
bodies alone can be indefinite (a neighbour pressed by its contact forces and free of its
constraints buckles), and so can S.  Where its most negative eigenvalue is at most
``INDEFINITE_SHARE`` of its largest (the paper's tendon and the second subject: 1e-5 … 5e-3)
the LCP may then have several
solutions; the one reached by block principal pivoting on the exact S from the status at X is
taken first (``lcp.pivoted_from``: at a converged state that status is one, and a small
increment continues it; at frame 18.5 of the 180° soleus-biased unilateral stride it was, while
the clipped S below changed 6 constraints and Newton went on to a saddle, docs/gait.md).  Where
pivoting ends on none, S is replaced by its nearest positive semidefinite matrix (its negative
eigenvalues set to zero).  Farther from
semidefinite (the gait envelope at twist ≥ 75°: −5.6e9 against 7.5e9 at 90°, 600 N) the
constraints active at X are held as equalities (``lcp.held_lcp``): the Schur complement of the
saddle-point system with them held is semidefinite where K is on the motions they allow, and its
LCP gives an exact solution of LCP(S, d) or none.  Without one there is no prediction
(bundle_circle7: the negative part dominates) and the law's phases decide the status.
The clipped S only chooses the active set: its pressures are then solved again with the exact S
(``lcp.exact_on_support``), which makes the step the saddle-point Newton step of that active set,
wherever that solves the exact LCP.  The clipped matrix's own pressures are off along the clipped
direction, and Δq = y − Xs Δz carries that error through K⁻¹, which is large exactly where K is
near its negative mode: on the solver_default_2025 GOH column (unilateral, 90.72 N, docs/fibres.md)
S had −9.2e3 against 1.3e7, the clipped pressures differed from the exact ones by up to 56 % and
the predicted step was 4.4 long against Newton's 0.028 on the same (unchanged) active set, leaving
|F| = 0.35 N for an increment of 2e-4 N and an unconverged projection; the stepper's solves from
it all failed.

S costs one factorisation of K (MUMPS, the model's matrix assembled in the probe phase) and one
solve per multiplier, so the predictor is used up to ``MAX_MULTIPLIERS``.  Not with friction's
tangential multipliers (their rows make K unsymmetric and the Coulomb status is not in the LCP):
the paper's tendon, equal loading, mu = 3 took 4576 Newton iterations and 4 cut-backs at 10 N
with the predictor, 526 and none without.  Collective: every rank
gets the same S, d (sums over ranks) and the same solution.

With the fade weights differentiated (``contact.fade: newton``, contact/weights.py) the rows and
columns of the multipliers are the same exact gradients of the weighted gaps (the variational
weights), so S = G K⁻¹ Gᵀ is the exact linearisation.  (Until the gait envelope the weights'
terms were in the rows only: K unsymmetric, S from the columns; the alex GOH column stopped at
98.9 N with S from the rows, measured 2026-11-26.)
"""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from ..contact.laws import HELD, PROBE
from ..linalg.compact_factor import install_for, release_python_pc
from ..linalg.inertia import mumps_factor
from .lcp import INDEFINITE_SHARE, held_lcp, solve_lcp
from .step_limits import MAX_EXPONENT_GROWTH

#: the predictor's limit: S is dense (multipliers²) and costs a solve per multiplier
MAX_MULTIPLIERS = 2500
#: halvings of the predicted step before it is dropped (the status is kept)
MAX_HALVINGS = 8


def multiplier_dofs(problem) -> np.ndarray:
    """Global PETSc DOF of every multiplier (model order of contact.space)."""
    c, lay = problem.contact, problem.layout
    return problem.model.dofs_per_node * lay.perm[problem.model.n_nodes + c.space.node] + c.space.slot


def _owned_values(vec: PETSc.Vec, dofs: np.ndarray, comm) -> np.ndarray:
    """vec[dofs] on every rank."""
    lo, hi = vec.getOwnershipRange()
    out = np.zeros(len(dofs))
    mine = (dofs >= lo) & (dofs < hi)
    out[mine] = vec.getArray(readonly=True)[dofs[mine] - lo]
    return comm.allreduce(out)


class KeptOperator:
    """The predictor's K between linearisations: while the Jacobian's pattern has not grown
    (``growths`` the same), the next K is copied into the kept one and MUMPS refactors it on its
    symbolic analysis (the ordering depends on the pattern alone: the same factors); after a
    growth a new K and the preconditioner reset (a MUMPS factorisation on the old symbolic
    analysis corrupts memory).  Collective (the growths are the same on every rank)."""

    def __init__(self, ksp: PETSc.KSP):
        self.ksp, self.K, self.growths = ksp, None, -1

    def copy_of(self, J: PETSc.Mat, growths: int) -> PETSc.Mat:
        """J's values in the kept K, or a new K."""
        if self.K is not None and growths == self.growths:
            J.copy(self.K, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
            return self.K
        self.forget()
        self.K, self.growths = J.duplicate(copy=True), growths
        return self.K

    def forget(self) -> None:
        """No kept K (and the preconditioner reset)."""
        self.ksp.getPC().reset()
        if self.K is not None:
            self.K.destroy()
        self.K, self.growths = None, -1


class ComplementarityPredictor:
    """Solves the linearised complementarity problem at a state (module docstring).  ``snes``:
    the Newton solver that factors the same matrix (its preconditioner is reset when the
    predictor's assembly grows the contact pattern, as the SNES's own assembly does: a MUMPS
    factorisation on the old symbolic analysis corrupts memory)."""

    def __init__(self, problem, snes: PETSc.SNES | None = None, compact: bool = False):
        self.problem, self.snes = problem, snes
        self.comm = problem.comm.tompi4py()
        self.dofs = multiplier_dofs(problem)
        self.ksp = PETSc.KSP().create(comm=problem.comm)
        self.ksp.setType("preonly")
        pc = self.ksp.getPC()
        # an unsymmetric K (a tangential law's terms, when they are not excluded above): LU
        pc.setType("cholesky" if problem.symmetric else "lu")
        pc.setFactorSolverType("mumps")
        self.ksp.setOptionsPrefix("ancf_lcp_")
        # K's multiplier rows are diagonal: no saddle point, MUMPS's own ordering
        install_for(problem, self.ksp, compact, "ancf_lcp_", ordering={})
        self.solves = 0
        self._z = np.zeros(len(self.dofs))        # the multipliers at the last linearisation
        self._select = None                       # E: the multipliers' columns (``_columns``)
        self._zero_rows = True                    # the matrix type can zero rows and columns
        self._kept = KeptOperator(self.ksp)        # K between linearisations
        self.last_held = False                     # the last prediction held the active set
        #: increments in a row whose prediction and check changed no status (solving/newton.py)
        self.settled = 0

    @staticmethod
    def applies(problem) -> bool:
        c = problem.contact
        return (c is not None and c.law.decides_activity
                and c.n_multipliers <= MAX_MULTIPLIERS
                and not any(t.multipliers for t in c.terms))

    def destroy(self) -> None:
        """Free the factor of K (its compact factor's context first: ``release_python_pc``)."""
        self._kept.forget()
        release_python_pc(self.ksp, self.problem.comm)
        self.ksp.destroy()
        if self._select is not None:
            self._select.destroy()

    def _columns(self, J: PETSc.Mat) -> PETSc.Mat:
        """The multipliers' columns of J as a dense N × M matrix (rows distributed like J,
        columns in model order of the multipliers): J times the dense selection matrix E."""
        if self._select is None:
            M = len(self.dofs)
            E = PETSc.Mat().createDense((J.getSizes()[1], (None, M)), comm=J.comm)
            E.setUp()
            lo, hi = J.getOwnershipRange()
            mine = (self.dofs >= lo) & (self.dofs < hi)
            arr = E.getDenseArray()
            arr[:] = 0.0
            arr[self.dofs[mine] - lo, np.flatnonzero(mine)] = 1.0
            del arr
            E.assemble()
            self._select = E
        return J.matMult(self._select)

    def predict(self, X: PETSc.Vec) -> bool:
        """Replace X by the Josephy–Newton step from X and set the contact status from the
        solution; False (X and the status unchanged) when a factorisation failed or S is too
        far from positive definite (``INDEFINITE_SHARE``) and holding the active constraints
        (``lcp.held_lcp``) gives no solution.  ``last_held``: this prediction came from the held
        constraints."""
        c = self.problem.contact
        law_phase, status = c.law.phase, c.status.copy()
        vecs, self.last_held = [], False
        lcp = self._linearised(X, vecs)
        z_new = start = None
        if lcp is not None:
            start = self.global_status(status)   # every rank's multipliers (collective)
            try:
                z_new = solve_lcp(lcp[0], lcp[1], start)
            except np.linalg.LinAlgError:        # S far from positive definite: no convex LCP
                z_new = held_lcp(lcp[0], lcp[1], start)
                self.last_held = z_new is not None
            except RuntimeError:                 # NNLS past its iteration limit: no prediction
                z_new = None
        c.begin_phase(law_phase)
        if z_new is None:
            c.status[:] = status
        else:
            # active where it presses, inactive where it opens; a degenerate constraint (both
            # within the tie tolerance) keeps its status: the exact rule accepts it either way,
            # and a status set by the sign of rounding made predictions and checks alternate
            # (the paper's ψ = 45° column with k_s x 10: 79 instead of 54 Newton iterations)
            w = (lcp[1] + lcp[0] @ z_new) / c.stiffness
            active = np.where(z_new > c.tie_tolerance, True, np.where(w > c.tie_tolerance, False, start))
            self._step(X, z_new, active, *vecs[:3])
            self.solves += 1
        for v in vecs:
            v.destroy()
        return z_new is not None

    def _linearised(self, X: PETSc.Vec, vecs: list):
        """(S, d) of the LCP at X, or None if a factorisation failed; ``vecs`` receives the
        objects the step needs (B = −Gᵀ, Xs = K⁻¹B, y = −K⁻¹F_q, then work vectors)."""
        P, c = self.problem, self.problem.contact
        F = P.F.duplicate()
        vecs.append(F)
        try:
            # held: the constraint gradients (columns −Gᵀ), c = k_s ḡ and F_q with every z
            c.begin_phase(HELD)
            P.residual(None, X, F)
            P.jacobian(self.snes, X, P.J, P.J)
            B = self._columns(P.J)
            cvec = -_owned_values(F, self.dofs, self.comm)
            rhs = F.copy()
            vecs.append(rhs)
            rhs.scale(-1.0)
            self._set_owned(rhs, np.zeros(len(self.dofs)))          # a probe's z rows: 0
            K = self._probe_matrix(X)
            self.ksp.setOperators(K)
            self.ksp.setFromOptions()
            self.ksp.setUp()
            Xs, y = B.duplicate(), X.duplicate()
            vecs[:0] = [B, Xs, y]
            factor = mumps_factor(self.ksp)
            if factor is None:
                return None
            factor.matSolve(B, Xs)                                    # K⁻¹(−Gᵀ)
            self.ksp.solve(rhs, y)                                   # −K⁻¹ F_q
        except PETSc.Error:
            return None
        Bl, Xl = B.getDenseArray(readonly=True), Xs.getDenseArray(readonly=True)
        S = self.comm.allreduce(Bl.T @ Xl)
        Bty = self.comm.allreduce(Bl.T @ y.getArray(readonly=True))
        z = _owned_values(X, self.dofs, self.comm)
        S = 0.5 * (S + S.T)
        self._z = z
        d = cvec - Bty - S @ z
        if not (np.all(np.isfinite(S)) and np.all(np.isfinite(d))):
            # a state the residual is not defined at (an inverted element: NaN by design,
            # problem.py), or a tangent MUMPS factored into infinities: no linearisation here
            # (the same on every rank: S and d are sums over the ranks)
            return None
        return S, d

    def _probe_matrix(self, X: PETSc.Vec) -> PETSc.Mat:
        """K with every multiplier acting on the bodies and the z rows decoupled (the probe
        phase): the held Jacobian in P.J with the multipliers' rows and columns replaced by
        −k_s on the diagonal (its q block is the same), or, where the matrix type cannot zero
        rows and columns (MPISBAIJ), assembled in the probe phase."""
        P, c = self.problem, self.problem.contact
        if self._zero_rows:
            K = self._kept.copy_of(P.J, P.pattern_growths)
            try:
                K.zeroRowsColumns(self.dofs.astype(PETSc.IntType), diag=-c.stiffness)
                return K
            except PETSc.Error:                   # the same type on every rank: all fail
                self._kept.forget()
                self._zero_rows = False
        c.begin_phase(PROBE)
        P.jacobian(self.snes, X, P.J, P.J)
        P.J.assemble()
        return self._kept.copy_of(P.J, P.pattern_growths)

    def global_status(self, status: np.ndarray) -> np.ndarray:
        """The status of every multiplier on every rank (each rank knows its own)."""
        c = self.problem.contact
        mine = np.zeros(len(status), dtype=np.int64)
        own = c.mults[c.owned]
        mine[own] = status[own]
        return self.comm.allreduce(mine) > 0

    def _step(self, X: PETSc.Vec, z_new: np.ndarray, active: np.ndarray, B, Xs, y) -> None:
        """X += (Δq = y − Xs Δz, Δz), as far as it leaves a state the residual is defined at
        (no inverted element, every projection found: a large first increment's linearised
        step may not) and no fibre law's exponent k2 Ē² grows by more than
        ``MAX_EXPONENT_GROWTH`` (the Newton steps' and load predictors' limit, step_limits.py),
        halving it up to MAX_HALVINGS times; the status from z_new.  Its sections are turned
        where Newton's are (``StepLimits.turned``)."""
        P, c = self.problem, self.problem.contact
        exponents = P.limits.exponents(X)
        dz = z_new - self._z
        back, F = y.duplicate(), y.duplicate()
        dzv = self._dense_vec(Xs, dz)
        Xs.mult(dzv, back)
        back.axpy(-1.0, y)                     # −(Δq, Δz): the state is X − back, the update
        self._set_owned(back, -dz)             # form StepLimits.turned takes
        P.limits.turned(X, back)
        c.status[:] = active
        alpha = 1.0
        for _ in range(MAX_HALVINGS + 1):
            X.axpy(-alpha, back)
            P.residual(None, X, F)
            # the flags are this rank's: every rank must take the same branch (else one halves
            # and evaluates again while the other waits in the SNES: a hang on 2 ranks)
            if (not self.comm.allreduce(int(P.inverted or P.contact_failed))
                    and P.limits.exponent_growth(exponents, X) <= MAX_EXPONENT_GROWTH):
                break
            X.axpy(alpha, back)
            c.projector.restore()              # the failed trial's projections are no start
            alpha *= 0.5
        c.status[:] = active                   # the residual evaluations keep the status
        for v in (back, F, dzv):
            v.destroy()

    def _set_owned(self, vec: PETSc.Vec, values: np.ndarray) -> None:
        """vec[dof_k] = values[k] for the multipliers this rank owns."""
        lo, hi = vec.getOwnershipRange()
        mine = (self.dofs >= lo) & (self.dofs < hi)
        arr = vec.getArray()
        arr[self.dofs[mine] - lo] = values[mine]
        del arr

    def _dense_vec(self, A: PETSc.Mat, values: np.ndarray) -> PETSc.Vec:
        """A vector conforming to A's columns holding ``values`` (every rank has all of them)."""
        v = A.createVecRight()
        lo, hi = v.getOwnershipRange()
        v.setArray(values[lo:hi])
        return v
