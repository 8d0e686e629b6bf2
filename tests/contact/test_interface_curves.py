"""contact/surface.py's InterfaceCurves (issue 40): every interface's S + shift, S' and S'' in one
pass are bitwise each curve's own evaluation, forward and reversed, for the spline degrees the
sections use, inside the curve and past its ends (where the projection's fade works)."""
import numpy as np
import pytest

from ancf_petsc.contact import surface
from ancf_petsc.contact.surface import InterfaceCurves
from ancf_petsc.physics.spline import SplineCurve


def _curves(rng):
    out = []
    for degree, reverse in ((3, False), (3, True), (2, True), (1, False), (5, True)):
        pts = np.cumsum(rng.standard_normal((9, 2)), axis=0)
        c = SplineCurve(pts, degree=degree)
        out.append(c.reversed() if reverse else c)
    return out


@pytest.mark.parametrize("per_curve", [True, False])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_one_pass_equals_each_curve(seed, per_curve, monkeypatch):
    """Per curve by scipy's compiled routine (few curves) or all at once (``SplineSet``)."""
    if not per_curve:
        monkeypatch.setattr(surface, "COMPILED_CURVES_MAX", 0)
    rng = np.random.default_rng(seed)
    curves = _curves(rng)
    shifts = [rng.standard_normal(2) for _ in curves]
    which = rng.integers(0, len(curves), 300)
    T = np.array([c.t_end for c in curves])[which]
    t = rng.uniform(-0.3, 1.3, 300) * T
    ic = InterfaceCurves(curves, shifts)
    assert ic.per_curve == per_curve
    S, S1, S2 = ic(which, t)
    for k, c in enumerate(curves):
        sel = which == k
        assert np.array_equal(S[sel], c(t[sel]) + shifts[k])
        assert np.array_equal(S1[sel], c(t[sel], 1))
        assert np.array_equal(S2[sel], c(t[sel], 2) if c.degree >= 2 else np.zeros((sel.sum(), 2)))
