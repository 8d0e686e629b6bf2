# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled element kernels (Cython): internal force, tangent and min J of the neo-Hookean and
GOH laws, per element, for any number S of shape functions (3333: 9, 3363: 18, ...).

The numpy kernels (kernels.py, materials.py, goh.py) are the reference; this module computes the
same quantities point by point in C and contracts the tangent with BLAS (scipy's cython_blas):

    f_a = Σ_p w P G_a                                  (eq. 9, P = ∂Ψ/∂F, eqs. 18, 23, 24)
    K[(a,i),(b,k)] = Σ_p w G_aj 𝔸_ijkl G_bl = Kq[(a,i),(b,k)] + Z[(a,k),(b,i)] + δ_ik Ks[a,b]

Every part is a symmetric sum of signed rank-one terms λ u uᵀ: the outer terms of 𝔸 on the vectors
h = F⁻ᵀG_a and f = F G_a (the 2 × 2 form [[c1, c2], [c2, 0]] diagonalised by one Jacobi rotation)
and a fibre's 4ψ'' t tᵀ go to Kq (D × D, D = 3S); the cross term γ F⁻ᵀ ⊠ F⁻ᵀ is γ h hᵀ with the
two component indices swapped (Z); the δ_ik terms (μJ^(-2/3) + 2κψ') G_a·G_b and 2(1 − 3κ)ψ'
(G_a·a0)(G_b·a0) form an S × S matrix Ks added to the three diagonal blocks.  Rows √|λ| u are
stored by the sign of λ and each part is two DSYRKs (one triangle), mirrored when K is written.
"""
import numpy as np

from libc.math cimport sqrt, exp, fabs, pow, hypot, NAN
from libc.stdlib cimport malloc, free
from libc.string cimport memset
from scipy.linalg.cython_blas cimport dsyrk


cdef struct Law:
    double mu, K, k1, k2, kappa, c, e_round
    int nfam


cdef struct Rows:
    double* buf     # cap rows of n doubles: positive rows from the top, negative from the bottom
    int n, cap, npos, nneg


cdef inline double* _row(Rows* r, double lam, double* scale) nogil:
    """The next row for λ (its sign picks the group) and √|λ| in scale; NULL for λ = 0."""
    if lam == 0.0:
        return NULL
    scale[0] = sqrt(fabs(lam))
    if lam > 0.0:
        r.npos += 1
        return r.buf + (r.npos - 1) * r.n
    r.nneg += 1
    return r.buf + (r.cap - r.nneg) * r.n


cdef void _syrk(Rows* r, double* C) nogil:
    """C (n × n, lower triangle in column-major order) = Σ_pos u uᵀ − Σ_neg u uᵀ."""
    cdef double one = 1.0, minus = -1.0, zero = 0.0
    cdef char L = b'L', N = b'N'
    if r.npos:
        dsyrk(&L, &N, &r.n, &r.npos, &one, r.buf, &r.n, &zero, C, &r.n)
    else:
        memset(C, 0, r.n * r.n * sizeof(double))
    if r.nneg:
        dsyrk(&L, &N, &r.n, &r.nneg, &minus, r.buf + (r.cap - r.nneg) * r.n, &r.n, &one, C, &r.n)
    r.npos = 0
    r.nneg = 0


cdef inline double _sym(const double* C, int n, int x, int y) nogil:
    return C[y * n + x] if x >= y else C[x * n + y]


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


cdef void _tangent_rows(const Law* L, const double* Gp, int S, double w, const double* F,
                        const double* H, const double* co, const double* fib, Rows* rq,
                        Rows* rz, Rows* rs, double* h, double* f) nogil:
    """The rows of Kq, Z and Ks of one point (module docstring); fib holds per family
    (a0, Fa, ψ', ψ'')."""
    cdef int a, i, D = 3 * S, m
    cdef double lam1, lam2, tau, t, cs, sn, sc, iso = co[0], g
    cdef double* u
    cdef double* v
    cdef const double* fb
    for a in range(S):
        for i in range(3):
            h[3 * a + i] = H[3 * i] * Gp[3 * a] + H[3 * i + 1] * Gp[3 * a + 1] + H[3 * i + 2] * Gp[3 * a + 2]
            f[3 * a + i] = F[3 * i] * Gp[3 * a] + F[3 * i + 1] * Gp[3 * a + 1] + F[3 * i + 2] * Gp[3 * a + 2]
    # w [[c1, c2], [c2, 0]] on (h, f): λ1 u1 u1ᵀ + λ2 u2 u2ᵀ by one Jacobi rotation
    lam1, lam2, cs, sn = w * co[1], 0.0, 1.0, 0.0
    if co[2] != 0.0:
        tau = -co[1] / (2.0 * co[2])
        t = (1.0 if tau >= 0.0 else -1.0) / (fabs(tau) + hypot(1.0, tau))
        cs = 1.0 / sqrt(1.0 + t * t)
        sn = t * cs
        lam1 = w * (co[1] - t * co[2])
        lam2 = w * t * co[2]
    u = _row(rq, lam1, &sc)
    if u != NULL:
        for m in range(D):
            u[m] = sc * (cs * h[m] - sn * f[m])
    u = _row(rq, lam2, &sc)
    if u != NULL:
        for m in range(D):
            u[m] = sc * (sn * h[m] + cs * f[m])
    u = _row(rz, w * co[3], &sc)
    if u != NULL:
        for m in range(D):
            u[m] = sc * h[m]
    for m in range(L.nfam):
        fb = fib + 8 * m
        iso += 2.0 * L.kappa * fb[6]
        u = _row(rq, 4.0 * fb[7] * w, &sc)
        v = _row(rs, 2.0 * L.c * fb[6] * w, &g)
        for a in range(S):
            t = fb[0] * Gp[3 * a] + fb[1] * Gp[3 * a + 1] + fb[2] * Gp[3 * a + 2]
            if v != NULL:
                v[a] = g * t
            if u != NULL:
                for i in range(3):
                    u[3 * a + i] = sc * (L.kappa * f[3 * a + i] + L.c * fb[3 + i] * t)
    for i in range(3):
        u = _row(rs, w * iso, &sc)
        if u != NULL:
            for a in range(S):
                u[a] = sc * Gp[3 * a + i]


cdef void _write_tangent(const double* Cq, const double* Cz, const double* Cs, int S, double* K) nogil:
    """K[(a,i),(b,k)] = Kq[(a,i),(b,k)] + Z[(a,k),(b,i)] + δ_ik Ks[a,b], from the triangles."""
    cdef int a, b, i, k, D = 3 * S
    cdef double ks
    for a in range(S):
        for b in range(S):
            ks = _sym(Cs, S, a, b)
            for i in range(3):
                for k in range(3):
                    K[(3 * a + i) * D + 3 * b + k] = (_sym(Cq, D, 3 * a + i, 3 * b + k)
                                                      + _sym(Cz, D, 3 * a + k, 3 * b + i)
                                                      + (ks if i == k else 0.0))


cdef struct Work:
    double *q
    double *G
    double *h
    double *f
    double *Cq
    double *Cz
    double *Cs
    double *fib
    Rows rq, rz, rs


cdef double* _work(Work* ws, int S, int P, int nfam) except NULL:
    """Per-call scratch: one element's q and G, the rows and the triangles (all in cache)."""
    cdef int D = 3 * S
    cdef size_t n = (3 * S + 3 * S * P + 2 * D + 2 * D * D + S * S + 8 * nfam
                     + D * P * (2 + nfam) + D * P + S * P * (3 + nfam))
    cdef double* mem = <double*> malloc(n * sizeof(double))
    if mem == NULL:
        raise MemoryError()
    ws.q = mem
    ws.G = ws.q + 3 * S
    ws.h = ws.G + 3 * S * P
    ws.f = ws.h + D
    ws.Cq = ws.f + D
    ws.Cz = ws.Cq + D * D
    ws.Cs = ws.Cz + D * D
    ws.fib = ws.Cs + S * S
    ws.rq = Rows(ws.fib + 8 * nfam, D, P * (2 + nfam), 0, 0)
    ws.rz = Rows(ws.rq.buf + D * P * (2 + nfam), D, P, 0, 0)
    ws.rs = Rows(ws.rz.buf + D * P, S, P * (3 + nfam), 0, 0)
    return mem


cdef void _element(const Law* L, Work* ws, const double[:, :, :] q, const double[:, :, :, :] G,
                   const double[:, :] w, const double[:, :, :, :] a0, int e, double* fe,
                   double* Jmin, double* Ke) nogil:
    """Force (and tangent if Ke) of element e; Jmin its smallest J."""
    cdef int S = G.shape[2], P = G.shape[1], D = 3 * S, p, a, i, j, m
    cdef double F[9]
    cdef double H[9]
    cdef double Pk[9]
    cdef double co[5]
    cdef double J, wp
    cdef double* Gp
    cdef double* fb
    for a in range(S):
        for i in range(3):
            ws.q[3 * a + i] = q[e, a, i]
            for p in range(P):
                ws.G[(p * S + a) * 3 + i] = G[e, p, a, i]
    memset(fe, 0, D * sizeof(double))
    Jmin[0] = 0.0
    for p in range(P):
        Gp = ws.G + p * S * 3
        memset(F, 0, 9 * sizeof(double))
        for a in range(S):
            for i in range(3):
                for j in range(3):
                    F[3 * i + j] += ws.q[3 * a + i] * Gp[3 * a + j]
        J = _matrix(L, F, H, Pk, co)
        Jmin[0] = J if p == 0 or J < Jmin[0] or J != J else Jmin[0]
        for m in range(L.nfam):
            fb = ws.fib + 8 * m
            for i in range(3):
                fb[i] = a0[m, e, p, i]
            _fibre(L, F, fb, co[4], Pk, fb + 3, fb + 6)
        wp = w[e, p]
        for a in range(S):
            for i in range(3):
                fe[3 * a + i] += wp * (Pk[3 * i] * Gp[3 * a] + Pk[3 * i + 1] * Gp[3 * a + 1]
                                       + Pk[3 * i + 2] * Gp[3 * a + 2])
        if Ke != NULL:
            _tangent_rows(L, Gp, S, wp, F, H, co, ws.fib, &ws.rq, &ws.rz, &ws.rs, ws.h, ws.f)
    if Ke != NULL:
        _syrk(&ws.rq, ws.Cq)
        _syrk(&ws.rz, ws.Cz)
        _syrk(&ws.rs, ws.Cs)
        _write_tangent(ws.Cq, ws.Cz, ws.Cs, S, Ke)


def evaluate(qe, G, w, tuple law, a0=None, bint tangent=True):
    """(f (E, 3S), K (E, 3S, 3S) or None, min J (E,)) of qe (E, S, 3), G (E, P, S, 3), w (E, P)
    for law = (μ, K, k1, k2, κ, e_rounding) and a0 (families, E, P, 3) or None (neo-Hookean)."""
    cdef const double[:, :, :] q_v = qe
    cdef const double[:, :, :, :] G_v = G
    cdef const double[:, :] w_v = w
    cdef const double[:, :, :, :] a_v = np.zeros((0, 1, 1, 3)) if a0 is None else a0
    cdef int E = G_v.shape[0], P = G_v.shape[1], S = G_v.shape[2], D = 3 * S, e
    cdef Law L
    L.mu, L.K, L.k1, L.k2, L.kappa, L.e_round = law[0], law[1], law[2], law[3], law[4], law[5]
    L.c = 1.0 - 3.0 * L.kappa
    L.nfam = a_v.shape[0]
    if q_v.shape[0] != E or q_v.shape[1] != S or w_v.shape[0] != E or w_v.shape[1] != P \
            or (L.nfam and (a_v.shape[1] != E or a_v.shape[2] != P)):
        raise ValueError("element_kernels.evaluate: inconsistent shapes")
    f = np.empty((E, D))
    Jmin = np.empty(E)
    K = np.empty((E, D, D)) if tangent else None
    cdef double[:, ::1] f_v = f
    cdef double[::1] J_v = Jmin
    cdef double[:, :, ::1] K_v = K if tangent else np.empty((1, 1, 1))
    cdef Work ws
    cdef double* mem = _work(&ws, S, P, L.nfam)
    try:
        with nogil:
            for e in range(E):
                _element(&L, &ws, q_v, G_v, w_v, a_v, e, &f_v[e, 0], &J_v[e],
                         &K_v[e, 0, 0] if tangent else NULL)
    finally:
        free(mem)
    return f, K, Jmin
