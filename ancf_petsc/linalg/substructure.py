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

Each rank factors S^r with sequential MUMPS LDLᵀ, which forms its Schur complement on Γ_r
itself (ICNTL(19)) and later solves in two halves around Σ (ICNTL(26): condensation, the forward
pass; expansion, the backward pass): MUMPS called directly (``mumps_schur.SchurFactor``), as
PETSc 3.18's interface offers the Schur complement but not the two half solves.  No MPI until
the Schur complements are summed (one Allreduce of the dense n_Γ × n_Γ matrix per set-up).  Σ
is small (the multipliers on the cut: 858 of 5 940 for 37 fascicles on two ranks), so every
rank factors it densely (``FascicleFactor``) and solves it redundantly: one Allreduce of an n_Γ
vector per application.  On one rank Γ is empty and this is one MUMPS factorisation of S.

Measured on the 37-fascicle bundle (docs/parallel.md), 2 ranks, per factorisation of S: 0.085 s
for each rank's S^r and ~0.01 s for Σ, against 0.15–0.18 s for MUMPS factoring the distributed S
on both ranks; per application ~2.4 ms against 4.7 ms.

Inertia adds up (Haynsworth): S's negative pivots are those of every S_II^r (MUMPS's INFOG(12)
counts the eliminated rows only) plus Σ's.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI
from petsc4py import PETSc

from . import logging
from .fascicles import FascicleSplit
from .interface_system import DenseInterface, DistributedInterface, interface_kind
from .mumps_schur import SchurFactor, mumps_controls

INSERT = PETSc.InsertMode.INSERT_VALUES
FORWARD, REVERSE = PETSc.ScatterMode.FORWARD, PETSc.ScatterMode.REVERSE
SELF = PETSc.COMM_SELF
#: -log_view events: S's factorisation (the ranks' MUMPS factors and the interface system) and
#: its solves (condensation, interface, expansion)
FACTOR_EVENT, SOLVE_EVENT = "ANCF Schur factor", "ANCF Schur solve"
#: inside both: the interface system's set-up and solves (interface_system.py)
INTERFACE_EVENT = "ANCF Schur interface"


class RankPattern:
    """The fixed sparsity of the upper triangle of rank r's S^r (rows ``ids``: I_r then Γ_r)
    and where the upper entries of its fascicles' dense blocks B_f K_f⁻¹ B_fᵀ land in the CSR
    value array (no two entries of one block share a slot: one fancy-indexed subtraction each)."""

    def __init__(self, positions: list, n_i: int, n: int):
        self.upper = []                                   # per block: its upper entries
        r_list, c_list = [], []
        for p in positions:
            i, j = np.triu_indices(len(p))
            flip = p[i] > p[j]                            # positions need not be sorted
            r, c = np.where(flip, p[j], p[i]), np.where(flip, p[i], p[j])
            self.upper.append(i * len(p) + j)
            r_list.append(r)
            c_list.append(c)
        r = np.concatenate(r_list + [np.arange(n_i)])
        c = np.concatenate(c_list + [np.arange(n_i)])
        key = np.int32 if n * n < 2 ** 31 else np.int64          # int32 sorts 5× faster
        keys, where = np.unique((r * n + c).astype(key), return_inverse=True)
        rows = (keys // n).astype(np.int64)
        self.indices = (keys % n).astype(np.int64)
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n))])
        self.nnz, self.n, self.n_i = len(keys), n, n_i
        ends = np.cumsum([0] + [len(u) for u in self.upper])
        self.block_slots = [where[a:b] for a, b in zip(ends[:-1], ends[1:])]
        self.diag_slots = where[ends[-1]:]                          # C on the interior diagonal

    def values(self, blocks: list, c_interior: np.ndarray, data: np.ndarray) -> None:
        """The upper triangle of S^r into ``data``: −Σ_f (block f) + C on I_r."""
        data[:] = 0.0
        for slots, upper, blk in zip(self.block_slots, self.upper, blocks):
            data[slots] -= blk.ravel()[upper]
        data[self.diag_slots] += c_interior

    def dense(self, data: np.ndarray) -> np.ndarray:
        """S^r as a dense symmetric array."""
        U = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n)).toarray()
        return U + np.triu(U, 1).T


class SubstructuredSchur:
    """Factors S (module docstring) once per set-up and solves with it.  ``setup`` and ``solve``
    are collective; a failed factorisation on any rank makes every rank's solves NaN (the outer
    Krylov method then stops with DIVERGED_NANORINF on all of them)."""

    def __init__(self, split: FascicleSplit, comm: PETSc.Comm, prefix: str, mumps: dict):
        self.mpi, self.prefix, self.mumps = comm.tompi4py(), prefix, mumps
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
        #: per local fascicle: the positions of its multipliers among ``ids``
        self.positions = [order[np.searchsorted(sorted_ids, m)] for m in split.m_index]
        self._z_dofs = split.z_dofs[self.ids]
        self.pattern: RankPattern | None = None
        self.factor: SchurFactor | None = None
        self.local = PETSc.Vec().createSeq(len(self.ids), comm=SELF)
        self._gather = None
        self.data: np.ndarray | None = None
        r0, r1 = split.z_range
        g_range = tuple(int(k) for k in np.searchsorted(gamma, [r0, r1]))
        self.interface = None
        if self.n_gamma:
            if interface_kind(self.n_gamma, prefix) == "dense":
                self.interface = DenseInterface(self.n_gamma, self.g_ids, self.mpi)
            else:
                self.interface = DistributedInterface(self.n_gamma, self.g_ids, g_range, comm,
                                                      prefix, mumps)
        self.counts = (0, 0)
        self.failed = False
        self.setups = 0

    # ------------------------------------------------------------------ the rank's multipliers
    def create_gather(self, x: PETSc.Vec) -> None:
        """The scatter between vectors laid out like ``x`` (the Jacobian's) and this rank's
        multipliers ``ids`` (collective, once)."""
        is_l = PETSc.IS().createGeneral(np.asarray(self._z_dofs, dtype=PETSc.IntType), comm=SELF)
        self._gather = PETSc.Scatter().create(x, is_l, self.local, None)
        is_l.destroy()

    def gather(self, x: PETSc.Vec, once: bool = False) -> np.ndarray:
        """x at this rank's multipliers (a copy); ``once``: the cut's entries only on the rank
        that adds them to Σ's right-hand side (zero elsewhere)."""
        self._gather.scatter(x, self.local, INSERT, FORWARD)
        out = self.local.getArray(readonly=True).copy()
        if once:
            out[self.n_i:][~self.g_once] = 0.0
        return out

    def put(self, z: np.ndarray, y: PETSc.Vec) -> None:
        """Write z (this rank's multipliers) into y (laid out like the Jacobian; the cut's
        entries come from both of their ranks, equal)."""
        self.local.setArray(z)
        self._gather.scatter(self.local, y, INSERT, REVERSE)

    # ------------------------------------------------------------------ set-up
    def setup(self, blocks: list, c: np.ndarray) -> None:
        """Factor S: ``blocks`` are B_f K_f⁻¹ B_fᵀ of the local fascicles (dense; None for a
        fascicle without multipliers), ``c`` the multipliers' own diagonal C at ``ids``."""
        logging.event(FACTOR_EVENT).begin()
        try:
            self._setup(blocks, c)
        finally:
            logging.event(FACTOR_EVENT).end()

    def _setup(self, blocks: list, c: np.ndarray) -> None:
        local_schur, neg, null, failed, error = None, 0, 0, False, ""
        try:
            local_schur, neg, null, failed = self._factor_rank(blocks, c[:self.n_i])
        except Exception as exc:                       # never one rank alone: see below
            failed, error = True, f"{type(exc).__name__}: {exc}"
        totals = np.array([neg, null, int(failed), int(bool(error))], dtype=np.int64)
        self.mpi.Allreduce(MPI.IN_PLACE, totals)
        if totals[3]:
            errors = [e for e in self.mpi.allgather(error) if e]
            raise RuntimeError(f"fascicle Schur solver: {errors[0]}")
        self.failed = bool(totals[2])
        self.counts = (int(totals[0]), int(totals[1]))
        if self.n_gamma and not self.failed:
            self._factor_interface(local_schur, c[self.n_i:])
        self.setups += 1

    def _factor_rank(self, blocks: list, c_interior: np.ndarray) -> tuple:
        """S^r assembled and factored on this rank: (its Schur complement on Γ_r or None,
        negative and null pivots of S_II^r, whether the numeric factorisation failed)."""
        present = [k for k, b in enumerate(blocks) if b is not None]
        if self.pattern is None:
            self.pattern = RankPattern([self.positions[k] for k in present], self.n_i, len(self.ids))
            if self.n_i:
                icntl, cntl = mumps_controls(self.prefix, self.mumps)
                self.factor = SchurFactor(self.pattern.indptr, self.pattern.indices, self.n_g,
                                          icntl, cntl)
            self.data = self.factor.values if self.factor else np.zeros(self.pattern.nnz)
        self.pattern.values([blocks[k] for k in present], c_interior, self.data)
        if self.factor is None:                        # no interior: S_ΓΓ^r itself
            return (self.pattern.dense(self.data) if self.n_g else None), 0, 0, False
        if not self.factor.factor():
            return None, 0, 0, True
        schur = self.factor.schur() if self.n_g else None
        return schur, self.factor.negative_pivots, self.factor.null_pivots, False

    def _factor_interface(self, local_schur: np.ndarray | None, c_g: np.ndarray) -> None:
        """Σ = C_Γ + Σ_r (S_ΓΓ − S_ΓI S_II⁻¹ S_IΓ)^r over the ranks (interface_system.py)."""
        logging.event(INTERFACE_EVENT).begin()
        self.interface.set_up(local_schur, self.g_ids[self.g_once], c_g[self.g_once])
        logging.event(INTERFACE_EVENT).end()

    # ------------------------------------------------------------------ solve
    def solve(self, t: np.ndarray) -> np.ndarray:
        """z = S⁻¹ t over this rank's multipliers ``ids``: t complete on I_r, and on Γ_r this
        rank's part of it (the parts add up over the ranks).  Condense on every rank, sum and
        solve the interface system, expand.  Collective."""
        if self.failed:
            return np.full(len(self.ids), np.nan)
        logging.event(SOLVE_EVENT).begin()
        try:
            return self._solve(t)
        finally:
            logging.event(SOLVE_EVENT).end()

    def _solve(self, t: np.ndarray) -> np.ndarray:
        ni, f = self.n_i, self.factor
        z = t.copy()
        if not self.n_gamma:
            if ni:
                z[:ni] = f.solve(t[:ni])
            return z
        part = t[ni:].copy()
        if ni and self.n_g:
            part += f.condense(t[:ni])                             # −S_ΓI S_II⁻¹ t_I
        logging.event(INTERFACE_EVENT).begin()
        zg = self.interface.solve(part)
        logging.event(INTERFACE_EVENT).end()
        if ni:
            z[:ni] = f.expand(zg) if self.n_g else f.solve(t[:ni])
        z[ni:] = zg
        return z

    def pivot_counts(self) -> tuple[int, int] | None:
        """(negative, null) pivots of S: those of every S_II^r plus Σ's (None before the first
        set-up or after a failed one)."""
        if self.setups == 0 or self.failed:
            return None
        neg, null = self.counts
        if self.interface is not None:
            counts = self.interface.pivot_counts()
            if counts is None:
                return None
            neg, null = neg + counts[0], null + counts[1]
        return neg, null

    def destroy(self) -> None:
        for obj in (self.local, self._gather):
            if obj is not None:
                obj.destroy()
        if self.factor is not None:
            self.factor.destroy()
        if self.interface is not None:
            self.interface.destroy()
        self.factor = self._gather = self.interface = None
