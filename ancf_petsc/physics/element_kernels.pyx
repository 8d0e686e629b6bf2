# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled element kernels (Cython): internal force, tangent and min J of the neo-Hookean and
GOH laws, per element, for any number S of shape functions (3333: 9, 3363: 18, ...).

The numpy kernels (kernels.py, materials.py, goh.py) are the reference; this module computes the
same quantities point by point in C and the tangent's sum over the points with one BLAS DGEMM per
element (scipy's cython_blas), in two contractions of the shape gradients with the elasticity:

    f_a = Σ_p w P G_a                               (eq. 9; P = ∂Ψ/∂F, eqs. 18, 23, 24; goh.py)
    K[(a,i),(b,k)] = Σ_p G_aj Y[(p,j),(i,k,b)],     Y[(p,j),(i,k,b)] = w Σ_l 𝔸_ijkl G_bl

The shape functions are scalars, so K's 3 × 3 component blocks K^ik (S × S) are G 𝔸^ik Gᵀ; by
the major symmetry 𝔸_ijkl = 𝔸_klij only the six blocks i ≤ k are computed (K^ki = K^ikᵀ), and
every δ_ik term of 𝔸 (μJ^(-2/3), GOH's 2ψ'H) is part of the diagonal blocks' 3 × 3 matrices.
Each point's 𝔸 is formed in C from the same dyadic terms as materials.TangentTerms.
"""
import numpy as np

from libc.math cimport exp, pow, NAN
from libc.stdlib cimport malloc, free
from libc.string cimport memset
from scipy.linalg.cython_blas cimport dgemm


cdef extern from *:
    # a pointer the compiler may assume unaliased (C99 restrict): the loops over a vectorise
    ctypedef double* rdouble "double * __restrict__"
    ctypedef const double* crdouble "const double * __restrict__"


cdef struct Law:
    double mu, K, k1, k2, kappa, c, e_round
    int nfam


cdef double _matrix(const Law* L, const double* F, double* H, double* P, double* co) nogil:
    """J; H = F⁻ᵀ, the matrix's P (eqs. 23, 24) and its tangent's coefficients co = (μJ^(-2/3),
    c1, c2, γ) as in materials.NeoHookean.stress_and_tangent."""
    cdef double cof[9]
    cdef double J, I1 = 0.0, Jm, muJm, pJ
    cdef int k
    cof[0] = F[4] * F[8] - F[5] * F[7]
    cof[1] = F[5] * F[6] - F[3] * F[8]
    cof[2] = F[3] * F[7] - F[4] * F[6]
    cof[3] = F[2] * F[7] - F[1] * F[8]
    cof[4] = F[0] * F[8] - F[2] * F[6]
    cof[5] = F[1] * F[6] - F[0] * F[7]
    cof[6] = F[1] * F[5] - F[2] * F[4]
    cof[7] = F[2] * F[3] - F[0] * F[5]
    cof[8] = F[0] * F[4] - F[1] * F[3]
    J = F[0] * cof[0] + F[1] * cof[1] + F[2] * cof[2]
    for k in range(9):
        H[k] = cof[k] / J
        I1 += F[k] * F[k]
    Jm = pow(J, -2.0 / 3.0) if J > 0.0 else NAN
    muJm = L.mu * Jm
    pJ = L.K * (J - 1.0) * J
    for k in range(9):
        P[k] = muJm * (F[k] - (I1 / 3.0) * H[k]) + pJ * H[k]
    co[0] = muJm
    co[1] = (2.0 / 9.0) * muJm * I1 + L.K * (2.0 * J - 1.0) * J
    co[2] = -(2.0 / 3.0) * muJm
    co[3] = muJm * I1 / 3.0 - L.K * (J * J - J)
    co[4] = I1
    return J


cdef void _fibre(const Law* L, const double* F, const double* a0, double I1, double* P,
                 double* Fa, double* d) nogil:
    """One GOH family (goh.py): Fa = F a0, adds 2ψ' F H to P; d = (ψ', ψ'') with ψ'' = 0 where
    the fibre is off (Ē < −e_rounding)."""
    cdef double I4 = 0.0, E, ex, s
    cdef bint on
    cdef int i, j
    for i in range(3):
        Fa[i] = F[3 * i] * a0[0] + F[3 * i + 1] * a0[1] + F[3 * i + 2] * a0[2]
        I4 += Fa[i] * Fa[i]
    E = I4 - 1.0 if L.c == 1.0 else L.kappa * (I1 - 3.0) + L.c * (I4 - 1.0)
    on = E >= -L.e_round
    E = E if E > 0.0 else 0.0
    ex = exp(L.k2 * E * E)
    d[0] = L.k1 * E * ex
    d[1] = L.k1 * ex * (1.0 + 2.0 * L.k2 * E * E) if on else 0.0
    s = 2.0 * d[0]
    for i in range(3):
        for j in range(3):
            P[3 * i + j] += (s * L.c) * Fa[i] * a0[j] + (s * L.kappa) * F[3 * i + j]


cdef inline int _pair(int i, int k) nogil:
    """The index of the component block (i, k), i ≤ k: (0,0) (0,1) (0,2) (1,1) (1,2) (2,2)."""
    return 3 * i - i * (i - 1) // 2 + k - i


cdef void _elasticity(const Law* L, const double* F, const double* H, const double* co,
                      const double* fib, double w, rdouble A) nogil:
    """w 𝔸_ijkl of one point for the pairs i ≤ k, A[(pair, j, l)] (54 numbers): the matrix's
    μJ^(-2/3) δ_ik δ_jl + (c1 H + c2 F) ⊗ H + c2 H ⊗ F + γ H ⊠ H (materials.NeoHookean) and
    per GOH family 2ψ'H_jl δ_ik + 4ψ'' (FH) ⊗ (FH), FH = κF + (1 − 3κ) Fa0 ⊗ a0 (goh.py)."""
    cdef int i, k, j, l, m, n
    cdef double V[9]
    cdef double T[9]
    cdef double wH[9]
    cdef double c2 = w * co[2], g = w * co[3], iso = co[0], r, d2
    cdef const double* fb
    cdef rdouble Aq
    for j in range(9):
        V[j] = w * (co[1] * H[j] + co[2] * F[j])
        wH[j] = c2 * H[j]
    n = 0
    for i in range(3):
        for k in range(i, 3):
            Aq = A + 9 * n
            for j in range(3):
                for l in range(3):
                    Aq[3 * j + l] = (V[3 * i + j] * H[3 * k + l] + wH[3 * i + j] * F[3 * k + l]
                                     + g * H[3 * k + j] * H[3 * i + l])
            n += 1
    for m in range(L.nfam):
        fb = fib + 8 * m
        iso += 2.0 * L.kappa * fb[6]
        r = w * 2.0 * L.c * fb[6]
        d2 = w * 4.0 * fb[7]
        if d2 != 0.0:
            for i in range(3):
                for j in range(3):
                    T[3 * i + j] = L.kappa * F[3 * i + j] + L.c * fb[3 + i] * fb[j]
            n = 0
            for i in range(3):
                for k in range(i, 3):
                    Aq = A + 9 * n
                    for j in range(3):
                        for l in range(3):
                            Aq[3 * j + l] += d2 * T[3 * i + j] * T[3 * k + l]
                    n += 1
        for i in range(3):
            Aq = A + 9 * _pair(i, i)
            for j in range(3):
                for l in range(3):
                    Aq[3 * j + l] += r * fb[j] * fb[l]
    for i in range(3):          # δ_ik δ_jl: the diagonal of the blocks (0,0), (1,1), (2,2)
        for j in range(3):
            A[9 * _pair(i, i) + 4 * j] += w * iso


cdef void _y_rows(const double* A, crdouble Gc, int S, rdouble Y) nogil:
    """Y[j, (pair, b)] = Σ_l A[pair, j, l] G_bl of one point: its 3 rows of 6S; Gc is (3, S)."""
    cdef int q, j
    cdef Py_ssize_t b
    cdef double a0, a1, a2
    cdef crdouble g0 = Gc
    cdef crdouble g1 = Gc + S
    cdef crdouble g2 = Gc + 2 * S
    cdef rdouble y
    for j in range(3):
        for q in range(6):
            a0 = A[9 * q + 3 * j]
            a1 = A[9 * q + 3 * j + 1]
            a2 = A[9 * q + 3 * j + 2]
            y = Y + (6 * j + q) * S
            for b in range(S):
                y[b] = a0 * g0[b] + a1 * g1[b] + a2 * g2[b]


cdef void _write_tangent(const double* C, int S, double* K) nogil:
    """K[(a,i),(b,k)] from C[a, (pair(i,k), b)] (blocks i ≤ k; the others by symmetry)."""
    cdef int a, b, i, k, D = 3 * S
    cdef double* Kr
    for a in range(S):
        for i in range(3):
            Kr = K + (3 * a + i) * D
            for k in range(3):
                if i <= k:
                    for b in range(S):
                        Kr[3 * b + k] = C[(6 * a + _pair(i, k)) * S + b]
                else:
                    for b in range(S):
                        Kr[3 * b + k] = C[(6 * b + _pair(k, i)) * S + a]


#: Gauss points per DGEMM of the tangent: OpenBLAS multiplies without packing (its small-matrix
#: kernels) while m n k <= 1e6; the rows Y of a chunk then also stay in the L2 cache
DEF GEMM_MNK = 1000000


cdef struct Work:
    double *q       # (3, S): the element's nodal vectors, component-major
    double *GT      # (S, P, 3): gradients G[a, (p, j)], a copy when G is not stored so
    const double *Gk    # G[a, (p, j)]: GT, or the element's G itself (the DGEMMs' shared factor)
    double *Gc      # (P, 3, S): gradients per point, component-major (the loops over b vectorise)
    double *Fs      # (3, P, 3): F of every point, F[i, (p, j)]
    double *wP      # (3, P, 3): w P[i, (p, j)]
    double *Y       # (3 chunk, 6S): the rows (p, j) of a chunk of points
    double *C       # (S, 6S)
    double *fib     # per family: a0, Fa, ψ', ψ''
    double *Ap      # 54: w 𝔸 of one point, pairs i ≤ k


cdef double* _work(Work* ws, int S, int P, int chunk, int nfam, bint tangent) except NULL:
    """Per-call scratch for one element (in cache)."""
    cdef size_t t = (18 * S * chunk + 6 * S * S) if tangent else 0
    cdef size_t n = 3 * S + 6 * S * P + 18 * P + t + 8 * nfam + 54
    cdef double* mem = <double*> malloc(n * sizeof(double))
    if mem == NULL:
        raise MemoryError()
    ws.q = mem
    ws.GT = ws.q + 3 * S
    ws.Gc = ws.GT + 3 * S * P
    ws.Fs = ws.Gc + 3 * S * P
    ws.wP = ws.Fs + 9 * P
    ws.Y = ws.wP + 9 * P
    ws.C = ws.Y + (18 * S * chunk if tangent else 0)
    ws.fib = ws.C + (6 * S * S if tangent else 0)
    ws.Ap = ws.fib + 8 * nfam
    return mem


cdef void _load(Work* ws, const double[:, :, :] q, const double[:, :, :, :] G, int e, bint rows) nogil:
    """The element's q and G into the scratch layouts, and F of every point, Fs[i, (p, j)]
    (eq. 7).  G as stored by ``Model.element_data`` ((E, S, P, 3) in memory) is used in place."""
    cdef int S = G.shape[2], P = G.shape[1], a, i, j
    cdef Py_ssize_t p, n3 = 3 * P
    cdef bint stored = (G.strides[3] == sizeof(double) and G.strides[1] == 3 * sizeof(double)
                        and G.strides[2] == n3 * sizeof(double))
    cdef double qa
    cdef rdouble g
    cdef rdouble Fr
    cdef crdouble gc
    ws.Gk = &G[e, 0, 0, 0] if stored else ws.GT
    for a in range(S):
        if not stored:
            g = ws.GT + a * n3
            for p in range(P):
                for j in range(3):
                    g[3 * p + j] = G[e, p, a, j]
        for i in range(3):
            ws.q[i * S + a] = q[e, a, i]
    for p in range(n3 if rows else 0):  # Gc (P, 3, S) for the tangent's rows: strided reads
        for a in range(S):
            ws.Gc[p * S + a] = ws.Gk[a * n3 + p]
    memset(ws.Fs, 0, 9 * P * sizeof(double))
    for a in range(S):
        gc = ws.Gk + a * n3
        for i in range(3):
            qa = ws.q[i * S + a]
            Fr = ws.Fs + i * n3
            for p in range(n3):
                Fr[p] += qa * gc[p]


cdef void _element(const Law* L, Work* ws, const double[:, :, :] q, const double[:, :, :, :] G,
                   const double[:, :] w, const double[:, :, :, :] a0, int e, int chunk,
                   double* fe, double* Jmin, double* Ke) nogil:
    """Force (and tangent if Ke) of element e; Jmin its smallest J."""
    cdef int S = G.shape[2], P = G.shape[1], p, i, m, n3 = 3 * P, m6 = 6 * S, three = 3, k, p0 = 0
    cdef double F[9]
    cdef double H[9]
    cdef double Pk[9]
    cdef double co[5]
    cdef double J, wp, one = 1.0, zero = 0.0, beta = 0.0
    cdef double* fb
    cdef char N = b'N', T = b'T'
    _load(ws, q, G, e, Ke != NULL)
    for p in range(P):
        for i in range(9):
            F[i] = ws.Fs[(i // 3) * n3 + 3 * p + i % 3]
        J = _matrix(L, F, H, Pk, co)
        Jmin[0] = J if p == 0 or J < Jmin[0] or J != J else Jmin[0]
        for m in range(L.nfam):
            fb = ws.fib + 8 * m
            for i in range(3):
                fb[i] = a0[m, e, p, i]
            _fibre(L, F, fb, co[4], Pk, fb + 3, fb + 6)
        wp = w[e, p]
        for i in range(9):
            ws.wP[(i // 3) * n3 + 3 * p + i % 3] = wp * Pk[i]
        if Ke != NULL:
            _elasticity(L, F, H, co, ws.fib, wp, ws.Ap)
            _y_rows(ws.Ap, ws.Gc + 3 * S * p, S, ws.Y + 18 * S * (p - p0))
            if p + 1 - p0 == chunk or p + 1 == P:
                # C[a, (pair, b)] += Σ_(p,j) G[a, (p, j)] Y[(p, j), (pair, b)]  (column-major 6S × S)
                k = 3 * (p + 1 - p0)
                dgemm(&N, &N, &m6, &S, &k, &one, ws.Y, &m6, <double*> ws.Gk + 3 * p0, &n3, &beta, ws.C, &m6)
                beta = 1.0
                p0 = p + 1
    # f[a, i] = Σ_(p,j) G[a, (p, j)] wP[i, (p, j)]: f (3 × S, column-major) = wPᵀ G
    dgemm(&T, &N, &three, &S, &n3, &one, ws.wP, &n3, <double*> ws.Gk, &n3, &zero, fe, &three)
    if Ke != NULL:
        _write_tangent(ws.C, S, Ke)


def evaluate(qe, G, w, tuple law, a0=None, bint tangent=True, int chunk=0):
    """(f (E, 3S), K (E, 3S, 3S) or None, min J (E,)) of qe (E, S, 3), G (E, P, S, 3), w (E, P)
    for law = (μ, K, k1, k2, κ, e_rounding) and a0 (families, E, P, 3) or None (neo-Hookean);
    ``chunk``: Gauss points per DGEMM of the tangent (0: as many as ``GEMM_MNK`` allows)."""
    cdef const double[:, :, :] q_v = qe
    cdef const double[:, :, :, :] G_v = G
    cdef const double[:, :] w_v = w
    cdef const double[:, :, :, :] a_v = np.zeros((0, 1, 1, 3)) if a0 is None else a0
    cdef int E = G_v.shape[0], P = G_v.shape[1], S = G_v.shape[2], D = 3 * S, e
    cdef Law L
    L.mu, L.K, L.k1, L.k2, L.kappa, L.e_round = law[0], law[1], law[2], law[3], law[4], law[5]
    L.c = 1.0 - 3.0 * L.kappa
    L.nfam = a_v.shape[0]
    if q_v.shape[0] != E or q_v.shape[1] != S or q_v.shape[2] != 3 or G_v.shape[3] != 3 \
            or w_v.shape[0] != E or w_v.shape[1] != P or a_v.shape[3] != 3 \
            or (L.nfam and (a_v.shape[1] != E or a_v.shape[2] != P)):
        raise ValueError("element_kernels.evaluate: inconsistent shapes")
    f = np.empty((E, D))
    Jmin = np.empty(E)
    K = np.empty((E, D, D)) if tangent else None
    cdef double[:, ::1] f_v = f
    cdef double[::1] J_v = Jmin
    cdef double[:, :, ::1] K_v = K if tangent else np.empty((1, 1, 1))
    cdef Work ws
    chunk = max(1, min(P, chunk if chunk > 0 else GEMM_MNK // (18 * S * S)))
    cdef double* mem = _work(&ws, S, P, chunk, L.nfam, tangent)
    try:
        with nogil:
            for e in range(E):
                _element(&L, &ws, q_v, G_v, w_v, a_v, e, chunk, &f_v[e, 0], &J_v[e],
                         &K_v[e, 0, 0] if tangent else NULL)
    finally:
        free(mem)
    return f, K, Jmin
