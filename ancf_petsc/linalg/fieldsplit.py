"""Fascicle-parallel linear solver: the saddle-point Jacobian split into fascicles | multipliers,
reduced to a Schur complement on the contact multipliers (``solver.linear: fieldsplit``).

With contact multipliers z (contact/multipliers.py) the Jacobian is

    J = [[K, Bᵀ], [B, C]],   K = diag(K_1 … K_n) + K_×,   B = [B_1 … B_n],

K_f the stiffness of fascicle (beam) f with the contact curvature −Σ τ ∇²g of its own points,
K_× the contact curvature that couples two fascicles (A's and B's nodes of a contact point),
B the constraint rows −k_s ∇ḡ (each multiplier couples the two fascicles of its interface) and
C diagonal (0 for active multipliers, −k_s × share for inactive ones).  Without K_× the fascicles
talk only through z, and block elimination (PCFIELDSPLIT's Schur factorisation) is exact:

    S = C − Σ_f B_f K_f⁻¹ B_fᵀ,   S z = r_z − Σ_f B_f K_f⁻¹ r_f,   u_f = K_f⁻¹ (r_f − B_fᵀ z).

``FascicleSchur`` is that exact inverse of J_bd = J − K_× as a PETSc preconditioner (PCPYTHON):
each rank factors its own fascicles' K_f (dense, diagonally scaled Cholesky, LU where K_f is
indefinite) and forms their blocks B_f K_f⁻¹ B_fᵀ of S; S itself is factored by substructuring
over the ranks (``substructure.SubstructuredSchur``: each rank's multipliers by its own MUMPS
factor, only those on the cut between two ranks' fascicles together).  The preconditioner works
in each rank's own multipliers (those of its fascicles, the cut's included): two scatters per
application.  A Krylov method (FGMRES, right preconditioned) on the full J absorbs K_×; it is
zero in an unloaded state, small beside K, and the residual falls by about 10× per iteration
under load.

Why it is cheaper than one LDLᵀ of J: K_f is a slender band (one fascicle), and S couples only
multipliers that share a fascicle.  Its graph is the cross-section of the bundle with every
interface a dense clique along the beam, which a nested dissection orders with fronts of the
size of a few interfaces, against fronts of the bundle's whole cross-section for J
(docs/parallel.md: 37 fascicles, 1.5e11 → 3.5e9 flops).

Stability: by Haynsworth's inertia additivity the inertia of J_bd is that of the K_f plus that
of S (``pivot_counts``): the stepper's count of negative tangent eigenvalues, for J_bd.

Every fascicle must be whole on one rank (``parallel.partition.beam_owner``) and held by its own supports
(K_f regular): ``choice.choose`` takes this solver only then.
"""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from . import logging
from .fascicles import FascicleFactor, FascicleSplit, fascicle_blocks
from .substructure import SubstructuredSchur

#: options prefix of the multiplier (Schur complement) factorisation: -fascicle_schur_...
SCHUR_PREFIX = "fascicle_schur_"
#: MUMPS settings of the Schur factorisations (each rank's, and the interface's where it is
#: distributed).  No null-pivot detection (unlike the direct solver): S is nearly singular where
#: constraints are nearly redundant (condition ~1e13 on 37 fascicles), and a pivot MUMPS drops
#: as null there leaves the preconditioner without a direction J has, so that GMRES stalls (37
#: fascicles: at 7e-5 instead of 11 iterations to 1e-9).  Delayed pivots outgrew MUMPS's default
#: 20 % workspace margin on 2 ranks (INFOG(1) = −9): 100 %.  AMD ordering (ICNTL(7) = 0): on the
#: distributed S of 37 fascicles 2.19 → 1.53 s for 9 factorisations against MUMPS's automatic
#: choice; on each rank's S^r the orderings AMD, AMF, PORD, QAMD take the same time.
#: A factor of S lagged by one Newton iteration is no preconditioner: FGMRES then stalls at
#: 100 iterations in the first increment.
SCHUR_ICNTL = {24: 0, 14: 100, 7: 0}

#: -log_view events of the solver's three phases
FACTOR_EVENT, SCHUR_EVENT, APPLY_EVENT = "ANCF fascicle factor", "ANCF Schur assembly", "ANCF fascicle apply"


class FascicleSchur:
    """PCPYTHON context: the exact inverse of J without the contact curvature between fascicles
    (module docstring).  ``setUp`` factors the local fascicles and the multiplier Schur
    complement; ``apply`` is one block elimination.  Collective."""

    def __init__(self, split: FascicleSplit, comm, prefix: str = ""):
        self.split, self.comm = split, comm
        self.prefix = prefix + SCHUR_PREFIX           # e.g. -left_fascicle_schur_mat_mumps_...
        sp_ = split
        # per fascicle: the node blocks of its nodes and of the multiplier nodes coupled to it
        # (SBAIJ extracts whole blocks, symmetrically), and its DOFs' positions in them
        self._is = []
        self._pos = []
        for u, m in zip(sp_.u_dofs, sp_.m_index):
            dofs = np.concatenate([u, sp_.z_dofs[m]])
            D = split.dofs_per_node
            blocks = np.unique(dofs // D)
            pos = (D * np.searchsorted(blocks, dofs // D) + dofs % D)
            self._is.append(PETSc.IS().createBlock(D, blocks.astype(PETSc.IntType), comm=PETSc.COMM_SELF))
            self._pos.append((pos[:len(u)], pos[len(u):]))
        self._subs = None
        self.factors: list[FascicleFactor] = []
        self.Bt: list[np.ndarray] = []
        self.schur = SubstructuredSchur(split, comm, self.prefix, SCHUR_ICNTL)
        self._u_local = None
        self._counts = (0, 0)
        self.setups = 0
        #: set per Newton iteration by the stepper: keep the last factors (``chord.TangentReuse``)
        self.keep_factors = False

    # ------------------------------------------------------------------ PCPYTHON interface
    def setUp(self, pc: PETSc.PC) -> None:
        if self.keep_factors and self.setups:
            return              # the previous iterate's factors (solving/chord.py), still exact J
        _, P = pc.getOperators()
        if self._u_local is None:
            rstart = P.getOwnershipRange()[0]
            self._u_local = [u - rstart for u in self.split.u_dofs]
            x = P.createVecLeft()
            self.schur.create_gather(x)
            x.destroy()
        logging.event(FACTOR_EVENT).begin()
        # fresh sub-matrices every time: the contact pattern of J grows when projections move
        # to other elements, and PETSc cannot reuse a sub-matrix whose pattern changed
        for sub in self._subs or []:
            sub.destroy()
        self._subs = P.createSubMatrices(self._is)
        self.factors, self.Bt = [], []
        blocks = []
        for sub, (iu, im) in zip(self._subs, self._pos):
            K, Bt = fascicle_blocks(sub, iu, im)
            f = FascicleFactor(K)
            self.factors.append(f)
            self.Bt.append(Bt)
            blocks.append(f.schur_block(Bt) if Bt.shape[1] else None)
        logging.event(FACTOR_EVENT).end()
        logging.event(SCHUR_EVENT).begin()
        diag = P.getDiagonal()                         # C: the multipliers' own diagonal
        c = self.schur.gather(diag)
        diag.destroy()
        self.schur.setup(blocks, c)
        logging.event(SCHUR_EVENT).end()
        local = np.array([sum(f.negative for f in self.factors), sum(f.null for f in self.factors)])
        total = np.empty_like(local)
        self.comm.tompi4py().Allreduce(local, total)
        self._counts = (int(total[0]), int(total[1]))
        self.setups += 1

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        logging.event(APPLY_EVENT).begin()
        xa = x.getArray(readonly=True)
        sc = self.schur
        # t = r_z − Σ_f B_f K_f⁻¹ r_f, over this rank's multipliers (its part of the cut's)
        t = sc.gather(x, once=True)
        for f, Bt, u, pos in zip(self.factors, self.Bt, self._u_local, sc.positions):
            t[pos] -= Bt.T @ f.solve(xa[u])
        z = sc.solve(t)
        # u_f = K_f⁻¹ (r_f − B_fᵀ z)
        x.copy(y)                                       # unused multiplier slots: identity rows
        ya = y.getArray()
        for f, Bt, u, pos in zip(self.factors, self.Bt, self._u_local, sc.positions):
            ya[u] = f.solve(xa[u] - Bt @ z[pos])
        del ya, xa
        sc.put(z, y)
        logging.event(APPLY_EVENT).end()

    def view(self, pc: PETSc.PC, viewer) -> None:
        n = self.comm.tompi4py().allreduce(len(self.factors))
        sc = self.schur
        cut = (f"; {sc.n_gamma} on the cut between ranks, {type(sc.interface).__name__}"
               if sc.interface is not None else "")
        viewer.printfASCII(f"  fascicle Schur: {n} fascicles factored densely, Schur complement on "
                           f"{self.split.n_multipliers} multipliers (MUMPS LDLT per rank{cut}; "
                           f"prefix -{self.prefix})\n")

    def destroy(self, pc: PETSc.PC) -> None:
        self.schur.destroy()
        for obj in list(self._is) + list(self._subs or []):
            obj.destroy()
        self._subs, self._is = None, []

    # ------------------------------------------------------------------ stability
    def pivot_counts(self) -> tuple[int, int] | None:
        """(negative, null) pivots of J_bd: those of the fascicle factors plus those of S's MUMPS
        LDLᵀ (``inertia.pivot_counts``; collective, None before the first set-up or where MUMPS
        does not count them)."""
        if self.setups == 0:
            return None
        counts = self.schur.pivot_counts()
        if counts is None:
            return None
        return self._counts[0] + counts[0], self._counts[1] + counts[1]
