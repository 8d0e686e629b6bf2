# distutils: extra_compile_args = -ffp-contract=off
# cython: boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled kernels of the closest-point descent: B's shape functions on its interface surface
(``surface.shape_on_curve`` for blocks with quadratic Lagrange axial functions) and the step
(``descent.newton_step``), one pass over the points each instead of ~60 numpy calls.

Every value is formed by the same floating-point operations in the same order as the numpy
original (no contraction into fused multiply-adds: ``-ffp-contract=off``), so the results are
bitwise equal to it (tests/contact/test_descent_native.py checks that)."""
import numpy as np

cimport numpy as cnp
from libc.math cimport fabs
from scipy.linalg.cython_blas cimport dgemm, dgemv

cnp.import_array()


def shapes(const double[::1] xi, const double[:, ::1] S, const double[:, ::1] S1,
           const double[:, ::1] S2, const long[:, ::1] ey, const long[:, ::1] ez,
           const double[:, ::1] coef, const cnp.uint8_t[:, ::1] live, int order):
    """N (P, 3V), N_ζ (P, 3V, 2) and N_ζζ (P, 3V, 2, 2) of a three-node block of V monomials at
    section points S(t) (S1 = S', S2 = S''): ``surface.shape_on_curve`` with S2.  ``ey``, ``ez``,
    ``coef``, ``live`` (6, V): the block's derivative table of the pairs (0,0), (1,0), (0,1),
    (2,0), (1,1), (0,2) (``base.derivative_table``); the last three are used for order ≥ 2."""
    cdef Py_ssize_t P = xi.shape[0], V = ey.shape[1], SL = 3 * V
    cdef Py_ssize_t p, a, v, n, k, np_ = 6 if order >= 2 else 3
    N_arr = np.empty((P, SL))
    Nz_arr = np.empty((2, P, SL))
    Nzz_arr = np.empty((2, 2, P, SL))
    cdef double[:, ::1] N = N_arr
    cdef double[:, :, ::1] Nz = Nz_arr
    cdef double[:, :, :, ::1] Nzz = Nzz_arr
    cdef double x, y, z, y1, z1, y2, z2, m, mt, mtt
    cdef double L[3]
    cdef double dL[3]
    cdef double ddL[3]
    cdef double Yp[16]
    cdef double Zp[16]
    cdef double d[6]
    ddL[0], ddL[1], ddL[2] = 1.0, -2.0, 1.0
    if order > 15:
        raise ValueError("section order above 15")
    for p in range(P):
        x = xi[p]
        L[0] = 0.5 * x * (x - 1.0)
        L[1] = 1.0 - x * x
        L[2] = 0.5 * x * (x + 1.0)
        dL[0] = x - 0.5
        dL[1] = -2.0 * x
        dL[2] = x + 0.5
        y, z = S[p, 0], S[p, 1]
        y1, z1, y2, z2 = S1[p, 0], S1[p, 1], S2[p, 0], S2[p, 1]
        Yp[0] = 1.0
        Zp[0] = 1.0
        for n in range(1, order + 1):
            Yp[n] = y if n == 1 else Yp[n - 1] * y
            Zp[n] = z if n == 1 else Zp[n - 1] * z
        for v in range(V):
            for k in range(np_):
                d[k] = coef[k, v] * (Yp[ey[k, v]] * Zp[ez[k, v]]) if live[k, v] else 0.0
            m = d[0]
            mt = d[1] * y1 + d[2] * z1
            mtt = d[1] * y2 + d[2] * z2
            if order >= 2:
                mtt = mtt + (d[3] * (y1 * y1) + d[5] * (z1 * z1) + d[4] * (2.0 * y1 * z1))
            for a in range(3):
                N[p, a * V + v] = L[a] * m
                Nz[0, p, a * V + v] = dL[a] * m
                Nz[1, p, a * V + v] = L[a] * mt
                Nzz[0, 0, p, a * V + v] = ddL[a] * m
                Nzz[0, 1, p, a * V + v] = dL[a] * mt
                Nzz[1, 0, p, a * V + v] = dL[a] * mt
                Nzz[1, 1, p, a * V + v] = L[a] * mtt
    return N_arr, Nz_arr.transpose(1, 2, 0), Nzz_arr.transpose(2, 3, 0, 1)


def newton_step(const double[:, :, :] Yz, const double[:, :, :, :] Yzz, const double[:, :] d,
                const cnp.uint8_t[::1] pinned, bint metric):
    """``descent.newton_step`` (dζ (P, 2), φ_ζ (P, 2)) for all points in one pass."""
    cdef Py_ssize_t P = d.shape[0], p, i
    dz_arr = np.empty((P, 2))
    r_arr = np.empty((P, 2))
    cdef double[:, ::1] dz = dz_arr
    cdef double[:, ::1] r = r_arr
    cdef double r0, r1, G00, G01, G10, G11, H00, H01, H10, H11, det, shift
    for p in range(P):
        r0 = -(Yz[p, 0, 0] * d[p, 0] + Yz[p, 1, 0] * d[p, 1] + Yz[p, 2, 0] * d[p, 2])
        r1 = -(Yz[p, 0, 1] * d[p, 0] + Yz[p, 1, 1] * d[p, 1] + Yz[p, 2, 1] * d[p, 2])
        G00 = Yz[p, 0, 0] * Yz[p, 0, 0] + Yz[p, 1, 0] * Yz[p, 1, 0] + Yz[p, 2, 0] * Yz[p, 2, 0]
        G01 = Yz[p, 0, 0] * Yz[p, 0, 1] + Yz[p, 1, 0] * Yz[p, 1, 1] + Yz[p, 2, 0] * Yz[p, 2, 1]
        G10 = Yz[p, 0, 1] * Yz[p, 0, 0] + Yz[p, 1, 1] * Yz[p, 1, 0] + Yz[p, 2, 1] * Yz[p, 2, 0]
        G11 = Yz[p, 0, 1] * Yz[p, 0, 1] + Yz[p, 1, 1] * Yz[p, 1, 1] + Yz[p, 2, 1] * Yz[p, 2, 1]
        H00 = G00 - (Yzz[p, 0, 0, 0] * d[p, 0] + Yzz[p, 1, 0, 0] * d[p, 1] + Yzz[p, 2, 0, 0] * d[p, 2])
        H01 = G01 - (Yzz[p, 0, 0, 1] * d[p, 0] + Yzz[p, 1, 0, 1] * d[p, 1] + Yzz[p, 2, 0, 1] * d[p, 2])
        H10 = G10 - (Yzz[p, 0, 1, 0] * d[p, 0] + Yzz[p, 1, 1, 0] * d[p, 1] + Yzz[p, 2, 1, 0] * d[p, 2])
        H11 = G11 - (Yzz[p, 0, 1, 1] * d[p, 0] + Yzz[p, 1, 1, 1] * d[p, 1] + Yzz[p, 2, 1, 1] * d[p, 2])
        det = H00 * H11 - H01 * H10
        if det <= 0.0 or H00 <= 0.0 or H11 <= 0.0:
            if metric:
                H00, H01, H10, H11 = G00, G01, G10, G11
            else:
                shift = max(max(fabs(H00), fabs(H01)), max(fabs(H10), fabs(H11)))
                H00 = H00 + shift
                H11 = H11 + shift
            det = H00 * H11 - H01 * H10
        r[p, 0], r[p, 1] = r0, r1
        if pinned[p]:
            dz[p, 0] = 0.0
            dz[p, 1] = -r1 / H11
        else:
            dz[p, 0] = -(H11 * r0 - H01 * r1) / det
            dz[p, 1] = -(-H10 * r0 + H00 * r1) / det
    return dz_arr, r_arr


cdef inline Py_ssize_t _interval(const double* t, Py_ssize_t nt, int k, double x) nogil:
    """scipy's ``find_interval`` (extrapolating, no previous interval): ℓ with t_ℓ ≤ x < t_ℓ+1
    within [k, n − 1]; −1 for NaN."""
    cdef Py_ssize_t n = nt - k - 1, l = k
    if x != x:
        return -1
    while x < t[l] and l != k:
        l -= 1
    l += 1
    while x >= t[l] and l != n:
        l += 1
    return l - 1


def curves(const long[::1] which, const double[::1] tp, const double[::1] t_end, const double[::1] knots,
           const double[:, ::1] coefs, const long[:, ::1] spec, const double[:, ::1] shifts,
           const cnp.uint8_t[::1] flipped):
    """``surface.InterfaceCurves.__call__`` (S + shift, S', S'') at parameters ``tp`` of curves
    ``which`` (a reversed curve at t_end − t): each spline evaluated as scipy's
    ``_bspl.evaluate_spline`` does (``_deBoor_D``, then Σ_a c[ℓ − k + a] h_a from a = 0).  ``spec``
    (curves × 3 derivatives, 4): knot offset, knot count, coefficient offset, degree (count −1:
    no such derivative, 0 returned)."""
    cdef Py_ssize_t P = tp.shape[0], p, nu, j, n, a, jp, ell, nt
    cdef int k
    cdef long w
    cdef double xv, xa, xb, wgt, acc
    cdef double h[32]
    cdef double hh[32]
    out = np.zeros((3, P, 2))
    cdef double[:, :, ::1] o = out
    cdef const double* t
    for p in range(P):
        w = which[p]
        xv = t_end[w] - tp[p] if flipped[w] else tp[p]
        for nu in range(3):
            nt = spec[w * 3 + nu, 1]
            if nt < 0:
                continue
            t = &knots[spec[w * 3 + nu, 0]]
            k = <int>spec[w * 3 + nu, 3]
            ell = _interval(t, nt, k, xv)
            if ell < 0:
                o[nu, p, 0] = xv
                o[nu, p, 1] = xv
                continue
            h[0] = 1.0
            for j in range(1, k + 1):
                for n in range(j):
                    hh[n] = h[n]
                h[0] = 0.0
                for n in range(1, j + 1):
                    xb = t[ell + n]
                    xa = t[ell + n - j]
                    if xb == xa:
                        h[n] = 0.0
                        continue
                    wgt = hh[n - 1] / (xb - xa)
                    h[n - 1] += wgt * (xb - xv)
                    h[n] = wgt * (xv - xa)
            for jp in range(2):
                acc = 0.0
                for a in range(k + 1):
                    acc = acc + coefs[spec[w * 3 + nu, 2] + ell + a - k, jp] * h[a]
                o[nu, p, jp] = acc
        o[0, p, 0] = o[0, p, 0] + shifts[w, 0]
        o[0, p, 1] = o[0, p, 1] + shifts[w, 1]
        if flipped[w]:
            o[1, p, 0] = -o[1, p, 0]
            o[1, p, 1] = -o[1, p, 1]
    return out[0], out[1], out[2]


def surface_products(const double[:, :, ::1] qB, const double[:, ::1] NB, const double[:, :, :] NBz,
                     const double[:, :, :] NBzz4):
    """Y (P, 3), Y_ζ (P, 3, 2), Y_ζζ (P, 3, 4) of ``projection.Projector.surface`` from B's nodal
    vectors qB (P, S, 3) and the shape functions of ``shapes`` (N_ζ and N_ζζ as it returns them:
    transposed views, (P, S, 2) and (P, S, 4) with unit stride along S): per point the BLAS calls
    numpy's matmul makes for ``NB[:, None, :] @ qB`` (gemv), ``qBᵀ @ NBz`` and ``qBᵀ @ NBzz``
    (gemm, both operands transposed: the views' layout), so the values are bitwise numpy's."""
    cdef Py_ssize_t P = qB.shape[0], p
    cdef int S = qB.shape[1], three = 3, two = 2, four = 4, inc = 1, ldz, ldzz
    cdef double one = 1.0, zero = 0.0
    cdef char tn = b'N', tt = b'T'
    if (NB.shape[0] != P or NBz.shape[0] != P or NBzz4.shape[0] != P or qB.shape[2] != 3
            or NB.shape[1] != S or NBz.shape[1] != S or NBzz4.shape[1] != S or NBz.shape[2] != 2
            or NBzz4.shape[2] != 4 or NBz.strides[1] != 8 or NBzz4.strides[1] != 8
            or NBz.strides[2] % 8 or NBzz4.strides[2] % 8 or NBz.strides[2] < 8 * S or NBzz4.strides[2] < 8 * S):
        raise ValueError("unexpected shapes or layout")
    ldz, ldzz = NBz.strides[2] // 8, NBzz4.strides[2] // 8
    Y_arr, Yz_arr, Yzz_arr = np.empty((P, 3)), np.empty((P, 3, 2)), np.empty((P, 3, 4))
    cdef double[:, ::1] Y = Y_arr
    cdef double[:, :, ::1] Yz = Yz_arr
    cdef double[:, :, ::1] Yzz = Yzz_arr
    for p in range(P):
        # cblas_dgemv(RowMajor, Trans, S, 3, 1, qB_p, 3, NB_p, 1, 0, Y_p, 1)
        dgemv(&tn, &three, &S, &one, <double*>&qB[p, 0, 0], &three, <double*>&NB[p, 0], &inc, &zero,
              &Y[p, 0], &inc)
        # cblas_dgemm(RowMajor, Trans, Trans, 3, k, S, 1, qB_p, 3, N_p, ld, 0, out_p, k)
        dgemm(&tt, &tt, &two, &three, &S, &one, <double*>&NBz[p, 0, 0], &ldz, <double*>&qB[p, 0, 0],
              &three, &zero, &Yz[p, 0, 0], &two)
        dgemm(&tt, &tt, &four, &three, &S, &one, <double*>&NBzz4[p, 0, 0], &ldzz, <double*>&qB[p, 0, 0],
              &three, &zero, &Yzz[p, 0, 0], &four)
    return Y_arr, Yz_arr, Yzz_arr
