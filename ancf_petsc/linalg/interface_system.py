"""The interface system Σ of the substructured multiplier Schur complement (substructure.py):

    Σ = C_Γ + Σ_r Σ^r,   Σ^r = S_ΓΓ^r − S_ΓI^r (S_II^r)⁻¹ S_IΓ^r   (dense on rank r's cut Γ_r),

on the multipliers Γ between two ranks' fascicle patches.  Two ways to hold it, chosen by its
size n_Γ (``interface_kind``):

* ``DenseInterface``: every rank sums the dense Σ^r into the whole n_Γ × n_Γ matrix (one
  Allreduce per set-up) and factors it itself (LAPACK, ``FascicleFactor`` of −Σ); each solve is one
  Allreduce of an n_Γ vector and a redundant dense solve.  37 fascicles on 2 ranks: n_Γ = 858,
  ~0.01 s per factorisation.  Its n_Γ² memory and n_Γ³ flops per rank rule it out on many ranks.
* ``DistributedInterface``: Σ as a distributed sparse matrix (rows with the multipliers' owners,
  the Σ^r added where they fall) factored by MUMPS LDLᵀ on all ranks.

Both give Σ's inertia for the stability count (the distributed one only with MUMPS's sequential
root front, ICNTL(13) = 1, which it asks for on up to 4 ranks).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI
from petsc4py import PETSc

from ..errors import InputError
from .database import option
from .fascicles import FascicleFactor
from .inertia import pivot_counts
from .mumps_schur import mumps_controls

ADD, INSERT = PETSc.InsertMode.ADD_VALUES, PETSc.InsertMode.INSERT_VALUES
FORWARD, REVERSE = PETSc.ScatterMode.FORWARD, PETSc.ScatterMode.REVERSE
#: the dense interface up to this many cut multipliers (n_Γ² doubles = 32 MB per rank at 2 000),
#: MUMPS on the distributed Σ beyond; -<prefix>interface dense | mumps chooses explicitly
DENSE_MAX = 2000
KINDS = ("dense", "mumps")


def interface_kind(n_gamma: int, prefix: str) -> str:
    """'dense' or 'mumps' for an interface of n_Γ multipliers (option -<prefix>interface)."""
    kind = option("interface", prefix)
    if kind is not None:
        if kind not in KINDS:
            raise InputError("", f"-{prefix}interface {kind}: expected {' or '.join(KINDS)}")
        return kind
    return "dense" if n_gamma <= DENSE_MAX else "mumps"


class DenseInterface:
    """Σ summed on every rank and factored densely there (module docstring)."""

    def __init__(self, n_gamma: int, g_ids: np.ndarray, mpi):
        self.n, self.g_ids, self.mpi = n_gamma, g_ids, mpi
        self.factor: FascicleFactor | None = None

    def set_up(self, local: np.ndarray | None, once: np.ndarray, c_once: np.ndarray) -> None:
        """Σ from this rank's Σ^r (``local``, on ``g_ids``; None without a cut) and C_Γ at the
        interface numbers ``once`` (each added by one rank only).  Collective."""
        sigma = np.zeros((self.n, self.n))
        if local is not None:
            sigma[np.ix_(self.g_ids, self.g_ids)] = local
        sigma[once, once] += c_once
        self.mpi.Allreduce(MPI.IN_PLACE, sigma)
        self.factor = FascicleFactor(-sigma)         # −Σ: positive definite where K_f are

    def solve(self, part: np.ndarray) -> np.ndarray:
        """Σ⁻¹ (Σ_r part_r) at ``g_ids``; ``part`` is this rank's share of the right-hand side
        at ``g_ids``.  Collective."""
        rhs = np.zeros(self.n)
        rhs[self.g_ids] = part
        self.mpi.Allreduce(MPI.IN_PLACE, rhs)
        return -self.factor.solve(rhs)[self.g_ids]

    def pivot_counts(self) -> tuple[int, int]:
        f = self.factor
        return self.n - f.negative - f.null, f.null

    def destroy(self) -> None:
        self.factor = None


class DistributedInterface:
    """Σ as a distributed AIJ matrix factored by MUMPS LDLᵀ on all ranks (module docstring)."""

    def __init__(self, n_gamma: int, g_ids: np.ndarray, g_range: tuple, comm: PETSc.Comm,
                 prefix: str, mumps: dict):
        self.n, self.g_ids, self.comm = n_gamma, g_ids, comm
        g0, g1 = g_range
        self.sigma = PETSc.Mat().createAIJ(((g1 - g0, n_gamma), (g1 - g0, n_gamma)), comm=comm)
        # pattern: the cliques Γ_r × Γ_r of every rank
        lists = comm.tompi4py().allgather(g_ids)
        rows = np.concatenate([np.asarray(g, dtype=np.int64) for g in lists])
        cols = np.concatenate([np.full(len(g), r, dtype=np.int64) for r, g in enumerate(lists)])
        R = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n_gamma, len(lists)))
        pattern = (R[g0:g1] @ R.T).tocsr()
        pattern.sort_indices()
        self.sigma.setPreallocationCSR((pattern.indptr.astype(PETSc.IntType),
                                        pattern.indices.astype(PETSc.IntType)))
        self.sigma.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        self.sigma.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        self.rhs, self.sol = self.sigma.createVecs()
        self.local = PETSc.Vec().createSeq(len(g_ids), comm=PETSc.COMM_SELF)
        is_g = PETSc.IS().createGeneral(np.asarray(g_ids, dtype=PETSc.IntType), comm=PETSc.COMM_SELF)
        self.scatter = PETSc.Scatter().create(self.sol, is_g, self.local, None)
        is_g.destroy()
        self.ksp = PETSc.KSP().create(comm=comm)
        self.ksp.setOptionsPrefix(prefix)
        self.ksp.setType("preonly")
        pc = self.ksp.getPC()
        pc.setType("cholesky")
        pc.setFactorSolverType("mumps")
        self.ksp.setFromOptions()
        defaults = dict(mumps)
        if 1 < comm.getSize() <= 4:
            defaults[13] = 1                 # a sequential root front: its inertia is complete
        self.icntl, _ = mumps_controls(prefix, defaults)  # PETSc reads the CNTLs itself
        self.set_ups = 0

    def set_up(self, local: np.ndarray | None, once: np.ndarray, c_once: np.ndarray) -> None:
        S = self.sigma
        S.zeroEntries()
        if local is not None:
            idx = np.asarray(self.g_ids, dtype=PETSc.IntType)
            S.setValues(idx, idx, local, ADD)
        if len(once):                        # (petsc4py divides by the row count)
            d = np.asarray(once, dtype=PETSc.IntType)[:, None]
            S.setValuesRCV(d, d, np.asarray(c_once, dtype=float)[:, None, None], ADD)
        S.assemble()
        self.ksp.setOperators(S)
        if self.set_ups == 0:
            pc = self.ksp.getPC()
            pc.setFactorSetUpSolverType()
            F = pc.getFactorMatrix()
            for k, v in self.icntl.items():
                F.setMumpsIcntl(k, v)
        self.ksp.setUp()
        self.set_ups += 1

    def solve(self, part: np.ndarray) -> np.ndarray:
        self.local.setArray(part)
        self.rhs.set(0.0)
        self.scatter.scatter(self.local, self.rhs, ADD, REVERSE)
        self.ksp.solve(self.rhs, self.sol)
        self.scatter.scatter(self.sol, self.local, INSERT, FORWARD)
        return self.local.getArray(readonly=True).copy()

    def pivot_counts(self) -> tuple[int, int] | None:
        return pivot_counts(self.ksp)

    def destroy(self) -> None:
        for obj in (self.sigma, self.rhs, self.sol, self.local, self.scatter, self.ksp):
            obj.destroy()
