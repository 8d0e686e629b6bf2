"""The first load increment from rest, bounded by the linear response (fibre-reinforced models).

A soft matrix with stiff fibres along a pretwist (the published GOH sets: μ = 15–107 kPa against
k1 = 1–75 MPa) is nearly a mechanism at rest: the tension of helical fibres twists the tendon
back, and only the matrix resists the untwist at first.  The untwist saturates as the fibres
straighten (measured on configs/achilles_type3_psi45_goh_alex.yaml at twist 45°, uniform bias:
the soleus' end moves 0.23 mm sideways at 0.25 N, 0.54 at 1 N, 1.36 at 8 N, 1.79 at 30 N and
1.92 at 100 N), so the response at rest is far stiffer than its linearisation predicts beyond
the first newton or so.  A first increment of the whole first level (30 N) from rest made the
first Newton step untwist the sections by several radians: the linearised rotation of the
gradient vectors stretched fibres to Ē = 0.44 (e^(k2 Ē²) growth allowed, k2 = 23.9), the contact
pairing was lost, and the stepper halved the increment five times (30 → 0.94 N) before one
converged: 200 of the level's 281 Newton iterations.  The tangent there is exact (central
differences to 1e-9); the fibres' tension-only switch is not the cause (fibres that carry
compression take the same path and the same cut-backs).

``bounded_first_increment`` solves the linearised problem at rest for the first increment once
(the tangent at the reference state, the SNES's own linear solver) and shrinks the increment so
that no section vector of a node (r_y, r_z: strains and rotations, dimensionless; r_yy, r_zz,
r_yz times the section size, a cubic element's r_yyy ... times its square) moves by more than ``REST_LINEAR_BOUND`` in that linear response:
within the range where the linearisation of a rotation stays accurate (a rotation θ stretches a
fibre across it by θ²/2 in the linear step).  Only for models with a fibre law: the isotropic
models' linear response at their first level is far inside the bound (the paper's columns:
0.036 at 10 N, configs/achilles_type3_psi45.yaml), as is the stiff-matrix GOH sets' (0.036 for
configs/achilles_type3_psi45_goh.yaml, whose path is unchanged), and the isotropic models take no
extra factorisation.  The soft-matrix sets' is 2.6 (alex, 10 N, the shipped config) to 3.0
(alex, 30 N, the envelope's twist 45°): their first increment becomes 1/26 to 1/30 of the level.
"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

#: largest change of a nodal gradient vector component in the linear response of the first
#: increment from rest (a strain or a rotation in radians): 0.1 rad is where the fibre stretch of
#: a linearised rotation (θ²/2 = 5e-3) reaches the fibre strains of the first levels
REST_LINEAR_BOUND = 0.1


def linear_gradient_change(problem, snes: PETSc.SNES, lam: float) -> float:
    """Largest |Δ| of a section-vector component (module docstring) of any beam node in the linear response at
    rest to the load factor ``lam`` (collective; inf when the solve fails).  The problem's
    contact is restored to its saved state afterwards."""
    P = problem
    X, F, dX, before = P.q0.copy(), P.q0.duplicate(), P.q0.duplicate(), P.load_factor
    try:
        P.load_factor = lam
        P.impose(X)
        P.residual(None, X, F)
        P.jacobian(None, X, P.J, P.J)
        ksp = snes.getKSP()
        ksp.setOperators(P.J, P.J)
        ksp.solve(F, dX)
        ok = ksp.getConvergedReason() > 0 and bool(np.isfinite(dX.norm()))
        d = np.abs(dX.getArray(readonly=True).reshape(-1, P.model.block.vectors_per_node, 3)[P.owned_physical])
        # r_y, r_z are dimensionless; a higher vector of section degree k (r_yy: per metre, r_yyy:
        # per square metre) counts times the section size^(k - 1)
        size = P.limits.size ** np.array([i + j - 1.0 for i, j in P.model.block.monomials])
        local = float((d[:, 1:] * size[None, 1:, None]).max(initial=0.0)) if ok else np.inf
        return P.comm.tompi4py().allreduce(local, op=MPI.MAX)
    finally:
        for v in (X, F, dX):
            v.destroy()
        P.restore()
        P.load_factor = before


def bounded_first_increment(problem, snes: PETSc.SNES, dlam: float, lam: float = 0.0) -> float:
    """The first increment ``dlam`` from rest at load factor ``lam`` (0, or a frame of zero
    loads), shrunk so that its linear response moves no gradient vector by more than
    ``REST_LINEAR_BOUND`` (module docstring); unchanged without a fibre law, or when the linear
    solve fails (the stepper's cut-backs then decide)."""
    if not problem.limits.fibres or dlam <= 0.0:
        return dlam
    change = linear_gradient_change(problem, snes, lam + dlam)
    if np.isfinite(change) and change > REST_LINEAR_BOUND:
        return dlam * REST_LINEAR_BOUND / change
    return dlam


def at_rest(problem, lam: float) -> bool:
    """Whether the converged state at load factor ``lam`` is the reference state, so that the
    next increment is one from rest (no load predictor, the contact weights kept): λ = 0, or
    every load and prescribed displacement zero at ``lam`` (a history unloaded to 0 N, or a table
    starting with a frame of zeros) without a contact law that remembers its path (friction's
    anchors).  Reloaded from such a frame with the tangent predictor and differentiated weights,
    the paper's tendon (2 elements, ψ = 45°) took 30 Newton iterations and a cut-back to
    150 / 50 / 50 N against 10 from rest, 228 and a cut-back with unilateral contact against 15."""
    c = problem.contact
    return lam == 0.0 or (problem.loads.unchanged(0.0, lam) and
                          (c is None or not any(t.history for t in c.terms)))


def increment_from_rest(stepper, lam: float, first_level: float, last_level: float | None) -> float:
    """The first increment from the rest state at load factor ``lam`` towards ``first_level``:
    the load control's (a contact law's share of the way, solver.initial_increment and
    max_increment), bounded by the linear response for a fibre law.  At λ = 0, and again at a
    history's frame of zero loads (``at_rest``), where the increment left by the unloading
    frames was kept: the soft GOH tendon (configs/achilles_type3_psi45_goh_alex.yaml at 2
    elements) reloaded from 0 to 30 N in 426 Newton iterations and 3 cut-backs against 58 from
    rest at the start of the run, to the same state."""
    c = stepper.problem.contact
    dlam = stepper.control.first_increment(first_level - lam, None if c is None else c.law.first_increment,
                                           None if last_level is None else last_level - lam,
                                           stepper.predictor is not None)
    if stepper.spec.initial_increment is None:         # fibre laws: the linear response's range
        dlam = bounded_first_increment(stepper.problem, stepper.solver.snes, dlam, lam)
    return dlam
