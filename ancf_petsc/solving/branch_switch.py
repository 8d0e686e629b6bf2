"""Branch switching at a bifurcation of the load path (issue 38; docs/gait.md, "Bifurcations").

Load control follows one branch of equilibria.  Where that branch loses stability within a
sub-step (it converges on a state whose tangent has more negative eigenvalues than the last
accepted one: a bifurcation or limit point was passed), the stepper cuts back; when every
smaller step fails too, the run would stop there, and when its retries are spent it would accept
the unstable state (status ``unstable``).  That state is the branch point: along its critical
mode (an eigenvector of a negative eigenvalue of the tangent, dense over the free DOFs) the
potential falls away from it, and a stable state lies on one or both sides.

``BranchSwitch`` keeps the latest converged state with a negative eigenvalue (``remember``, with
a copy of the tangent it converged with).  Where the stepper, on a stable path, would accept it,
or would give up with it still ahead of the path, the switch perturbs
it along ± the mode by a = ``AMPLITUDES`` × the section size (the largest displacement of a
section cubature point), solves at the same load and keeps a converged stable state
(``switch``).  A path already on saddles (``solver.allow_unstable``, or accepted after a switch
found nothing) goes on as it is.  Of the two sides, the
lower total potential Π = Σ∫Ψ dV − f·q is taken with a frictionless law (at a converged state
the multipliers' term vanishes: gaps closed or multipliers zero), the smaller jump with friction
or an elastic interface (no potential); a larger amplitude is only tried when neither side
reached a stable state at a smaller one; where turned Newton steps find none, with straight ones
(``StepLimits.straight``: the solves start far from equilibrium).  Runs that never meet a less
stable state are not touched.  Every switch is logged, kept in the level's record (summary.json
``branch_switches``) and named in the final message.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc
from scipy import sparse
from scipy.sparse.linalg import eigsh

from ..petsc.potential import constrained_potential
from .solver_messages import switch_line

#: perturbation sizes, in units of the section size sqrt(largest section area), tried in turn: a
#: tendon's subtendons held by contact find a stable state 0.3-3 mm away (docs/gait.md: the 180 deg
#: unilateral strides and column, sections of ~4.5 mm); a free column past Euler's load only at
#: the post-buckled elastica's deflection, ~0.5 L at 1.09 P_cr (tests/solving/test_branch_switch.py)
AMPLITUDES = (0.07, 0.22, 0.67, 2.0, 6.0, 20.0, 60.0)
#: a mode is mechanical when this share of its squared norm is on beam-node DOFs (the KKT
#: tangent's constraint eigenvectors live on the multipliers); at most MAX_MODES modes are tried
NODE_SHARE, MAX_MODES = 0.5, 2
#: free DOFs up to which the tangent's eigenpairs are all computed (dense); beyond, the
#: ``SPARSE_PAIRS`` nearest zero from below (a 16-element tendon has ~2 500)
DENSE_LIMIT = 4000
SPARSE_PAIRS = 24
#: a snap's load factors (``BranchSwitch.snap``), as shares beyond the critical state's, tried in
#: turn (capped at the level): the second subject's sliding columns (critical_point.py) were
#: passed at the first
SNAP_STEPS = (1e-3, 1e-2, 1e-1)
#: a snap's perturbation sizes: the stable states found beyond the envelope's critical points lay
#: 0.24-0.63 mm (and 2.7 mm on a soft-matrix column) from them, 0.05-0.6 section sizes
SNAP_AMPLITUDES = AMPLITUDES[:4]


#: a switch's ``kind`` in its report: from an unstable state at its load, or (``snap``) from a
#: stable critical point to a load just beyond it (critical_point.py)
BIFURCATION, LIMIT_POINT = "bifurcation", "limit point"


@dataclass
class BranchPoint:
    """An unstable converged state ahead of the path: its load factor, state, the tangent it
    converged with, its negative eigenvalues and whether a switch from it was tried.  A snap's
    (``kind`` LIMIT_POINT) is the critical state to be left at the load factor ``lam`` beyond
    it (``origin``: its own and its critical_point share), along the given ``modes`` and
    ``amplitudes`` (no tangent kept)."""
    lam: float
    X: PETSc.Vec
    J: PETSc.Mat | None
    negative: int
    step: float                 # the sub-step that reached it (the increment after a switch)
    tried: bool = False
    kind: str = BIFURCATION
    origin: tuple[float, float] | None = None    # a snap's: the critical state's load factor, share
    modes: list | None = None
    amplitudes: tuple = AMPLITUDES

    def destroy(self) -> None:
        self.X.destroy()
        if self.J is not None:
            self.J.destroy()


class BranchSwitch:
    """The branch point of a load path and the switch from it (collective where noted)."""

    def __init__(self, problem, enabled: bool = True):
        self.problem, self.enabled = problem, enabled
        self.point: BranchPoint | None = None
        self.resumed: tuple[int, int | None] = (0, None)   # ``resume``'s (reason, negative)
        self.outcome = ""                       # why the last switch found nothing (the log's)

    def remember(self, lam: float, X: PETSc.Vec, J: PETSc.Mat, negative: int, reached: float) -> None:
        """A sub-step from ``reached`` converged at ``lam`` on a state with ``negative``
        eigenvalues > 0 and tangent ``J``: the latest such state is the branch point."""
        if not self.enabled:
            return
        if self.point is not None:
            self.point.destroy()
        self.point = BranchPoint(lam, X.copy(), J.copy(), negative, lam - reached)

    def pending(self, reached: float) -> BranchPoint | None:
        """The untried branch point at or ahead of ``reached``, if any."""
        p = self.point
        return p if p is not None and not p.tried and p.lam >= reached else None

    def resume(self, stepper, path, target: float) -> None:
        """Back to the (tried) branch point's own state after a switch found nothing: solved
        for again from its copy so that the contact state is its own; ``resumed``: the solve's
        reason and negative eigenvalues.  Collective."""
        P, point = self.problem, self.point
        P.restore()
        point.X.copy(P.X)
        snes = stepper.solver.snes
        snes.setForceIteration(True)            # a Newton step from the converged copy: the factor
        try:                                    # (inertia, tangent predictor) is its own
            reason, _, fnorm = stepper.solve_at(point.lam, P.X, target, path.lam)
        finally:
            snes.setForceIteration(False)
        neg = stable_verdict(stepper, reason, fnorm)
        self.resumed = (reason if neg is not None else min(reason, -1), neg)

    def destroy(self) -> None:
        if self.point is not None:
            self.point.destroy()
            self.point = None

    def applies(self, path, negative: int | None) -> bool:
        """Whether a converged sub-step, its stability retries spent, is about to be accepted as
        a saddle where the last accepted state was stable: a switch is tried first."""
        return self.enabled and path.accepted_negative == 0 and bool(negative)

    def take(self, stepper, path, X_prev: PETSc.Vec, target: float, tally, resume: bool) -> bool:
        """Switch from the pending branch point and accept the state reached as ``path``'s
        (logged, reported in ``tally.switches``, its Newton iterations in ``tally.its``); at a
        give-up, or (``resume``) instead of accepting the saddle, which is solved for again
        when no switch works (``resumed``).  False when there was no point or no stable state.
        Collective."""
        P, point = self.problem, self.pending(path.lam)
        if point is None or path.accepted_negative > 0:      # a path already on saddles: as it is
            return False
        its0 = stepper.newton_iterations
        report = self.switch(stepper, point, path, target)
        if report is None:
            stepper.log(f"  {'snap' if point.kind == LIMIT_POINT else 'branch switch'} at load factor "
                        f"{point.lam:.6g}: {self.outcome}")
            if resume:
                self.resume(stepper, path, target)
            else:
                X_prev.copy(P.X)
                P.restore()
            tally.its += stepper.newton_iterations - its0
            return False
        report["iterations"] = stepper.newton_iterations - its0
        tally.its += report["iterations"]
        stepper.log(switch_line(report))
        tally.switches.append(report)
        tally.substeps, tally.consecutive = tally.substeps + 1, 0
        P.checkpoint()
        stepper.tangent.valid = False           # the SNES's factor: the chosen side's settling solve
        path.accepted_negative = report["negative_after"]
        path.dX_last.set(0.0)                   # no load predictor across the jump
        path.dlam_last, path.lam = 0.0, report["load_factor"]
        path.dlam = max(point.step, stepper.spec.min_increment)
        return True

    def snaps(self, path) -> bool:
        """Whether a snap is tried from ``path``'s state: switching is on (LDLᵀ's inertia tells a
        stable state), the path is stable and has left rest."""
        return self.enabled and not path.accepted_negative and path.lam > 0.0

    def snap(self, stepper, path, X_prev: PETSc.Vec, target: float, tally, critical) -> bool:
        """Past the critical point ``critical`` (critical_point.CriticalPoint: the stable state
        of ``path`` in ``X_prev``, which ``take`` restores after a failure): the switch along its
        mode to each load factor of ``SNAP_STEPS`` beyond it in turn, until one reaches a stable state.
        Collective."""
        if not self.snaps(path):
            return False
        for share in SNAP_STEPS:
            lam = min(path.lam * (1.0 + share), target)
            if self.point is not None:
                self.point.destroy()
            self.point = BranchPoint(lam, X_prev.copy(), None, 0, lam - path.lam, kind=LIMIT_POINT,
                                     origin=(path.lam, critical.share),
                                     modes=[(critical.eigenvalue, critical.mode.copy())],
                                     amplitudes=SNAP_AMPLITUDES)
            if self.take(stepper, path, X_prev, target, tally, resume=False):
                return True
        return False

    def switch(self, stepper, point: BranchPoint, path, target: float) -> dict | None:
        """Perturb the branch point ``point`` (reached from a stable path) along its critical
        modes (``AMPLITUDES``, both signs) and solve at its load; on success leave the chosen
        stable state in ``problem.X`` with its own contact state and return its report, else
        restore the last checkpoint and return None.  Collective."""
        P = self.problem
        point.tried = True
        size = section_size(P.model)
        modes = (point.modes if point.modes is not None
                 else critical_modes(P, point.J, min(MAX_MODES, point.negative)))
        self.outcome = ("no stable state along the critical mode(s)" if modes else "its tangent has no negative eigenvalue " + (
            "whose vector is on the beam nodes (the count's saddle lies mostly on the contact multipliers)" if P.contact is not None
            else "(the count is of null pivots: modes the factorisation rounds to 0)") + ": nothing to switch along")
        conservative = P.contact is None or not P.contact.terms
        P.load_factor = point.lam
        base = constrained_potential(P, point.X) if conservative else None
        try:
            args = (stepper, point, modes, size, conservative, base, path, target)
            report = self._switch_along(*args)
            if report is None and P.limits.turns is not None:   # an Euler column's elastica at 0.46 L
                with P.limits.straight():
                    report = self._switch_along(*args)
            return report
        finally:
            for _, mode in modes:
                mode.destroy()

    def _switch_along(self, stepper, point: BranchPoint, modes: list, size: float, conservative: bool,
                      base: float | None, path, target: float) -> dict | None:
        """``switch``'s ladder: every mode, amplitude and sign in turn."""
        P = self.problem
        for eigenvalue, mode in modes:
            scale = size / max(section_displacement(P, mode), 1e-300)
            for amplitude in point.amplitudes:
                found = []
                for sign in (1.0, -1.0):
                    neg = self._attempt(stepper, point, mode, sign * amplitude * scale, path, target)
                    if neg == 0:
                        found.append(self._side(P, point, sign, neg, conservative))
                side = self._keep(stepper, point, mode, found, amplitude * scale, path, target,
                                  "potential" if conservative else "jump")
                if side is not None:
                    report = {"kind": point.kind, "load_factor": point.lam, "negative_before": point.negative,
                              "negative_after": side["negative"], "sign": side["sign"],
                              "jump": side["jump"], "eigenvalue": eigenvalue, "amplitude": amplitude * size,
                              "sides": len(found), "rule": "lower potential" if conservative else "smaller jump"}
                    if base is not None:
                        report["potential_drop"] = base - side["potential"]
                    if point.origin is not None:
                        report["critical_load_factor"], report["critical_share"] = point.origin
                    return report
        P.restore()
        return None

    def _attempt(self, stepper, point: BranchPoint, mode: PETSc.Vec, offset: float, path,
                 target: float) -> int | None:
        """Newton at the point's load from the point moved by ``offset`` along ``mode``, the
        contact state the last checkpoint's: the verdict (``stable_verdict``).  Deterministic:
        the same offset reaches the same state."""
        P = self.problem
        P.restore()
        point.X.copy(P.X)
        P.X.axpy(offset, mode)
        reason, _, fnorm = stepper.solve_at(point.lam, P.X, target, path.lam)
        return stable_verdict(stepper, reason, fnorm)

    def _side(self, P, point: BranchPoint, sign: float, neg: int, conservative: bool) -> dict:
        """One side's converged stable state: its jump from the branch point [m] (largest
        section-point displacement) and its potential (frictionless laws)."""
        d = P.X.copy()
        d.axpy(-1.0, point.X)
        jump = section_displacement(P, d)
        d.destroy()
        return {"sign": sign, "negative": neg, "jump": jump,
                "potential": constrained_potential(P, P.X) if conservative else None}

    def _keep(self, stepper, point: BranchPoint, mode: PETSc.Vec, found: list[dict], offset: float,
              path, target: float, key: str) -> dict | None:
        """The side to go on from, its state in ``problem.X`` with its own contact state: the
        preferred one, solved for again unless it was the last solved (the "−" side); the
        other when that solve does not reach it again; None when neither holds."""
        last = -1.0                                  # the sign of the state in problem.X
        for side in sorted(found, key=lambda s: s is not preferred(found, key)):
            if side["sign"] == last:
                return side
            neg = self._attempt(stepper, point, mode, side["sign"] * offset, path, target)
            last = side["sign"] if neg == 0 else 0.0
            if last:
                return side
        return None


def stable_verdict(stepper, reason: int, fnorm: float) -> int | None:
    """The negative tangent eigenvalues of a solve that converged to a clean state with a small
    residual, None for any other solve (or without an inertia count)."""
    ok = (reason > 0 and stepper.solver.residual_small(reason, fnorm) and np.isfinite(fnorm)
          and stepper.problem.state_is_clean())
    return stepper.solver.negative_eigenvalues(stepper.problem.X) if ok else None


def section_size(model) -> float:
    """sqrt of the largest section area [m] (the unit of the perturbation amplitudes)."""
    return float(np.sqrt(max(float(np.sum(b.section.weights)) for b in model.beams)))


def section_displacement(problem, V: PETSc.Vec) -> float:
    """The largest displacement of a section cubature point of any beam node for nodal
    increments ``V`` (Σ_k m_k(y, z) V_k over the section's points); the same on every rank."""
    g = problem.gather(V)
    value = 0.0
    if problem.comm.rank == 0:
        model = problem.model
        node_beam = model.node_beam()
        for b in model.beams:
            m = model.block.section_monomials(b.section.points[:, 0], b.section.points[:, 1])
            u = np.einsum("pk,nkc->npc", m, g[node_beam == b.index])
            value = max(value, float(np.sqrt(np.max(np.sum(u * u, axis=2)))))
    return float(problem.comm.tompi4py().bcast(value, root=0))


def critical_modes(problem, J: PETSc.Mat, count: int) -> list[tuple[float, PETSc.Vec]]:
    """Up to ``count`` eigenpairs of the tangent ``J`` over the free DOFs with a negative
    eigenvalue and a mechanical eigenvector (``NODE_SHARE`` on beam nodes), smallest |λ| first,
    computed on rank 0 (``eigenpairs``; the KKT matrix's constraint eigenvalues are −1e5 … −1e6
    and their vectors live on the multipliers), the vectors scattered back."""
    A = matrix_on_zero(J)
    pairs = []
    if problem.comm.rank == 0:
        free = ~problem.fixed_mask
        w, V = eigenpairs(A[free][:, free])
        node = node_rows(problem, free)
        for i in np.argsort(np.abs(w)):
            if w[i] < 0.0 and np.sum(V[node, i] ** 2) >= NODE_SHARE:
                pairs.append((float(w[i]), oriented_mode(problem, free, V[:, i])))
            if len(pairs) == count:
                break
    pairs = problem.comm.tompi4py().bcast(pairs, root=0)
    return [(w, scattered(problem, full)) for w, full in pairs]


def node_rows(problem, free: np.ndarray) -> np.ndarray:
    """Which of the ``free`` DOFs (the global order, rank 0) are beam-node DOFs, not multipliers'."""
    return np.repeat(np.argsort(problem.layout.perm) < problem.model.n_nodes, problem.model.dofs_per_node)[free]


def oriented_mode(problem, free: np.ndarray, values: np.ndarray) -> np.ndarray:
    """A mode over the ``free`` DOFs as an array over every DOF (0 on the held ones), its sign
    the same on every rank count (``orientation``)."""
    full = np.zeros(len(free))
    full[free] = values
    return full * orientation(problem, full)


def scattered(problem, full: np.ndarray) -> PETSc.Vec:
    """An array over every DOF (the same on every rank) as a vector laid out as problem.X."""
    v = problem.X.duplicate()
    v.setArray(full[slice(*v.getOwnershipRange())])
    return v


def eigenpairs(A: sparse.csr_matrix) -> tuple[np.ndarray, np.ndarray]:
    """Eigenpairs of the symmetric ``A``: all of them (dense) up to ``DENSE_LIMIT`` rows, else the
    ``SPARSE_PAIRS`` nearest a shift just below 0 (shift-invert Lanczos, ARPACK), which holds the
    small negative mechanical ones and not the constraints' −1e5 …"""
    n = A.shape[0]
    if n <= DENSE_LIMIT:
        return np.linalg.eigh(A.toarray())
    shift = -1e-9 * float(np.abs(A.diagonal()).max())
    return eigsh(A.tocsc(), k=min(SPARSE_PAIRS, n - 2), sigma=shift, which="LM")


def orientation(problem, full: np.ndarray) -> float:
    """±1 making a mode's largest beam-node component (in the model's order, which no partition
    changes) positive: the same side is "+" on every rank count."""
    D = problem.model.dofs_per_node
    nodes = full.reshape(-1, D)[problem.layout.perm][:problem.model.n_nodes].ravel()
    return 1.0 if nodes[np.argmax(np.abs(nodes))] >= 0.0 else -1.0


def preferred(sides: list[dict], key: str) -> dict:
    """The side with the smallest ``key``; the first (the "+" side) unless another is smaller by
    more than rounding (1e-9 of the values): a symmetric bifurcation picks the same side on every
    rank count."""
    best = sides[0]
    for side in sides[1:]:
        if side[key] < best[key] - 1e-9 * max(abs(side[key]), abs(best[key])):
            best = side
    return best


def matrix_on_zero(J: PETSc.Mat) -> sparse.csr_matrix | None:
    """The whole matrix ``J`` as a symmetric scipy CSR matrix on rank 0 (None elsewhere); an
    upper-triangle storage (SBAIJ, or AIJ holding one triangle for Cholesky) is mirrored."""
    A = J.convert("aij", PETSc.Mat()) if J.getType() not in ("seqaij", "mpiaij") else J
    n, rank = A.getSize()[0], A.getComm().getRank()
    rows = PETSc.IS().createStride(n if rank == 0 else 0, 0, 1, comm=PETSc.COMM_SELF)
    sub = A.createSubMatrices(rows, rows)[0]
    out = None
    if rank == 0:
        ai, aj, av = sub.getValuesCSR()
        out = sparse.csr_matrix((av, aj, ai), shape=(n, n))
        if sparse.tril(out, -1).nnz == 0:
            out = (out + sparse.triu(out, 1).T).tocsr()
    for obj in (sub, rows) + ((A,) if A is not J else ()):
        obj.destroy()
    return out
