"""The multiplier Schur complement S of the fascicle-parallel solver (fieldsplit.py), factored by
substructuring over the ranks' fascicle patches.

S = C − Σ_f B_f K_f⁻¹ B_fᵀ couples two multipliers when they touch a common fascicle.  Every
fascicle is whole on one rank, so a multiplier between two fascicles of rank r is *interior* to r
(I_r: every entry of its row comes from r's fascicles), and a multiplier between fascicles of two
ranks lies on the *interface* Γ (the cut).  Rank r's fascicles alone give

    S^r = [[S_II^r, S_IΓ^r], [S_ΓI^r, S_ΓΓ^r]]   (C added on I_r),

and S = Σ_r S^r (extended by zero), an arrow matrix with one block per rank.  Block elimination
leaves a system on the interface only:

    Σ = C_Γ + Σ_r (S_ΓΓ^r − S_ΓI^r (S_II^r)⁻¹ S_IΓ^r),
    Σ z_Γ = t_Γ − Σ_r S_ΓI^r (S_II^r)⁻¹ t_I^r,      z_I^r = (S_II^r)⁻¹ (t_I^r − S_IΓ^r z_Γ).

Each rank factors S^r with sequential MUMPS LDLᵀ, which forms its Schur complement on Γ_r itself
(ICNTL(19): PETSc's MatFactorSetSchurIS, called through ctypes since petsc4py 3.18 does not wrap
it); no MPI until the Schur complements are summed (one Allreduce of the dense n_Γ × n_Γ
matrix).  Σ is small (the multipliers on the cut: 858 of 5 940 for 37 fascicles on two ranks), so
every rank factors it densely (``FascicleFactor``) and solves it redundantly: one Allreduce of an
n_Γ vector per application.  On one rank Γ is empty and this is one MUMPS factorisation of S.

Inertia adds up (Haynsworth): S's negative pivots are those of every S_II^r (MUMPS's INFOG(12)
counts the eliminated rows only) plus Σ's.
"""
from __future__ import annotations

import ctypes

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI
from petsc4py import PETSc

from .fascicles import FascicleFactor, FascicleSplit

INSERT = PETSc.InsertMode.INSERT_VALUES
FORWARD, REVERSE = PETSc.ScatterMode.FORWARD, PETSc.ScatterMode.REVERSE
SELF = PETSc.COMM_SELF
_LIB = None


def _petsc_lib() -> ctypes.CDLL:
    """PETSc's C library, for the two Schur-complement calls petsc4py 3.18 lacks."""
    global _LIB
    if _LIB is None:
        _LIB = ctypes.CDLL("libpetsc_real.so.3.18")
    return _LIB


def _check(code: int, call: str) -> None:
    if code:
        raise RuntimeError(f"{call} failed (PETSc error {code})")


def set_schur_rows(F: PETSc.Mat, rows: PETSc.IS) -> None:
    """Ask the (not yet factored) MUMPS factor F to stop at the Schur complement on ``rows``."""
    _check(_petsc_lib().MatFactorSetSchurIS(ctypes.c_void_p(F.handle), ctypes.c_void_p(rows.handle)),
           "MatFactorSetSchurIS")


def schur_complement(F: PETSc.Mat, n: int) -> np.ndarray:
    """The dense n × n Schur complement MUMPS formed in the last factorisation of F (a copy)."""
    lib = _petsc_lib()
    S, status = ctypes.c_void_p(), ctypes.c_int()
    _check(lib.MatFactorCreateSchurComplement(ctypes.c_void_p(F.handle), ctypes.byref(S),
                                              ctypes.byref(status)), "MatFactorCreateSchurComplement")
    ptr = ctypes.POINTER(ctypes.c_double)()
    lib.MatDenseGetArray(S, ctypes.byref(ptr))
    out = np.ctypeslib.as_array(ptr, shape=(n, n)).T.copy()          # column-major
    lib.MatDenseRestoreArray(S, ctypes.byref(ptr))
    lib.MatDestroy(ctypes.byref(S))
    return out


def _ints(a) -> np.ndarray:
    return np.asarray(a, dtype=PETSc.IntType)


class RankPattern:
    """The fixed sparsity of rank r's S^r (rows ``ids``: I_r then Γ_r) and where every entry of
    its fascicles' dense blocks B_f K_f⁻¹ B_fᵀ lands in the CSR value array (a fascicle's block
    has no two entries in one slot, so it is added with one fancy-indexed subtraction)."""

    def __init__(self, positions: list, n_i: int, n: int):
        r = np.concatenate([np.repeat(p, len(p)) for p in positions] + [np.arange(n_i)])
        c = np.concatenate([np.tile(p, len(p)) for p in positions] + [np.arange(n_i)])
        key = np.int32 if n * n < 2 ** 31 else np.int64          # int32 sorts 5× faster
        keys, where = np.unique((r * n + c).astype(key), return_inverse=True)
        rows, self.indices = (keys // n).astype(np.int64), _ints(keys % n)
        self.indptr = _ints(np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n))]))
        self.nnz, self.n, self.n_i = len(keys), n, n_i
        ends = np.cumsum([0] + [len(p) ** 2 for p in positions])
        self.block_slots = [where[a:b] for a, b in zip(ends[:-1], ends[1:])]
        self.diag_slots = where[ends[-1]:]                          # C on the interior diagonal
        # S_IΓ: rows < n_i, columns ≥ n_i
        ig = (rows < n_i) & (self.indices >= n_i)
        self.ig_slots = np.flatnonzero(ig)
        self.ig_indices = _ints(self.indices[ig] - n_i)
        self.ig_indptr = _ints(np.concatenate([[0], np.cumsum(np.bincount(rows[ig], minlength=n_i))]))

    def values(self, blocks: list, c_interior: np.ndarray, data: np.ndarray) -> None:
        """S^r's CSR values into ``data``: −Σ_f (block f) + C on I_r."""
        data[:] = 0.0
        for slots, blk in zip(self.block_slots, blocks):
            data[slots] -= blk.ravel()
        data[self.diag_slots] += c_interior

    def interior_interface(self, data: np.ndarray, n_g: int) -> sp.csr_matrix:
        """S_IΓ (n_i × n_g) of the values ``data``."""
        return sp.csr_matrix((data[self.ig_slots], self.ig_indices, self.ig_indptr), shape=(self.n_i, n_g))


class SubstructuredSchur:
    """Factors S (module docstring) once per set-up and solves with it.  ``setup`` and ``solve``
    are collective; a failed factorisation on any rank makes every rank's solves NaN (the outer
    Krylov method then stops with DIVERGED_NANORINF on all of them)."""

    def __init__(self, split: FascicleSplit, comm: PETSc.Comm, prefix: str, mumps: dict):
        self.comm, self.mpi, self.prefix, self.mumps = comm, comm.tompi4py(), prefix, mumps
        rank = comm.getRank()
        on_rank = split.beam_rank[split.z_beams]                   # (M, 2) ranks of both beams
        interface = on_rank[:, 0] != on_rank[:, 1]
        touched = (np.unique(np.concatenate(split.m_index)) if split.m_index
                   else np.zeros(0, dtype=np.int64))
        inner = touched[~interface[touched]]
        cut = touched[interface[touched]]
        self.ids = np.concatenate([inner, cut])                    # rows of S^r: I_r, then Γ_r
        self.n_i, self.n_g = len(inner), len(cut)
        gamma = np.flatnonzero(interface)
        self.n_gamma = len(gamma)
        self.g_ids = np.searchsorted(gamma, cut)                   # Γ_r in Γ's numbering
        # C_Γ and t_Γ enter Σ once: from the lower-numbered rank of the two beams
        self.g_once = on_rank[cut].min(axis=1) == rank
        order = np.argsort(self.ids, kind="stable")
        sorted_ids = self.ids[order]
        self._positions = [order[np.searchsorted(sorted_ids, m)] for m in split.m_index]
        self.pattern: RankPattern | None = None
        self.local = PETSc.Vec().createSeq(len(self.ids), comm=SELF)
        self._gather = None
        self.A = self.ksp = None
        self.data: np.ndarray | None = None    # S^r's CSR values: A's own storage
        self.S_ig = sp.csr_matrix((self.n_i, self.n_g))
        self.sigma: FascicleFactor | None = None
        self._rhs = self._sol = None
        self.counts = (0, 0)
        self.failed = False
        self.setups = 0

    # ------------------------------------------------------------------ set-up
    def setup(self, blocks: list, c_diag: PETSc.Vec) -> None:
        """Factor S: ``blocks`` are B_f K_f⁻¹ B_fᵀ of the local fascicles (dense; None for a
        fascicle without multipliers), ``c_diag`` the multipliers' own diagonal C (multiplier
        space, distributed)."""
        if self._gather is None:
            is_l = PETSc.IS().createGeneral(_ints(self.ids), comm=SELF)
            self._gather = PETSc.Scatter().create(c_diag, is_l, self.local, None)
            is_l.destroy()
        present = [k for k, b in enumerate(blocks) if b is not None]
        if self.pattern is None:
            self.pattern = RankPattern([self._positions[k] for k in present], self.n_i, len(self.ids))
        self._gather.scatter(c_diag, self.local, INSERT, FORWARD)
        c = self.local.getArray(readonly=True)
        if self.data is None:
            self.data = np.zeros(self.pattern.nnz)
        data = self.data
        self.pattern.values([blocks[k] for k in present], c[:self.n_i], data)
        self.S_ig = self.pattern.interior_interface(data, self.n_g)
        local_schur, neg, null, failed = np.zeros((self.n_g, self.n_g)), 0, 0, False
        if self.n_i:
            F = self._factor(data)
            failed = int(F.getMumpsInfog(1)) < 0
            if not failed:
                neg, null = int(F.getMumpsInfog(12)), int(F.getMumpsInfog(28))
                if self.n_g:
                    local_schur = schur_complement(F, self.n_g)
        elif self.n_g:                                 # no interior: S_ΓΓ^r itself
            local_schur = sp.csr_matrix((data, self.pattern.indices, self.pattern.indptr),
                                        shape=(self.n_g, self.n_g)).toarray()
        totals = np.array([neg, null, int(failed)], dtype=np.int64)
        self.mpi.Allreduce(MPI.IN_PLACE, totals)
        self.failed = bool(totals[2])
        self.counts = (int(totals[0]), int(totals[1]))
        if self.n_gamma and not self.failed:
            self._factor_interface(local_schur, c[self.n_i:])
        self.setups += 1

    def _factor(self, data: np.ndarray) -> PETSc.Mat:
        """S^r factored by sequential MUMPS LDLᵀ, with the Schur complement on Γ_r if any."""
        pat = self.pattern
        if self.A is None:
            n = pat.n
            self.A = PETSc.Mat().createAIJWithArrays((n, n), (pat.indptr, pat.indices, data), comm=SELF)
            self.A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
            self.A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
            self.ksp = PETSc.KSP().create(comm=SELF)
            self.ksp.setOptionsPrefix(self.prefix)
            self.ksp.setType("preonly")
            pc = self.ksp.getPC()
            pc.setType("cholesky")
            pc.setFactorSolverType("mumps")
            self.ksp.setFromOptions()
            self.ksp.setOperators(self.A)
            pc.setFactorSetUpSolverType()
            F = pc.getFactorMatrix()
            opts = PETSc.Options()
            for k, v in self.mumps.items():
                if not opts.hasName(f"{self.prefix}mat_mumps_icntl_{k}"):
                    F.setMumpsIcntl(k, v)
            if self.n_g:
                rows = PETSc.IS().createStride(self.n_g, self.n_i, 1, comm=SELF)
                set_schur_rows(F, rows)
                rows.destroy()
            self._rhs, self._sol = self.A.createVecs()
        self.A.assemble()                              # the values changed in place
        self.ksp.setOperators(self.A)                  # new values: KSPSetUp refactors
        self.ksp.setUp()
        F = self.ksp.getPC().getFactorMatrix()
        if self.n_g:
            F.setMumpsIcntl(26, 0)                     # solves: the interior rows only
        return F

    def _factor_interface(self, local_schur: np.ndarray, c_g: np.ndarray) -> None:
        """Σ = C_Γ + Σ_r (S_ΓΓ − S_ΓI S_II⁻¹ S_IΓ)^r, summed over the ranks and factored densely
        (as −Σ, which is positive definite where the fascicles are) on every rank."""
        sigma = np.zeros((self.n_gamma, self.n_gamma))
        g = self.g_ids
        sigma[np.ix_(g, g)] = local_schur
        once = g[self.g_once]
        sigma[once, once] += c_g[self.g_once]
        self.mpi.Allreduce(MPI.IN_PLACE, sigma)
        self.sigma = FascicleFactor(-sigma)

    # ------------------------------------------------------------------ solve
    def _interior(self, b: np.ndarray) -> np.ndarray:
        """(S_II^r)⁻¹ b (ICNTL(26) = 0: MUMPS leaves the Γ_r rows out)."""
        rhs = self._rhs.getArray()
        rhs[:self.n_i] = b
        rhs[self.n_i:] = 0.0
        del rhs
        self.ksp.getPC().getFactorMatrix().solve(self._rhs, self._sol)
        return self._sol.getArray(readonly=True)[:self.n_i].copy()

    def solve(self, t: PETSc.Vec, z: PETSc.Vec) -> None:
        """z = S⁻¹ t (multiplier space, distributed)."""
        if self.failed:
            z.set(np.nan)
            return
        ni = self.n_i
        self._gather.scatter(t, self.local, INSERT, FORWARD)
        tl = self.local.getArray(readonly=True).copy()
        y = self._interior(tl[:ni]) if ni else np.zeros(0)
        if self.n_gamma:
            rhs = np.zeros(self.n_gamma)
            if self.n_g:
                rhs[self.g_ids] = -(self.S_ig.T @ y) if ni else 0.0
                once = self.g_ids[self.g_once]
                rhs[once] += tl[ni:][self.g_once]
            self.mpi.Allreduce(MPI.IN_PLACE, rhs)
            zg = -self.sigma.solve(rhs)[self.g_ids]                # Σ⁻¹ = −(−Σ)⁻¹
            tl[ni:] = zg
            if ni and self.n_g:
                y = self._interior(tl[:ni] - self.S_ig @ zg)
        tl[:ni] = y
        self.local.setArray(tl)
        self._gather.scatter(self.local, z, INSERT, REVERSE)

    def pivot_counts(self) -> tuple[int, int] | None:
        """(negative, null) pivots of S: those of every S_II^r plus Σ's (None before the first
        set-up or after a failed one)."""
        if self.setups == 0 or self.failed:
            return None
        neg, null = self.counts
        if self.n_gamma:
            f = self.sigma
            neg, null = neg + self.n_gamma - f.negative - f.null, null + f.null
        return neg, null

    def destroy(self) -> None:
        for obj in (self.A, self.ksp, self.local, self._gather, self._rhs, self._sol):
            if obj is not None:
                obj.destroy()
        self.A = self.ksp = self._gather = self._rhs = self._sol = None
