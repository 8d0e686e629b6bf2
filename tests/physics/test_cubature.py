"""Cubature rules of ancf_petsc.physics.cubature (paper Sec. 2.2, eqs. 9-11)."""
from fractions import Fraction
from math import comb

import numpy as np
import pytest

from ancf_petsc.physics.cubature import (CurvePiece, compress_rule, ellipse_rule, gauss_green_rule,
    gauss_legendre, rectangle_rule)
from ancf_petsc.physics.spline import SplineCurve
from ancf_petsc.physics.section import make_outline

# A non-convex (notched, L-ish) polygon, counter-clockwise, integer vertices scaled by 1/8.
POLY_INT = [(0, 0), (9, -2), (12, 3), (7, 4), (6, 9), (11, 13), (2, 12), (-3, 7), (3, 5)]
POLY_DEN = 8
POLY = np.array(POLY_INT, dtype=float) / POLY_DEN


def exact_polygon_moment(verts_int, den, i, j):
    """Exact int_P y^i z^j dA by Green's theorem, 1/(i+1) * loop integral of y^(i+1) z^j dz,
    each edge y = y0 + s dy, z = z0 + s dz expanded binomially, in rational arithmetic."""
    V = [(Fraction(a, den), Fraction(b, den)) for a, b in verts_int]
    total = Fraction(0)
    for k in range(len(V)):
        (y0, z0), (y1, z1) = V[k], V[(k + 1) % len(V)]
        dy, dz = y1 - y0, z1 - z0
        for a in range(i + 2):
            ca = comb(i + 1, a) * y0 ** (i + 1 - a) * dy ** a
            for b in range(j + 1):
                total += ca * comb(j, b) * z0 ** (j - b) * dz ** b * dz / (a + b + 1)
    return total / (i + 1)


def inside_polygon(P, poly):
    """Exact crossing-number test (independent of the library's helper)."""
    P = np.asarray(P)
    a, b = poly, np.roll(poly, -1, axis=0)
    py, pz = P[:, :1], P[:, 1:]
    straddle = (a[:, 1] > pz) != (b[:, 1] > pz)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, 0] + (pz - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (np.count_nonzero(straddle & (py < x), axis=1) % 2) == 1


def polygon_pieces(poly):
    """Straight edges as degree-1 pieces (independent of SplineCurve)."""
    out = []
    for k in range(len(poly)):
        a, b = poly[k], poly[(k + 1) % len(poly)]
        out.append(CurvePiece(lambda t, a=a, b=b: a + t[:, None] * (b - a),
                              lambda t, a=a, b=b: np.tile(b - a, (t.size, 1)), 0.0, 1.0, 1))
    return out


def check_moments(pts, w, d, verts_int=POLY_INT, den=POLY_DEN, rtol=1e-12):
    R = np.abs(np.array(verts_int, float) / den).max()
    area = float(exact_polygon_moment(verts_int, den, 0, 0))
    for i in range(d + 1):
        for j in range(d + 1 - i):
            exact = float(exact_polygon_moment(verts_int, den, i, j))
            got = float(np.sum(w * pts[:, 0] ** i * pts[:, 1] ** j))
            scale = area * R ** (i + j)
            assert abs(got - exact) <= rtol * scale, (i, j, got, exact)


def test_gauss_legendre():
    x, w = gauss_legendre(5)
    assert x.shape == w.shape == (5,)
    assert np.isclose(w.sum(), 2.0)
    assert np.isclose(np.sum(w * x ** 8), 2.0 / 9.0, rtol=1e-14)
    with pytest.raises(ValueError):
        gauss_legendre(0)


@pytest.mark.parametrize("d", [2, 3, 4, 6, 8, 10])
def test_polygon_raw_gauss_green(d):
    pts, w = gauss_green_rule(polygon_pieces(POLY), d)
    check_moments(pts, w, d)
    # Xi is arbitrary (paper Sec. 2.2): any vertical line gives the same moments.
    pts2, w2 = gauss_green_rule(polygon_pieces(POLY), d, xi_line=-0.7)
    check_moments(pts2, w2, d)


@pytest.mark.parametrize("d", [2, 3, 4, 6, 8, 10])
def test_polygon_compressed(d):
    pts, w = gauss_green_rule(polygon_pieces(POLY), d)
    pc, wc = compress_rule(pts, w, d, lambda P: inside_polygon(P, POLY))
    check_moments(pc, wc, d)
    assert np.all(wc > 0)
    assert inside_polygon(pc, POLY).all()
    assert wc.size <= (d + 1) * (d + 2) // 2


@pytest.mark.parametrize("d", [2, 5, 8])
def test_polygon_via_spline_outline(d):
    """Degree-1 SplineCurves (split into three curves, CW input) through make_outline."""
    closed = np.vstack([POLY, POLY[:1]])[::-1]           # clockwise, closed
    loop = [(SplineCurve(closed[0:4], 1, "a"), False), (SplineCurve(closed[3:7], 1, "b"), False),
            (SplineCurve(closed[6:], 1, "c"), False)]
    raw = make_outline(loop, degree=d, compress=False)
    sec = make_outline(loop, degree=d, compress=True)
    for s in (raw, sec):
        check_moments(s.points + s.centroid, s.weights, d)
    assert np.all(sec.weights > 0) and sec.weights.size <= (d + 1) * (d + 2) // 2
    assert inside_polygon(sec.points + sec.centroid, POLY).all()
    assert not sec.notes


@pytest.mark.parametrize("d", [0, 1, 2, 5, 6, 9])
def test_rectangle_rule_exact(d):
    W, H = 0.3, 1.7
    pts, w = rectangle_rule(W, H, d)
    for i in range(d + 1):
        for j in range(d + 1 - i):
            ey = 0.0 if i % 2 else 2 * (W / 2) ** (i + 1) / (i + 1)
            ez = 0.0 if j % 2 else 2 * (H / 2) ** (j + 1) / (j + 1)
            got = np.sum(w * pts[:, 0] ** i * pts[:, 1] ** j)
            assert abs(got - ey * ez) <= 1e-13 * W * H * max(W, H) ** (i + j)


def _ellipse_moment(a, b, i, j):
    """int y^i z^j over the ellipse (i, j even):
    a^(i+1) b^(j+1) * 2 G((i+1)/2) G((j+1)/2) / ((i+j+2) G((i+j+2)/2)), G = Gamma."""
    from math import gamma
    if i % 2 or j % 2:
        return 0.0
    return (a ** (i + 1) * b ** (j + 1) * 2 * gamma((i + 1) / 2) * gamma((j + 1) / 2)
            / ((i + j + 2) * gamma((i + j + 2) / 2)))


@pytest.mark.parametrize("d", [0, 1, 2, 3, 6, 10])
def test_ellipse_rule_exact(d):
    a, b = 1.3, 0.6
    pts, w = ellipse_rule(a, b, d)
    assert np.all(w > 0)
    assert np.all((pts[:, 0] / a) ** 2 + (pts[:, 1] / b) ** 2 < 1)
    for i in range(d + 1):
        for j in range(d + 1 - i):
            got = np.sum(w * pts[:, 0] ** i * pts[:, 1] ** j)
            exact = _ellipse_moment(a, b, i, j)
            assert abs(got - exact) <= 1e-13 * np.pi * a * b * max(a, b) ** (i + j), (i, j)


def _closed_curve_area_errors(param, exact, counts, degree=3):
    errs = []
    for m in counts:
        th = np.linspace(-np.pi, np.pi, m + 1)
        P = param(th)
        P[-1] = P[0]
        sec = make_outline([(SplineCurve(P, degree, "c"), False)], degree=4, compress=True)
        assert not sec.notes
        errs.append(abs(sec.area - exact) / exact)
    return np.array(errs)


def test_spline_area_convergence():
    """Splines through points on an ellipse / a cardioid converge to the exact area."""
    counts = [8, 16, 32, 64, 128]
    a, b = 2.0, 1.0
    ell = _closed_curve_area_errors(lambda t: np.column_stack([a * np.cos(t), b * np.sin(t)]),
                                    np.pi * a * b, counts)
    c = 1.0     # cardioid r = c (1 + cos th), cusp at th = +-pi (the curve's end points)
    car = _closed_curve_area_errors(
        lambda t: np.column_stack([c * (1 + np.cos(t)) * np.cos(t),
                                   c * (1 + np.cos(t)) * np.sin(t)]), 1.5 * np.pi * c ** 2, counts)
    print("\n  m   ellipse rel.err   cardioid rel.err")
    for m, e1, e2 in zip(counts, ell, car):
        print(f"{m:4d}   {e1:14.3e}   {e2:14.3e}")
    for errs in (ell, car):
        assert np.all(errs[1:] <= errs[:-1] * 1.05)           # (monotone-ish) decrease
        assert errs[-1] < 1e-6
        assert errs[-1] < 1e-3 * errs[0]


@pytest.mark.parametrize("d", [4, 6, 8])
def test_compressed_rule_properties(d):
    """Compressed rule of a curved non-convex outline (cubic spline loop)."""
    th = np.linspace(0, 2 * np.pi, 25)
    r = 1.0 + 0.35 * np.cos(3 * th)
    P = np.column_stack([r * np.cos(th), r * np.sin(th)])
    P[-1] = P[0]
    raw = make_outline([(SplineCurve(P, 3, "star"), False)], degree=d, compress=False)
    sec = make_outline([(SplineCurve(P, 3, "star"), False)], degree=d, compress=True)
    assert not sec.notes
    assert np.all(sec.weights > 0)
    assert sec.weights.size <= (d + 1) * (d + 2) // 2
    assert sec.contains(sec.points).all()
    # every monomial up to degree d agrees with the raw (exact) Gauss-Green rule
    for i in range(d + 1):
        for j in range(d + 1 - i):
            m_raw = np.sum(raw.weights * raw.points[:, 0] ** i * raw.points[:, 1] ** j)
            m_c = np.sum(sec.weights * sec.points[:, 0] ** i * sec.points[:, 1] ** j)
            assert abs(m_raw - m_c) <= 1e-12 * sec.area * 1.4 ** (i + j)
    # the raw rule of this non-convex domain has nodes outside: compression is needed
    assert not sec.contains(raw.points).all() or np.any(raw.weights < 0)
