# cython: boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled operands of the contact Jacobian's gap-Hessian term (contact/blocks.py): per segment
−Σ_p τ_p ∇²g_p = Σ_p τ_p W_p C_p W_pᵀ (contact/gap.py) as one product L R of an (D, 4 P_s) and a
(4 P_s, D) matrix, both formed here in one pass over the points (the numpy path forms W and C
per point, scatters them into the segment layout and transposes: ~25 numpy calls and three
copies of the operands per segment group).

The factors C_p are formed from the same formulas as ``gap.gap_hessian_factors`` but W_p C_p τ_p
by plain loops, not by BLAS: the product L R agrees with the numpy path to rounding (summation
order), not bitwise (tests/contact/test_blocks_native.py bounds the difference)."""
import numpy as np

cimport numpy as cnp

cnp.import_array()


cdef inline void _inverse2(double m00, double m01, double m10, double m11, double* out) nogil:
    """Inverse of [[m00, m01], [m10, m11]] into out (row-major), as gap._inverse2."""
    cdef double det = m00 * m11 - m01 * m10
    out[0] = m11 / det
    out[1] = -m01 / det
    out[2] = -m10 / det
    out[3] = m00 / det


def hessian_operands(const double[:, ::1] NA, const double[:, ::1] NB, const double[:, :, ::1] NBz,
                     const double[:, :, ::1] Yz, const double[:, :, :, ::1] Yzz,
                     const double[:, ::1] n, const double[::1] g, const double[::1] tau,
                     const long[::1] s_loc, const long[::1] p_loc, const long[::1] col_b,
                     Py_ssize_t n_s, Py_ssize_t P_s, Py_ssize_t D):
    """L (n_s, D, 4 P_s) and R (n_s, 4 P_s, D) with L R = Σ_p τ_p W_p C_p W_pᵀ per segment, over
    D unknowns.  Point p (arrays over the points: A's and B's shape functions NA, NB (P, S), B's
    ζ-derivatives NBz (P, S, 2), the surface's Y_ζ (P, 3, 2), Y_ζζ (P, 3, 2, 2), normal n,
    gap g, τ) is the ``p_loc``-th of segment ``s_loc``; its rows of W (A's S slots × 3, then
    B's) are the block's unknowns 0 … 3S − 1 and ``col_b`` … ``col_b`` + 3S − 1."""
    cdef Py_ssize_t P = NA.shape[0], S = NA.shape[1], half = 3 * NA.shape[1]
    cdef Py_ssize_t p, s, q, slot, i, k, l, a, r, col
    L_arr = np.zeros((n_s, D, 4 * P_s))
    R_arr = np.zeros((n_s, 4 * P_s, D))
    cdef double[:, :, ::1] Lm = L_arr
    cdef double[:, :, ::1] Rm = R_arr
    cdef double am[4]
    cdef double bm[4]
    cdef double ai[4]
    cdef double Hi[4]
    cdef double ab[4]
    cdef double cuu[4]
    cdef double C[16]
    cdef double w[4]
    cdef double nab, gp, t
    with nogil:
        for p in range(P):
            gp = g[p]
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
            t = tau[p]
            for k in range(2):
                for l in range(2):
                    C[4 * k + l] = 0.5 * (cuu[2 * k + l] + cuu[2 * l + k]) * t
                    C[4 * k + 2 + l] = Hi[2 * k + l] * t
                    C[4 * (2 + k) + l] = Hi[2 * k + l] * t
                    C[4 * (2 + k) + 2 + l] = gp * Hi[2 * k + l] * t
            s, q = s_loc[p], 4 * p_loc[p]
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
                        Rm[s, q + a, col] = w[a]
                        Lm[s, col, q + a] = w[0] * C[a] + w[1] * C[4 + a] + w[2] * C[8 + a] + w[3] * C[12 + a]
    return L_arr, R_arr
