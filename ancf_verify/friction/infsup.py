"""Which contact pressure space the beams' section kinematics determine (issue 42): the discrete
inf-sup constant of the pressure space across the interface on each element order, at rest.

The sliding constraints are B q = 0 with B_kp = ∫ φ_k ∂g/∂q dA (the weighted gaps); the pressure
λ = Σ λ_k φ_k is determined by the kinematics when no pressure mode does (almost) no work on
every displacement, that is when

    β² = min_λ  λᵀ B K⁻¹ Bᵀ λ / λᵀ M λ,      M_kl = ∫ φ_k φ_l dA,

is bounded away from zero (K: the beams' stiffness at rest, supports held; the pressure
measured in L² over the interface, as in a Taylor–Hood analysis).  In the solver's unknowns
(z_k = λ_k A_k / k_s, constraint rows k_s Φ ∂g/∂q with Φ_kp = w_p φ_k(p) / A_k) this is the
generalised eigenproblem S y = β² k_s² Φ W⁻¹ Φᵀ y with S = G K⁻¹ Gᵀ, G the Jacobian's
constraint rows.  β² is shown as β² E / ℓ (E the soleus' small-strain modulus, ℓ = √area of its
section: dimensionless), per interface (the eigenproblem restricted to its multipliers) and
over all.  A pairing is stable when β² stays put as the elements are refined and when raising
the degree across lowers it by a bounded factor; a degree whose top mode finds no gap mode of the
section field to act on shows up as a drop by orders of magnitude.  Dense, one rank, friction off.
"""
from __future__ import annotations

import os
from dataclasses import replace

import numpy as np

from ancf_verify.contact.tendon import SOURCE
from ancf_verify.friction.beams import ancf_config
from ancf_verify.friction.rows import IFACES


def problem(element: str | None, elements: int, space: str | None, out: str):
    """The beams' Problem of the friction comparison without friction (one rank, at rest)."""
    from petsc4py import PETSc
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.contact import build_contact
    from ancf_petsc.model.build import build_model
    from ancf_petsc.parallel.partition import make_layout
    from ancf_petsc.petsc.problem import Problem
    raw = ancf_config(45.0, elements, 0.0, None, out, space, element=element)
    del raw["contact"]["tangential"]
    # a space with more functions across than the sections determine (the cubic across 3363,
    # which this study measures) is refused by the config (config/contact._bounded_across): it is
    # parsed with one function fewer across and given its own after
    across = raw["contact"].get("projection", {}).get("curve")
    if across is not None:
        raw["contact"]["projection"]["curve"] = min(across, 2)
    spec = parse_config(raw, base_dir=SOURCE.configs)
    if across is not None:
        spec.contact = replace(spec.contact, projection=(spec.contact.projection[0], across))
    model = build_model(spec)
    contact = build_contact(model, spec.contact, lambda *_: None)
    comm = PETSc.COMM_WORLD
    layout = make_layout(model, "blocks", comm.size, comm.rank, contact, comm.tompi4py())
    return Problem(model, layout, comm, contact, "aij")


def blocks(P) -> tuple:
    """(K, G) at rest: the stiffness over the free physical DOFs, the constraint rows."""
    from ancf_petsc.petsc.complementarity import multiplier_dofs
    X = P.q0.copy()
    P.load_factor = 0.0
    P.impose(X)
    F = X.duplicate()
    P.residual(None, X, F)
    P.jacobian(None, X, P.J, P.J)
    J = P.J.convert("dense").getDenseArray().copy()
    mult = multiplier_dofs(P)
    held = np.array([np.count_nonzero(J[i]) == 1 and J[i, i] != 0 for i in range(J.shape[0])])
    taken = np.zeros(J.shape[0], dtype=bool)
    taken[mult] = True
    phys = np.flatnonzero(~taken & ~held)
    return J[np.ix_(phys, phys)], J[np.ix_(mult, phys)]


def infsup(element: str | None, elements: int, space: str | None, tmp: str) -> dict:
    """β² E / ℓ of one element order, mesh and pressure space: over all interfaces and per
    interface, with the number of multipliers."""
    from scipy.linalg import eigh
    from ancf_petsc.contact.multipliers import reference_modulus
    P = problem(element, elements, space, os.path.join(tmp, f"infsup_{element}_{elements}_{space}"))
    c = P.contact
    K, G = blocks(P)
    S = G @ np.linalg.solve(K, G.T)
    S = 0.5 * (S + S.T)
    Phi = c.space.Phi.toarray()
    M = c.space.stiffness ** 2 * (Phi / c.points.w[None, :]) @ Phi.T
    beam = P.model.beams[0]
    scale = reference_modulus(beam) / np.sqrt(beam.section.area)
    out = {"element": element or "3363", "elements": elements, "space": space, "multipliers": len(S),
           "all": scale * float(eigh(S, M, eigvals_only=True)[0])}
    for i, name in enumerate(IFACES):
        m = np.flatnonzero(c.space.interface == i)
        out[name] = scale * float(eigh(S[np.ix_(m, m)], M[np.ix_(m, m)], eigvals_only=True)[0])
    return out
