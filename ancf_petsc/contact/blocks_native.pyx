# distutils: extra_compile_args = -ffp-contract=off
# cython: boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled parts of the normal contact's residual and Jacobian (contact/blocks.py): the points'
forces scattered onto their elements' DOFs (``add_point_forces``, bitwise the numpy code: no
fused multiply-adds, ``-ffp-contract=off``) and the gap-Hessian term (``add_gap_hessian``): per segment
−Σ_p τ_p ∇²g_p = Σ_p τ_p W_p C_p W_pᵀ (contact/gap.py) as BLAS products over the blocks each
point has (A–A, and A–B, B–B per B element), W_p and the operands formed here in one pass over
the points (the numpy path forms W per point, scatters W and W C τ into a padded segment layout
and multiplies the padded operands: the reference, equal to rounding;
tests/contact/test_blocks_native.py)."""
import numpy as np

cimport numpy as cnp
from scipy.linalg.cython_blas cimport dgemm

cnp.import_array()


#: scratch arrays of ``add_gap_hessian`` kept between calls (fresh ones of a few MB cost page
#: faults on every call: half of the kernel's time); every entry used is written in each call
_scratch = [np.zeros(0) for _ in range(5)]


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
    B's) are the block's unknowns 0 … 3S − 1 and ``col_b[p]`` … ``col_b[p]`` + 3S − 1.

    Only the blocks a point has are multiplied (A's 3S rows have no v columns, W's columns 2, 3):
    per segment A–A over its points with k = 2 per point, and per B element of the segment A–B
    and B–B with k = 4 (B–A is A–B's transpose: W C Wᵀ is symmetric, C_p is); ~58 k multiply-adds
    per point against the padded (Dq × 4 P_s) (4 P_s × Dq) product's 93 k, or 165 k on a
    two-element-wide block.  The sums run in another order than the numpy path's padded product:
    they agree to rounding (tests/contact/test_blocks_native.py)."""
    cdef Py_ssize_t P = NA.shape[0], S = NA.shape[1], n_s = K.shape[0], p, q, s, i, j
    cdef Py_ssize_t g0, g1, s0, s1, c
    cdef int R = 6 * NA.shape[1], half = 3 * NA.shape[1], four = 4, D = K.shape[1], k
    cdef double one = 1.0, zero = 0.0
    cdef char nt = b'N', tt = b'T'
    if K.shape[2] != D or Dq > D or Ct.shape[0] != P or Ct.shape[1] != 4 or Ct.shape[2] != 4:
        raise ValueError("K must be (n_s, D, D) with Dq <= D, Ct (P, 4, 4)")
    for p in range(P):
        if (s_loc[p] < 0 or s_loc[p] >= n_s or p_loc[p] < 0 or p_loc[p] >= P_s
                or col_b[p] < 3 * S or col_b[p] + 3 * S > Dq):
            raise ValueError("a point outside the blocks")
    if P == 0:
        return
    # the points by segment, B element, place in the segment
    order_arr = np.lexsort((np.asarray(p_loc), np.asarray(col_b), np.asarray(s_loc)))
    cdef long[::1] order = order_arr
    W_arr = np.empty((R, 4))
    WC_arr = np.empty((R, 4))
    # the operands transposed, in that order: row 4 q + a of Wt is W_q's column a; the A rows'
    # u columns (a = 0, 1) also apart, row 2 q + a of WtA
    Wt_arr, WCt_arr = _scratch_array(0, (4 * P, R)), _scratch_array(1, (4 * P, R))
    WtA_arr, WCtA_arr = _scratch_array(2, (2 * P, half)), _scratch_array(3, (2 * P, half))
    T_arr = _scratch_array(4, (half, half))
    cdef double[:, ::1] W = W_arr
    cdef double[:, ::1] WC = WC_arr
    cdef double[:, ::1] Wt = Wt_arr
    cdef double[:, ::1] WCt = WCt_arr
    cdef double[:, ::1] WtA = WtA_arr
    cdef double[:, ::1] WCtA = WCtA_arr
    cdef double[:, ::1] T = T_arr
    for q in range(P):
        p = order[q]
        _point_w(p, W, NA, NB, NBz, Yz, n)
        dgemm(&nt, &nt, &four, &R, &four, &one, <double*>&Ct[p, 0, 0], &four, &W[0, 0], &four, &zero,
              &WC[0, 0], &four)
        _columns_as_rows(W, WC, Wt, WCt, 4 * q, 4, R)
        _columns_as_rows(W, WC, WtA, WCtA, 2 * q, 2, half)
    s0 = 0
    while s0 < P:
        s = s_loc[order[s0]]
        s1 = _run_end(s_loc, order, s0, P)
        # A–A: K[s, i, j] += Σ WCtA[ρ, i] WtA[ρ, j] (column-major: Kᵀ = WtAᵀ WCtA)
        k = <int>(2 * (s1 - s0))
        dgemm(&nt, &tt, &half, &half, &k, &one, &WtA[2 * s0, 0], &half, &WCtA[2 * s0, 0], &half, &one,
              &K[s, 0, 0], &D)
        g0 = s0
        while g0 < s1:
            c = col_b[order[g0]]
            g1 = _run_end(col_b, order, g0, s1)
            k = <int>(4 * (g1 - g0))
            # A–B into T (T[i, j] = Σ WCt[ρ, i] Wt[ρ, half + j]), then added at (A, B) and (B, A)
            dgemm(&nt, &tt, &half, &half, &k, &one, &Wt[4 * g0, half], &R, &WCt[4 * g0, 0], &R, &zero,
                  &T[0, 0], &half)
            for i in range(half):
                for j in range(half):
                    K[s, i, c + j] = K[s, i, c + j] + T[i, j]
                    K[s, c + j, i] = K[s, c + j, i] + T[i, j]
            # B–B: K[s, c + i, c + j] += Σ WCt[ρ, half + i] Wt[ρ, half + j]
            dgemm(&nt, &tt, &half, &half, &k, &one, &Wt[4 * g0, half], &R, &WCt[4 * g0, half], &R, &one,
                  &K[s, c, c], &D)
            g0 = g1
        s0 = s1


cdef Py_ssize_t _run_end(const long[::1] key, const long[::1] order, Py_ssize_t start,
                         Py_ssize_t stop) nogil:
    """The end of the run of points ``order[start:stop]`` sharing ``key[order[start]]``."""
    cdef Py_ssize_t end = start + 1
    while end < stop and key[order[end]] == key[order[start]]:
        end += 1
    return end


cdef void _columns_as_rows(const double[:, ::1] W, const double[:, ::1] WC, double[:, ::1] Wt,
                           double[:, ::1] WCt, Py_ssize_t row, int ncols, int nrows) nogil:
    """Columns 0 … ncols − 1 of W and W C (their first nrows rows) as rows row … of Wt, WCt."""
    cdef Py_ssize_t a, r
    for a in range(ncols):
        for r in range(nrows):
            Wt[row + a, r] = W[r, a]
            WCt[row + a, r] = WC[r, a]


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


def add_band_blocks(double[:, :, ::1] K, const long[::1] seg, const long[::1] j,
                    const double[:, ::1] pgrad, const double[:, ::1] gw, const double[::1] coef,
                    const double[:, :, ::1] hess, int el, int stride, bint variational):
    """The fade band's terms of each point p straight into its segment's block (blocks.py,
    ``_band_blocks``: bitwise its numpy values and ``add_point_blocks``): t_ab = −(p ∇g)_a ∇w_b,
    and with ``variational`` t_ab + t_ba − (p g)_p ∇²w_ab, point after point."""
    cdef Py_ssize_t n = seg.shape[0], p, a, b, ra, rb, s, b0
    cdef Py_ssize_t two = 2 * el, D = K.shape[1]
    cdef double v
    if (j.shape[0] != n or pgrad.shape[0] != n or gw.shape[0] != n or pgrad.shape[1] != two
            or gw.shape[1] != two or (variational and (coef.shape[0] != n or hess.shape[0] != n
                                                       or hess.shape[1] != two or hess.shape[2] != two))):
        raise ValueError("seg, j, pgrad, gw (n, 2 el), coef (n,) and hess (n, 2 el, 2 el) do not match")
    for p in range(n):
        if seg[p] < 0 or seg[p] >= K.shape[0] or j[p] < 0 or el + stride * j[p] + el > D or K.shape[2] != D:
            raise ValueError("a point outside the blocks")
    for p in range(n):
        s, b0 = seg[p], el + stride * j[p]
        for a in range(two):
            ra = a if a < el else b0 + a - el
            for b in range(two):
                rb = b if b < el else b0 + b - el
                v = (-pgrad[p, a]) * gw[p, b]
                if variational:
                    v = (v + (-pgrad[p, b]) * gw[p, a]) - coef[p] * hess[p, a, b]
                K[s, ra, rb] = K[s, ra, rb] + v


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
