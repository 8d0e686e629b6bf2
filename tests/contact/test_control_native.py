"""contact/control_native.pyx (issue 40): the compiled fade weights and the descent's step test
and next trial equal their numpy originals to the last bit (the numpy code is the reference and
the fallback), and the module is compiled wherever Cython is."""

import numpy as np
import pytest

from ancf_petsc import native
from ancf_petsc.contact import fade
from ancf_petsc.contact.control import DescentControl
from ancf_petsc.contact.descent import Backtracking

NAME = "contact.control_native"
compiled = pytest.mark.skipif(native.load(NAME) is None, reason=native.status(NAME))


def _places(rng, P=600):
    """Partner places on and past both ends of curves and beams, with edge values and NaN."""
    T = rng.uniform(0.5, 2.0, P)
    xi = rng.uniform(-1.8, 1.8, P)
    t = rng.uniform(-0.7, 1.7, P) * T
    first, last = rng.random(P) < 0.4, rng.random(P) < 0.4
    xi[:6] = [1.0, -1.0, 1.25, -1.5, np.nan, -0.0]
    t[6:12] = [0.0, T[7], -0.25 * T[8], 1.5 * T[9], np.nan, -0.0]
    return xi, t, T, first, last


@compiled
@pytest.mark.parametrize("seed", [0, 1])
def test_end_weight_and_slope_equal_numpy(seed, monkeypatch):
    rng = np.random.default_rng(seed)
    args = _places(rng)
    got = fade.end_weight(*args), fade.end_weight_slope(*args)
    monkeypatch.setenv("ANCF_NATIVE", "0")
    assert fade._compiled(*args) is None
    want = fade.end_weight(*args), fade.end_weight_slope(*args)
    for a, b in zip(got, want):
        np.testing.assert_array_equal(a, b)
    assert np.any((want[0] > 0.0) & (want[0] < 1.0)) and np.any(want[1] != 0.0)   # in the bands


class _Wrapper:
    """The part of a Projector the control uses: B's element range per interface and ``wrap``."""

    def __init__(self):
        from ancf_petsc.contact.projection import Projector
        self._b_first, self._b_last = np.array([0, 5]), np.array([4, 5])     # a one-element beam too
        self._curve_end = np.array([1.0, 2.5])
        self.wrap = Projector.wrap.__get__(self)
        self.wrap_bounds = Projector.wrap_bounds.__get__(self)


def _search_state(rng, P, keep_direction):
    itf = rng.integers(0, 2, P)
    eB = np.where(itf == 0, rng.integers(0, 5, P), 5)
    xi, t = rng.uniform(-1.2, 1.2, P), rng.uniform(-0.3, 1.3, P)
    search = Backtracking(eB, xi, t, np.array([1.0, 2.5])[itf], keep_direction)
    search.phi = rng.uniform(0.0, 1.0, P)
    search.phi[:20] = np.inf
    search.alpha = rng.choice([1.0, 0.5, 0.125], P)
    search.descent = -rng.uniform(0.0, 1.0, P)
    search.slack = rng.uniform(0.0, 1e-3, P)
    search.e_back = rng.integers(-1, 5, P)
    return itf, eB + rng.integers(-1, 2, P) * (itf == 0), xi, t, search


@compiled
@pytest.mark.parametrize("keep_direction", [False, True])
@pytest.mark.parametrize("seed", [0, 1])
def test_assess_and_advance_equal_numpy(seed, keep_direction):
    """Worse and better points, non-finite and tiny steps, ascent directions after the ξ cut,
    steps across elements and beam and curve ends: every array the numpy code leaves."""
    rng = np.random.default_rng(seed)
    P = 400
    d = rng.standard_normal((P, 3)) * rng.choice([1e-6, 0.3, 1.0], (P, 1))
    dz = rng.standard_normal((P, 2)) * rng.choice([1e-13, 0.5, 3.0], (P, 1))
    dz[:4] = [[np.nan, 0.0], [0.0, np.inf], [1e-12, 1e-12], [2.5, -0.1]]
    r = rng.standard_normal((P, 2))
    valid = rng.random(P) < 0.9
    tol_t = np.full(P, 1e-11)
    out = []
    for compiled_path in (True, False):
        control = DescentControl(_Wrapper(), compiled_path)
        assert control.compiled == compiled_path
        itf, eB, xi, t, search = _search_state(np.random.default_rng(seed + 10), P, keep_direction)
        dz_, r_, stuck = dz.copy(), r.copy(), np.zeros(P, dtype=bool)
        worse, ok = control.assess(search, d, valid, dz_, r_, 1e-11, tol_t, stuck)
        eB, xi, t, weight, crossed = control.advance(search, itf, eB, xi, t, d, dz_, r_, worse)
        out.append([worse, ok, stuck, dz_, r_, eB, xi, t, weight, crossed]
                   + [getattr(search, k) for k in ("e", "xi", "t", "e_back", "phi", "phi_now", "slack",
                                                  "descent", "dz", "alpha")])
    for a, b in zip(*out):
        np.testing.assert_array_equal(a, b)
    worse, ok, stuck, crossed = out[1][0], out[1][1], out[1][2], out[1][9]
    assert worse.any() and (~worse).any() and ok.any() and stuck.sum() == 2 and crossed.any()
