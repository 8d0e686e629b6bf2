"""The pieces of the fascicle-parallel solver (``fieldsplit.py``) that know one fascicle: which
DOFs and multipliers belong to each fascicle on this rank (``FascicleSplit``), a fascicle's
stiffness K_f and constraint rows B_fᵀ cut from the assembled Jacobian (``fascicle_blocks``),
and its dense factorisation with inertia (``FascicleFactor``).

K_f is a slender band (one fascicle: 18 DOFs × a few hundred nodes), small enough to factor
densely with LAPACK; its rows are scaled by |diag K_f|^-1/2 first, since the quadratic section
modes of element 3363 are ~1e15 softer than the axial ones in SI units.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from petsc4py import PETSc
from scipy.linalg import lapack
from scipy.linalg.blas import dtrsm



@dataclass
class FascicleSplit:
    """Index sets (PETSc numbering) of one rank's fascicles and of the multipliers.

    The multiplier space numbers the multipliers in increasing PETSc DOF order, so that every
    rank owns one contiguous range of it (its own multiplier nodes)."""
    beams: list               # indices of the local beams
    u_dofs: list              # per local beam: DOFs of its nodes (owned by this rank)
    m_index: list             # per local beam: the multipliers coupled to it (multiplier space)
    z_dofs: np.ndarray        # (M,) PETSc DOF of every multiplier, in multiplier-space order
    z_range: tuple            # this rank's owned range of the multiplier space
    z_beams: np.ndarray       # (M, 2) the two beams (A, B) each multiplier couples
    beam_rank: np.ndarray     # (n_beams,) the rank that holds each beam
    dofs_per_node: int = 18   # DOFs of a node block (the model's, Model.dofs_per_node)

    @property
    def n_multipliers(self) -> int:
        return len(self.z_dofs)


def fascicle_split(problem) -> FascicleSplit:
    """The split of ``problem`` (petsc.problem.Problem) on this rank.  Raises ValueError when a beam
    is not whole on one rank (use ``parallel.partition.make_layout(..., 'beams')``) or there is no contact."""
    model, layout, contact = problem.model, problem.layout, problem.contact
    D = model.dofs_per_node
    if contact is None or contact.n_multipliers == 0:
        raise ValueError("the fascicle split needs contact multipliers")
    lo, hi = layout.owned_nodes
    beams, u_dofs = [], []
    beam_rank = np.zeros(len(model.beams), dtype=np.int64)
    for beam in model.beams:
        owners = layout.node_owner[beam.node_offset + np.arange(beam.n_nodes)]
        beam_rank[beam.index] = owners[0]
        if np.any(owners != owners[0]):
            raise ValueError(f"beam {beam.name} is split over ranks; the fascicle split needs "
                             "whole beams per rank (partition 'beams')")
        if owners[0] == layout.rank:
            blocks = layout.perm[beam.node_offset + np.arange(beam.n_nodes)]
            beams.append(beam.index)
            u_dofs.append((D * blocks[:, None] + np.arange(D)).ravel())
    dofs = layout.petsc_dofs(contact.multiplier_dofs())
    order = np.argsort(dofs, kind="stable")
    z_dofs = dofs[order]
    itf = contact.space.interface[order]
    ends = np.array([[i.a.index, i.b.index] for i in contact.interfaces], dtype=np.int64)
    z_beams = ends[itf]
    r0, r1 = np.searchsorted(z_dofs, [D * lo, D * hi])
    m_index = [np.flatnonzero((z_beams[:, 0] == b) | (z_beams[:, 1] == b)) for b in beams]
    return FascicleSplit(beams, u_dofs, m_index, z_dofs, (int(r0), int(r1)), z_beams, beam_rank, D)


#: a Cholesky factor is also kept in LAPACK's band storage when the half-bandwidth of K_f is
#: below this share of its size: a fascicle's K_f (594 DOFs, half-bandwidth 53, the three nodes of
#: an element) then solves 10× faster (dpbtrs 0.014 ms against dpotrs 0.135 ms per solve, two
#: solves per fascicle and GMRES iteration); the dense factor stays for the Schur block (BLAS 3)
BAND_SHARE = 0.25


class FascicleFactor:
    """One fascicle's K_f, diagonally scaled (s K s, s = |diag K|^-1/2: the quadratic section
    modes are ~1e15 softer than the axial ones in SI units), factored densely: Cholesky, or LU
    where K_f is not positive definite; then its inertia comes from an LDLᵀ (Bunch–Kaufman)."""

    def __init__(self, K: np.ndarray):
        d = np.abs(np.diag(K))
        self.s = 1.0 / np.sqrt(np.where(d > 0.0, d, 1.0))
        Ks = K * self.s[:, None] * self.s[None, :]
        self.n = len(K)
        self.L = self.lu = self.piv = None
        L, info = lapack.dpotrf(Ks, lower=1, clean=1)
        self.negative = self.null = 0
        self.band = None
        if info == 0:
            self.kind, self.L = "cholesky", L
            self.band = _lower_band(L, K)
            return
        self.kind = "lu"
        self.lu, self.piv, info = lapack.dgetrf(Ks)
        if info > 0:
            self.null = 1                                   # exactly singular: a free mechanism
        self.negative, null = _ldlt_inertia(Ks)
        self.null = max(self.null, null)

    def solve(self, r: np.ndarray) -> np.ndarray:
        """K_f⁻¹ r for r (n,) or (n, k)."""
        b = (self.s * r.T).T
        if self.band is not None:
            x, _ = lapack.dpbtrs(self.band, b, lower=1)
        elif self.kind == "cholesky":
            x, _ = lapack.dpotrs(self.L, b, lower=1)
        else:
            x, _ = lapack.dgetrs(self.lu, self.piv, b)
        return (self.s * x.T).T

    def schur_block(self, Bt: np.ndarray) -> np.ndarray:
        """B_f K_f⁻¹ B_fᵀ for Bt = B_fᵀ (n, m): a symmetric (m, m) block."""
        Y = Bt * self.s[:, None]
        if self.kind == "cholesky":
            W = dtrsm(1.0, self.L, Y, lower=1)              # L⁻¹ s Bᵀ
            return W.T @ W
        X, _ = lapack.dgetrs(self.lu, self.piv, Y)
        out = Y.T @ X
        return 0.5 * (out + out.T)


def _lower_band(L: np.ndarray, K: np.ndarray) -> np.ndarray | None:
    """L (lower Cholesky factor of K) in LAPACK's lower band storage, ab[k, j] = L[j + k, j], if
    K's half-bandwidth is below BAND_SHARE of its size (L fills no further); None otherwise."""
    n = len(K)
    kd = int(np.max(np.arange(n) - np.argmax(K != 0, axis=1))) if n else 0
    if kd >= BAND_SHARE * n:
        return None
    ab = np.zeros((kd + 1, n))
    for k in range(kd + 1):
        ab[k, :n - k] = np.diagonal(L, -k)
    return ab


def _ldlt_inertia(A: np.ndarray) -> tuple[int, int]:
    """(negative, zero) eigenvalue counts of symmetric A from its Bunch–Kaufman LDLᵀ (Sylvester:
    those of the block-diagonal D; LAPACK marks a 2×2 block by two equal negative pivots)."""
    lwork = int(lapack.dsytrf_lwork(len(A), lower=1)[0])
    ldu, ipiv, _ = lapack.dsytrf(A, lower=1, lwork=max(lwork, 1))
    d = np.diag(ldu)
    first = np.flatnonzero(np.asarray(ipiv) < 0)[0::2]          # first rows of the 2×2 blocks
    one = np.ones(len(A), dtype=bool)
    one[first] = one[first + 1] = False
    det = d[first] * d[first + 1] - ldu[first + 1, first] ** 2
    neg = int(np.sum(d[one] < 0.0) + np.sum(det < 0.0) + 2 * np.sum((det > 0.0) & (d[first] < 0.0)))
    zero = int(np.sum(d[one] == 0.0) + np.sum(det == 0.0))
    return neg, zero


def fascicle_blocks(sub: PETSc.Mat, iu: np.ndarray, im: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """K_f (dense, rows/columns ``iu``) and B_fᵀ (dense, rows ``iu``, columns ``im``) from a
    sequential (S)BAIJ/AIJ sub-matrix.  SBAIJ holds the upper triangle U (``iu`` ascending):
    K_f = U_uu + U_uuᵀ − diag, and an entry of B_fᵀ sits in U_um or, transposed, in U_mu."""
    n = sub.getSize()[0]
    if sub.getType().endswith("sbaij"):
        sub.setOption(PETSc.Mat.Option.GETROW_UPPERTRIANGULAR, True)
        ia, ja, a = sub.getValuesCSR()
        # (a diagonal block's rows also return its stored lower part: not the matrix's)
        U = sp.triu(sp.csr_matrix((a, ja, ia), shape=(n, n))).tocsr()
        Uu = U[iu]
        K = Uu[:, iu].toarray()
        K += K.T
        K[np.diag_indices_from(K)] *= 0.5
        Bt = Uu[:, im].toarray() + U[im][:, iu].T.toarray()
        return K, Bt
    ia, ja, a = sub.getValuesCSR()
    rows = sp.csr_matrix((a, ja, ia), shape=(n, n))[iu]
    return rows[:, iu].toarray(), rows[:, im].toarray()
