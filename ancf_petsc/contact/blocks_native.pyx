# distutils: extra_compile_args = -ffp-contract=off
# cython: boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled parts of the normal contact's residual and Jacobian (contact/blocks.py): the points'
forces scattered onto their elements' DOFs (``add_point_forces``, bitwise the numpy code: no
fused multiply-adds, ``-ffp-contract=off``) and the gap-Hessian term (``add_gap_hessian``): per segment
−Σ_p τ_p ∇²g_p = Σ_p τ_p W_p C_p W_pᵀ (contact/gap.py) as one BLAS product L R (L = [W_p C_p τ_p],
R = [W_pᵀ] over the segment's points) added into the segment's block, the operands formed here in
one pass over its points (the numpy path forms W and C per point, scatters them into a padded
segment layout, transposes, multiplies into a temporary and adds: ~25 numpy calls and four
copies of the operands per segment group).

The factors C_p of the Hessian term are formed from the same formulas as
``gap.gap_hessian_factors`` but W_p C_p τ_p by plain loops and the sum over the points in other
blocks: it agrees with the numpy path to rounding (summation order), not bitwise (tests/contact/test_blocks_native.py bounds the difference)."""
import numpy as np

cimport numpy as cnp
from scipy.linalg.cython_blas cimport dgemm

cnp.import_array()


cdef inline void _inverse2(double m00, double m01, double m10, double m11, double* out) nogil:
    """Inverse of [[m00, m01], [m10, m11]] into out (row-major), as gap._inverse2."""
    cdef double det = m00 * m11 - m01 * m10
    out[0] = m11 / det
    out[1] = -m01 / det
    out[2] = -m10 / det
    out[3] = m00 / det


def add_gap_hessian(double[:, :, ::1] K, const double[:, ::1] NA, const double[:, ::1] NB,
                    const double[:, :, ::1] NBz, const double[:, :, ::1] Yz,
                    const double[:, :, :, ::1] Yzz, const double[:, ::1] n, const double[::1] g,
                    const double[::1] tau, const long[::1] s_loc, const long[::1] col_b, int Dq):
    """K[s, :Dq, :Dq] += Σ_p τ_p W_p C_p W_pᵀ over the points p of each segment s (``s_loc``),
    two BLAS products per segment into K.  The points' arrays: A's and B's shape functions NA,
    NB (P, S), B's ζ-derivatives NBz (P, S, 2), the surface's Y_ζ (P, 3, 2), Y_ζζ (P, 3, 2, 2),
    normal n, gap g, τ; point p's rows of W (A's S slots × 3, then B's) are the block's unknowns
    0 … 3S − 1 and ``col_b[p]`` … ``col_b[p]`` + 3S − 1."""
    cdef Py_ssize_t P = NA.shape[0], n_s = K.shape[0]
    cdef Py_ssize_t p, s, m, most = 0
    cdef int k, ldl, D = K.shape[1], ea = 3 * NA.shape[1], eb = Dq - 3 * NA.shape[1]
    cdef double one = 1.0
    cdef char trans = b'N'
    if K.shape[2] != D or Dq > D:
        raise ValueError("K must be (n_s, D, D) with Dq <= D")
    counts = np.zeros(n_s + 1, dtype=np.int64)
    cdef long[::1] start = counts
    for p in range(P):
        if s_loc[p] < 0 or s_loc[p] >= n_s or col_b[p] < 3 * NA.shape[1] or col_b[p] + 3 * NA.shape[1] > Dq:
            raise ValueError("a point outside the blocks")
        start[s_loc[p] + 1] += 1
    for s in range(n_s):
        most = max(most, start[s + 1])
        start[s + 1] += start[s]
    order_arr = np.empty(P, dtype=np.int64)
    fill_arr = counts[:n_s].copy()
    cdef long[::1] order = order_arr
    cdef long[::1] fill = fill_arr
    for p in range(P):
        order[fill[s_loc[p]]] = p
        fill[s_loc[p]] += 1
    L_arr = np.empty((Dq, 4 * most))
    R_arr = np.empty((4 * most, Dq))
    cdef double[:, ::1] Lm = L_arr
    cdef double[:, ::1] Rm = R_arr
    ldl = 4 * most
    for s in range(n_s):
        m = start[s + 1] - start[s]
        if m == 0:
            continue
        L_arr[:, :4 * m] = 0.0
        R_arr[:4 * m] = 0.0
        for k in range(m):
            _point_rows(order[start[s] + k], 2 * k, 2 * m, Lm, Rm, NA, NB, NBz, Yz, Yzz, n, g, tau, col_b)
        # column-major: K_sᵀ += Rᵀ Lᵀ, i.e. row-major K_s += L R; A's rows of W have no v part
        # (R's last 2m rows are 0 in A's columns): those columns take the u part alone
        k = 2 * m
        dgemm(&trans, &trans, &ea, &Dq, &k, &one, &Rm[0, 0], &Dq, &Lm[0, 0], &ldl, &one,
              &K[s, 0, 0], &D)
        k = 4 * m
        dgemm(&trans, &trans, &eb, &Dq, &k, &one, &Rm[0, ea], &Dq, &Lm[0, 0], &ldl, &one,
              &K[s, 0, ea], &D)


cdef void _point_rows(Py_ssize_t p, Py_ssize_t q, Py_ssize_t v, double[:, ::1] Lm, double[:, ::1] Rm,
                      const double[:, ::1] NA, const double[:, ::1] NB, const double[:, :, ::1] NBz,
                      const double[:, :, ::1] Yz, const double[:, :, :, ::1] Yzz,
                      const double[:, ::1] n, const double[::1] g, const double[::1] tau,
                      const long[::1] col_b) nogil:
    """Point p's columns of L = W C τ and rows of R = Wᵀ, u parts at q, q + 1 and v parts at
    v + q, v + q + 1 (gap.gap_hessian_factors:
    C = [[a⁻¹ b H⁻¹ (symmetrised), H⁻¹], [H⁻¹, g H⁻¹]], H = a − g b)."""
    cdef Py_ssize_t S = NA.shape[1], half = 3 * NA.shape[1], slot, i, k, l, a, r, col
    cdef double am[4]
    cdef double bm[4]
    cdef double ai[4]
    cdef double Hi[4]
    cdef double ab[4]
    cdef double cuu[4]
    cdef double C[16]
    cdef double w[4]
    cdef double nab, gp = g[p], t = tau[p]
    for k in range(2):
        for l in range(2):
            am[2 * k + l] = Yz[p, 0, k] * Yz[p, 0, l] + Yz[p, 1, k] * Yz[p, 1, l] + Yz[p, 2, k] * Yz[p, 2, l]
            bm[2 * k + l] = Yzz[p, 0, k, l] * n[p, 0] + Yzz[p, 1, k, l] * n[p, 1] + Yzz[p, 2, k, l] * n[p, 2]
    _inverse2(am[0] - gp * bm[0], am[1] - gp * bm[1], am[2] - gp * bm[2], am[3] - gp * bm[3], Hi)
    _inverse2(am[0], am[1], am[2], am[3], ai)
    for k in range(2):
        for l in range(2):
            ab[2 * k + l] = ai[2 * k] * bm[l] + ai[2 * k + 1] * bm[2 + l]
    for k in range(2):
        for l in range(2):
            cuu[2 * k + l] = ab[2 * k] * Hi[l] + ab[2 * k + 1] * Hi[2 + l]
    for k in range(2):
        for l in range(2):
            C[4 * k + l] = 0.5 * (cuu[2 * k + l] + cuu[2 * l + k]) * t
            C[4 * k + 2 + l] = Hi[2 * k + l] * t
            C[4 * (2 + k) + l] = Hi[2 * k + l] * t
            C[4 * (2 + k) + 2 + l] = gp * Hi[2 * k + l] * t
    for slot in range(2 * S):
        nab = NA[p, slot] if slot < S else -NB[p, slot - S]
        for i in range(3):
            r = 3 * slot + i
            col = r if r < half else col_b[p] + r - half
            w[0] = nab * Yz[p, i, 0]
            w[1] = nab * Yz[p, i, 1]
            if slot < S:
                w[2] = 0.0
                w[3] = 0.0
            else:
                w[2] = NBz[p, slot - S, 0] * n[p, i]
                w[3] = NBz[p, slot - S, 1] * n[p, i]
            for a in range(4):
                l = q + a if a < 2 else v + q + a - 2
                Rm[l, col] = w[a]
                Lm[col, l] = w[0] * C[a] + w[1] * C[4 + a] + w[2] * C[8 + a] + w[3] * C[12 + a]


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
