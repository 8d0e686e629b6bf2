"""contact/descent_native.pyx (issue 40): the compiled interface curves, B's shape functions on
the surface and the closest-point step equal their numpy originals to the last bit (the numpy
code is the reference and the fallback), and the module is compiled wherever Cython is."""

import numpy as np
import pytest

from ancf_petsc import native
from ancf_petsc.contact import surface
from ancf_petsc.contact.descent import newton_step
from ancf_petsc.contact.surface import InterfaceCurves, SurfaceKernels, shape_on_curve
from ancf_petsc.physics.elements import ELEMENTS
from ancf_petsc.physics.spline import SplineCurve

NAME = "contact.descent_native"
compiled = pytest.mark.skipif(native.load(NAME) is None, reason=native.status(NAME))


def _curves(rng):
    out = []
    for degree, reverse in ((3, False), (3, True), (2, True), (1, False), (5, True)):
        c = SplineCurve(np.cumsum(rng.standard_normal((9, 2)), axis=0), degree=degree)
        out.append(c.reversed() if reverse else c)
    return out


@compiled
@pytest.mark.parametrize("per_curve", [True, False])
@pytest.mark.parametrize("seed", [0, 1])
def test_curves_equal_numpy(seed, per_curve, monkeypatch):
    """S + shift, S', S'' inside and past the curves' ends, forward and reversed, NaN kept."""
    if not per_curve:
        monkeypatch.setattr(surface, "COMPILED_CURVES_MAX", 0)
    rng = np.random.default_rng(seed)
    curves = _curves(rng)
    shifts = [rng.standard_normal(2) for _ in curves]
    which = rng.integers(0, len(curves), 400)
    t = rng.uniform(-0.3, 1.3, 400) * np.array([c.t_end for c in curves])[which]
    t[:5] = [0.0, np.nan, curves[which[2]].t_end, -1e-300, 1e300]
    ic = InterfaceCurves(curves, shifts)
    assert ic._native is not None
    fast = ic(which, t)
    ic._native = None
    for a, b in zip(fast, ic(which, t)):
        np.testing.assert_array_equal(a, b)
        assert a.flags.c_contiguous and a.shape == (400, 2)


def _blocks():
    out = {}
    for e in ELEMENTS.values():
        if SurfaceKernels(e.block).compiled:
            out[e.block.monomials] = e.block
    return list(out.values())


@compiled
@pytest.mark.parametrize("seed", [0, 1])
def test_shapes_equal_shape_on_curve(seed):
    """N, N_ζ, N_ζζ of every block the kernel takes (3363's and the higher orders)."""
    rng = np.random.default_rng(seed)
    blocks = _blocks()
    assert len(blocks) >= 1
    P = 257
    xi = rng.uniform(-1.6, 1.6, P)
    S, S1, S2 = (rng.standard_normal((P, 2)) * s for s in (3e-3, 1.0, 50.0))
    for block in blocks:
        got = SurfaceKernels(block).shapes(xi, S, S1, S2)
        want = shape_on_curve(xi, S, S1, S2, block)
        for a, b in zip(got, want):
            np.testing.assert_array_equal(a, b)
            assert a.strides == b.strides          # the matmuls after it take the same paths


@compiled
@pytest.mark.parametrize("metric", [True, False])
def test_newton_step_equals_numpy(metric):
    """Newton's step, the indefinite points' Gauss–Newton or Levenberg step, the pinned points'
    step in t, and the degenerate points (non-finite steps) as numpy gives them."""
    rng = np.random.default_rng(3)
    P = 500
    Yz = rng.standard_normal((P, 3, 2))
    Yzz = rng.standard_normal((P, 3, 2, 2)) * rng.choice([1e-3, 1.0, 30.0], (P, 1, 1, 1))
    d = rng.standard_normal((P, 3)) * 0.1
    Yz[:3] = 0.0                                  # singular H: inf / nan
    pinned = rng.random(P) < 0.2
    kernels = SurfaceKernels(ELEMENTS["3363"].block)
    assert kernels.compiled
    with np.errstate(all="ignore"):
        got = kernels.step(Yz, Yzz, d, pinned, metric)
        want = newton_step(Yz.copy(), Yzz, d, pinned, metric)
    for a, b in zip(got, want):
        np.testing.assert_array_equal(a, b)


@compiled
@pytest.mark.parametrize("seed", [0, 1])
def test_surface_products_equal_numpy(seed):
    """Y, Y_ζ, Y_ζζ of the surface from the compiled shapes: the compiled BLAS calls give numpy's
    matmuls to the last bit (nodal vectors of widely spread magnitudes)."""
    rng = np.random.default_rng(seed)
    P = 193
    kernels = SurfaceKernels(ELEMENTS["3363"].block)
    xi = rng.uniform(-1.6, 1.6, P)
    S, S1, S2 = (rng.standard_normal((P, 2)) * s for s in (3e-3, 1.0, 50.0))
    NB, NBz, NBzz = kernels.shapes(xi, S, S1, S2)
    qB = rng.standard_normal((P, 18, 3)) * np.exp(3.0 * rng.standard_normal((P, 18, 1)))
    calls = []
    products = kernels._products
    kernels._products = lambda *a: calls.append(1) or products(*a)
    got = kernels.surface(qB, NB, NBz, NBzz)
    assert calls                                   # the compiled path ran
    want = (np.matmul(NB[:, None, :], qB)[:, 0], np.matmul(qB.transpose(0, 2, 1), NBz),
            np.matmul(qB.transpose(0, 2, 1), NBzz.reshape(P, 18, 4)).reshape(P, 3, 2, 2))
    for a, b in zip(got, want):
        np.testing.assert_array_equal(a, b)
        assert a.shape == b.shape
