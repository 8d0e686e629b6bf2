# distutils: extra_compile_args = -ffp-contract=off
# cython: boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled weights of partner places past B's ends (contact/fade.py ``end_weight`` and
``end_weight_slope``): one pass over the points instead of ~30 numpy calls each.

Every value is formed by the same floating-point operations in the same order as the numpy
original (no fused multiply-adds: ``-ffp-contract=off``; NaN kept as numpy's maximum/minimum
keep it), so the results are bitwise equal to it (tests/contact/test_fade_native.py)."""
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
