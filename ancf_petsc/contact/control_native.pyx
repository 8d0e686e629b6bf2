# distutils: extra_compile_args = -ffp-contract=off
# cython: boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled control of the closest-point descent (contact/projection.py ``Projector.descend``):
the weights of partner places past B's ends (contact/fade.py ``end_weight``,
``end_weight_slope``), the test of a step (``assess``: descent.Backtracking.worse, the stuck
points, convergence) and the next trial (``advance``: Backtracking.accept and trial, then
``Projector.wrap``): one pass over the points each instead of ~20-40 numpy calls.

Every value is formed by the same floating-point operations in the same order as the numpy
original (no fused multiply-adds: ``-ffp-contract=off``; NaN kept as numpy's maximum/minimum
keep it), so the results are bitwise equal to it (tests/contact/test_control_native.py)."""
from libc.math cimport fabs, floor, isfinite, sqrt
import numpy as np

cimport numpy as cnp

cnp.import_array()


cdef inline double _max(double a, double b) nogil:
    """numpy.maximum: a NaN first argument propagates."""
    return a if (a >= b or a != a) else b


cdef inline double _min(double a, double b) nogil:
    """numpy.minimum: a NaN first argument propagates."""
    return a if (a <= b or a != a) else b


cdef inline double _fade(double u) nogil:
    cdef double v = _min(_max(u, 0.0), 1.0)
    return 1.0 - v * v * v * (10.0 - 15.0 * v + 6.0 * v * v)


cdef inline double _fade_slope(double u) nogil:
    if u > 0.0 and u < 1.0:
        return -30.0 * u * u * ((1.0 - u) * (1.0 - u))
    return 0.0


cdef inline void _arguments(double xi, double t, double T, bint first, bint last, double overhang,
                            double fade_end, double end_fade, double* u_t, double* u_x, bint* below,
                            double* raw) nogil:
    """fade._fade_arguments of one point."""
    below[0] = -t > t - T
    u_t[0] = ((-t if below[0] else t - T) / T - overhang) / (fade_end - overhang)
    raw[0] = (xi - 1.0 if last else 0.0) + (-1.0 - xi if first else 0.0)
    u_x[0] = _max(raw[0], 0.0) / (2.0 * end_fade)


def end_weight(const double[::1] xi, const double[::1] t, const double[::1] T,
               const cnp.uint8_t[::1] first, const cnp.uint8_t[::1] last,
               double overhang, double fade_end, double end_fade):
    """``fade.end_weight`` (P,) with the fade's constants CURVE_OVERHANG, CURVE_FADE_END, END_FADE."""
    cdef Py_ssize_t p, P = xi.shape[0]
    out = np.empty(P)
    cdef double[::1] w = out
    cdef double u_t, u_x, raw
    cdef bint below
    with nogil:
        for p in range(P):
            _arguments(xi[p], t[p], T[p], first[p], last[p], overhang, fade_end, end_fade,
                       &u_t, &u_x, &below, &raw)
            w[p] = _fade(u_t) * _fade(u_x)
    return out


def end_weight_slope(const double[::1] xi, const double[::1] t, const double[::1] T,
                     const cnp.uint8_t[::1] first, const cnp.uint8_t[::1] last,
                     double overhang, double fade_end, double end_fade):
    """``fade.end_weight_slope`` (P, 2) with the fade's constants."""
    cdef Py_ssize_t p, P = xi.shape[0]
    out = np.empty((P, 2))
    cdef double[:, ::1] w = out
    cdef double u_t, u_x, raw, sx
    cdef bint below
    with nogil:
        for p in range(P):
            _arguments(xi[p], t[p], T[p], first[p], last[p], overhang, fade_end, end_fade,
                       &u_t, &u_x, &below, &raw)
            sx = (1.0 if last[p] else 0.0) - (1.0 if first[p] else 0.0)
            w[p, 1] = _fade_slope(u_t) * (-1.0 if below else 1.0) / (T[p] * (fade_end - overhang)) * _fade(u_x)
            w[p, 0] = _fade(u_t) * _fade_slope(u_x) * sx * (1.0 if raw > 0.0 else 0.0) / (2.0 * end_fade)
    return out


def assess(const double[::1] phi, const double[::1] phi0, const double[::1] alpha,
           const double[::1] descent, const double[::1] slack, double[:, ::1] dz, double[:, ::1] r,
           const cnp.uint8_t[::1] valid, const double[::1] tol_t, double tol, double armijo,
           cnp.uint8_t[::1] stuck_ever, cnp.uint8_t[::1] worse, cnp.uint8_t[::1] ok):
    """One test of the descent's points: ``worse`` (φ above the Armijo line of the step's start
    φ0, Backtracking.worse), a non-finite step zeroed with its φ_ζ and recorded in ``stuck_ever``,
    ``ok`` (converged or invalid); returns whether every point is ok."""
    cdef Py_ssize_t p, P = phi.shape[0]
    cdef bint all_ok = True, bad
    with nogil:
        for p in range(P):
            worse[p] = valid[p] and phi[p] > phi0[p] + armijo * alpha[p] * descent[p] + slack[p]
            bad = not (isfinite(dz[p, 0]) and isfinite(dz[p, 1]))
            if bad:
                dz[p, 0] = 0.0
                dz[p, 1] = 0.0
                r[p, 0] = 0.0
                r[p, 1] = 0.0
                stuck_ever[p] = 1
            ok[p] = (fabs(dz[p, 0]) < tol and fabs(dz[p, 1]) < tol_t[p] and not worse[p]) or not valid[p]
            all_ok = all_ok and ok[p]
    return all_ok


def advance(long[::1] eB, double[::1] xiB, double[::1] tB, const double[:, ::1] d,
            const double[:, ::1] dz, const double[:, ::1] r, const cnp.uint8_t[::1] worse,
            long[::1] e, double[::1] xi, double[::1] t, long[::1] e_back, double[::1] phi,
            const double[::1] phi_now, double[::1] slack, double[::1] descent, double[:, ::1] step,
            double[::1] alpha, const double[::1] length, bint keep_direction,
            const long[::1] b_first, const long[::1] b_last, const double[::1] T, double rounding,
            double overhang, double fade_end, double end_fade, cnp.uint8_t[::1] crossed,
            double[::1] weight):
    """``crossed`` (worse and on another element than the step's start), then the points not
    worse start a full step from where they are and the others halve theirs (Backtracking.accept
    with its state e … alpha, length), and (eB, ξB, tB) become the trials (Backtracking.trial)
    wrapped onto B's elements ``b_first`` … ``b_last`` of curve length T (Projector.wrap) with
    their weights; returns whether any point crossed."""
    cdef Py_ssize_t p, P = eB.shape[0]
    cdef bint any_crossed = False, ascent
    cdef double s0, s1, m, x, tt, lo_x = -1.0 - 2.0 * end_fade, hi_x = 1.0 + 2.0 * end_fade
    cdef double u_t, u_x, raw
    cdef bint below
    cdef long shift, e_new
    with nogil:
        for p in range(P):
            crossed[p] = worse[p] and eB[p] != e[p]
            any_crossed = any_crossed or crossed[p]
            if not worse[p]:
                e_back[p] = e[p]
                e[p], xi[p], t[p] = eB[p], xiB[p], tB[p]
                phi[p] = phi_now[p]
                slack[p] = rounding * length[p] * (sqrt(d[p, 0] * d[p, 0] + d[p, 1] * d[p, 1] + d[p, 2] * d[p, 2])
                                                   + rounding * length[p])
                s0 = _min(_max(dz[p, 0], -1.0), 1.0)
                s1 = dz[p, 1]
                ascent = (r[p, 0] * s0 + r[p, 1] * s1 >= 0.0) and keep_direction
                if ascent:
                    m = _max(fabs(dz[p, 0]), 1.0)
                    s0 = dz[p, 0] / m
                    s1 = dz[p, 1] / m
                step[p, 0], step[p, 1] = s0, s1
                descent[p] = _min(r[p, 0] * s0 + r[p, 1] * s1, 0.0)
                alpha[p] = 1.0
            else:
                alpha[p] = alpha[p] * 0.5
            # the trial, wrapped
            x = xi[p] + alpha[p] * step[p, 0]
            tt = t[p] + alpha[p] * step[p, 1]
            shift = 0 if x == 1.0 else <long>floor((x + 1.0) / 2.0)
            e_new = e[p] + shift
            e_new = b_first[p] if e_new < b_first[p] else e_new
            e_new = b_last[p] if e_new > b_last[p] else e_new
            x = _min(_max(x - 2.0 * <double>(e_new - e[p]), lo_x), hi_x)
            tt = _min(_max(tt, -fade_end * T[p]), (1.0 + fade_end) * T[p])
            eB[p], xiB[p], tB[p] = e_new, x, tt
            _arguments(x, tt, T[p], e_new == b_first[p], e_new == b_last[p], overhang, fade_end,
                       end_fade, &u_t, &u_x, &below, &raw)
            weight[p] = _fade(u_t) * _fade(u_x)
    return any_crossed
