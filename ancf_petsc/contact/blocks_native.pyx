# distutils: extra_compile_args = -ffp-contract=off
# cython: boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled parts of the normal contact's residual and Jacobian (contact/blocks.py): the points'
forces scattered onto their elements' DOFs (``add_point_forces``, bitwise the numpy code: no
fused multiply-adds, ``-ffp-contract=off``) and the gap-Hessian term (``add_gap_hessian``): per segment
−Σ_p τ_p ∇²g_p = Σ_p τ_p W_p C_p W_pᵀ (contact/gap.py) as one BLAS product L R (L = [W_p C_p τ_p],
R = [W_pᵀ] over the segment's points) added into the segment's block, W_p and the operands formed
here in one pass over the points (the numpy path forms W per point, scatters W and W C τ into a
padded segment layout, transposes and copies them: ~25 numpy calls and four copies of the
operands per segment group).  The products are the BLAS calls numpy's matmul makes there
(scipy's BLAS is numpy's: the same library, the same kernels), on the same operands in the same
layout: the Jacobian is bitwise the numpy path's (tests/contact/test_blocks_native.py)."""
import numpy as np

cimport numpy as cnp
from scipy.linalg.cython_blas cimport dgemm

cnp.import_array()


#: scratch arrays of ``add_gap_hessian`` kept between calls (fresh ones of a few MB cost page
#: faults on every call: half of the kernel's time); every entry used is written in each call
_scratch = [np.zeros(0), np.zeros(0), np.zeros(0)]


def _scratch_array(which: int, shape: tuple):
    """Scratch array ``which`` as a contiguous array of ``shape`` (its values left over)."""
    size = int(np.prod(shape))
    if _scratch[which].size < size:
        _scratch[which] = np.zeros(size)
    return _scratch[which][:size].reshape(shape)


def add_gap_hessian(double[:, :, ::1] K, const double[:, ::1] NA, const double[:, ::1] NB,
                    const double[:, :, ::1] NBz, const double[:, :, ::1] Yz, const double[:, ::1] n,
                    const double[:, :, ::1] Ct, const long[::1] s_loc, const long[::1] p_loc,
                    const long[::1] col_b, int P_s, int Dq):
    """K[s, :Dq, :Dq] += Σ_p W_p Ct_p W_pᵀ over the points p of each segment s (``s_loc``; the
    ``p_loc``-th of at most P_s), with Ct_p = τ_p C_p (4, 4) (gap.gap_hessian_factors) and W_p
    formed here from A's and B's shape functions NA, NB (P, S), B's ζ-derivatives NBz (P, S, 2),
    the surface's Y_ζ (P, 3, 2) and the normal n; point p's rows of W (A's S slots × 3, then
    B's) are the block's unknowns 0 … 3S − 1 and ``col_b[p]`` … ``col_b[p]`` + 3S − 1.  The
    products are the BLAS calls numpy's matmul makes in blocks.add_gap_hessian's numpy path,
    on the same operands: the sums are bitwise equal to it."""
    cdef Py_ssize_t P = NA.shape[0], S = NA.shape[1], n_s = K.shape[0], p, s, i, j, q
    cdef int R = 6 * NA.shape[1], four = 4, k = 4 * P_s, D = K.shape[1]
    cdef double one = 1.0, zero = 0.0
    cdef char trans = b'N'
    if K.shape[2] != D or Dq > D or Ct.shape[0] != P or Ct.shape[1] != 4 or Ct.shape[2] != 4:
        raise ValueError("K must be (n_s, D, D) with Dq <= D, Ct (P, 4, 4)")
    for p in range(P):
        if (s_loc[p] < 0 or s_loc[p] >= n_s or p_loc[p] < 0 or p_loc[p] >= P_s
                or col_b[p] < 3 * S or col_b[p] + 3 * S > Dq):
            raise ValueError("a point outside the blocks")
    W_arr = np.empty((R, 4))
    WC_arr = np.empty((R, 4))
    # every entry of L and R is written: a point's W and W C τ over its unknowns, zero over the
    # block's other ones and over the slots of absent points (cheaper than zeroing them first)
    L_arr, R_arr = _scratch_array(0, (n_s, Dq, k)), _scratch_array(1, (n_s, k, Dq))
    T_arr = _scratch_array(2, (Dq, Dq))
    filled_arr = np.zeros((n_s, P_s), dtype=np.uint8)
    cdef cnp.uint8_t[:, ::1] filled = filled_arr
    cdef double[:, ::1] W = W_arr
    cdef double[:, ::1] WC = WC_arr
    cdef double[:, :, ::1] Lm = L_arr
    cdef double[:, :, ::1] Rm = R_arr
    cdef double[:, ::1] Tm = T_arr
    for p in range(P):
        _point_w(p, W, NA, NB, NBz, Yz, n)
        # numpy: cblas_dgemm(RowMajor, N, N, R, 4, 4, 1, W, 4, Ct_p, 4, 0, WC, 4)
        dgemm(&trans, &trans, &four, &R, &four, &one, <double*>&Ct[p, 0, 0], &four, &W[0, 0], &four, &zero,
              &WC[0, 0], &four)
        _scatter(p, W, WC, Lm, Rm, s_loc[p], 4 * p_loc[p], col_b[p], 3 * S)
        filled[s_loc[p], p_loc[p]] = 1
    for s in range(n_s):
        for q in range(P_s):
            if not filled[s, q]:
                for i in range(Dq):
                    for j in range(4):
                        Lm[s, i, 4 * q + j] = 0.0
                        Rm[s, 4 * q + j, i] = 0.0
    for s in range(n_s):
        # numpy: cblas_dgemm(RowMajor, N, N, Dq, Dq, k, 1, L_s, k, R_s, Dq, 0, T, Dq), then K += T
        dgemm(&trans, &trans, &Dq, &Dq, &k, &one, &Rm[s, 0, 0], &Dq, &Lm[s, 0, 0], &k, &zero,
              &Tm[0, 0], &Dq)
        for i in range(Dq):
            for j in range(Dq):
                K[s, i, j] = K[s, i, j] + Tm[i, j]


cdef void _point_w(Py_ssize_t p, double[:, ::1] W, const double[:, ::1] NA, const double[:, ::1] NB,
                   const double[:, :, ::1] NBz, const double[:, :, ::1] Yz, const double[:, ::1] n) nogil:
    """W_p (6S, 4) = [u₁ u₂ v₁ v₂] (gap.gap_hessian_factors: [N_A, −N_B] ⊗ Y_ζ, [0, N_B,ζ] ⊗ n)."""
    cdef Py_ssize_t S = NA.shape[1], slot, i, r
    cdef double nab
    for slot in range(2 * S):
        nab = NA[p, slot] if slot < S else -NB[p, slot - S]
        for i in range(3):
            r = 3 * slot + i
            W[r, 0] = nab * Yz[p, i, 0]
            W[r, 1] = nab * Yz[p, i, 1]
            if slot < S:
                W[r, 2] = 0.0
                W[r, 3] = 0.0
            else:
                W[r, 2] = NBz[p, slot - S, 0] * n[p, i]
                W[r, 3] = NBz[p, slot - S, 1] * n[p, i]


cdef void _scatter(Py_ssize_t p, double[:, ::1] W, double[:, ::1] WC, double[:, :, ::1] Lm,
                   double[:, :, ::1] Rm, Py_ssize_t s, Py_ssize_t q, Py_ssize_t col_b,
                   Py_ssize_t half) nogil:
    """Point p's W and W C τ into its segment's operands: L[s, col, q + a] = (W C τ)[row, a],
    R[s, q + a, col] = W[row, a] (blocks.add_gap_hessian's ``spread`` and transposes)."""
    cdef Py_ssize_t r, a, col
    for col in range(half, Lm.shape[1]):           # the block's unknowns the point has not
        if col < col_b or col >= col_b + half:
            for a in range(4):
                Lm[s, col, q + a] = 0.0
                Rm[s, q + a, col] = 0.0
    for r in range(W.shape[0]):
        col = r if r < half else col_b + r - half
        for a in range(4):
            Lm[s, col, q + a] = WC[r, a]
            Rm[s, q + a, col] = W[r, a]


def add_point_forces(double[::1] floc, const long[:, ::1] pos, const double[:, ::1] N,
                     const double[:, ::1] traction, double sign, int dofs_per_node):
    """floc += Σ_p sign N_p ⊗ traction_p over the DOFs of each point's element (node positions
    ``pos`` (P, nodes) in the local array, slot-major: slot s, component i is the element's
    unknown 3 s + i): ``np.bincount`` of the products into a zeroed array, in the points' order,
    then added (bitwise what blocks.add_normal_forces's numpy code adds)."""
    cdef Py_ssize_t P = N.shape[0], S = N.shape[1], n = floc.shape[0], p, s, i, j, dof
    acc_arr = np.zeros(n)
    cdef double[::1] acc = acc_arr
    cdef double v
    if pos.shape[0] != P or traction.shape[0] != P or 3 * S > pos.shape[1] * dofs_per_node:
        raise ValueError("shapes of pos, N, traction do not match")
    for p in range(P):
        for s in range(S):
            v = sign * N[p, s]
            for i in range(3):
                j = 3 * s + i
                dof = dofs_per_node * pos[p, j // dofs_per_node] + j % dofs_per_node
                if dof < 0 or dof >= n:
                    raise IndexError("a DOF outside the local array")
                acc[dof] += v * traction[p, i]
    for j in range(n):
        floc[j] = floc[j] + acc[j]
