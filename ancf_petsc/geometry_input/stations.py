"""Sections measured at stations along the tendon → the reference section at any x.

Between two stations x_k < x_{k+1} (s = (x - x_k) / (x_{k+1} - x_k)) every outline is interpolated
in size and shape.  Two ways, chosen once for the whole tendon:

* **shared curves** (``structured``): there are interfaces (curves used by two loops), every loop
  has the same sequence of curves at every station and every interface is the same at every station.  The interfaces
  are kept as they are (one SplineCurve object for the whole length, so contact works unchanged);
  each free curve is blended point by point at equal fractions of its arc length.
* **registered outlines** (otherwise): each outline is resampled at ``RING`` points; the points of
  station k+1 are matched to those of station k by the cyclic shift that best superposes them
  (2D Procrustes, via FFT, refined to a fraction of a sample), the whole section's rotation θ about
  its area centroid is the Procrustes angle over all matched points, and

      P(s) = c(s) + R(s θ) [ (1 - s)(A - c_k) + s R(-θ)(B - c_{k+1}) ],   c(s) = (1 - s) c_k + s c_{k+1}

  (A, B matched points, c area centroids of the whole section).  A section that rotates in place,
  a linear taper (B - c = k (A - c)) and a translation are reproduced exactly; other shape changes
  are blended linearly.

Outside [x_0, x_K] the nearest station's section is used.
"""
from __future__ import annotations

import numpy as np

from ..physics.spline import SplineCurve
from . import polyline as pl
from .build import Station, fit_segment

__all__ = ["SectionField", "match_rings", "RING"]

RING = 512                  # samples per outline for matching and blending
TIE = 1e-4                  # matches within this fraction of the best are equally good


def _complex(P: np.ndarray) -> np.ndarray:
    return P[:, 0] + 1j * P[:, 1]


def _starts(A: np.ndarray, B: np.ndarray) -> list[float]:
    """Cyclic starts (in samples, refined by a parabola through each peak and its neighbours) of
    B's matches to A as good as the best, |Σ conj(a_i) b_{i+j}| (centred points), the smallest
    turn first: one for most outlines, two for an ellipse, many for a circle."""
    n = len(A)
    a = _complex(A - A.mean(axis=0))
    b = _complex(B - B.mean(axis=0))
    C = np.fft.ifft(np.conj(np.fft.fft(a)) * np.fft.fft(b))     # ∝ Σ_i conj(a_i) b_{i+j}
    mag = np.abs(C)
    peaks = np.flatnonzero((mag >= np.roll(mag, 1)) & (mag >= np.roll(mag, -1)))
    good = peaks[mag[peaks] >= (1.0 - TIE) * mag.max()]
    good = good[np.argsort(np.abs(np.angle(C[good])), kind="stable")]
    out = []
    for j in good:
        y0, y1, y2 = mag[(j - 1) % n], mag[j], mag[(j + 1) % n]
        den = y0 - 2.0 * y1 + y2
        out.append(int(j) + (float(np.clip(0.5 * (y0 - y2) / den, -0.5, 0.5)) if den < 0 else 0.0))
    return out


def _resampled(B: np.ndarray, start: float, n: int) -> np.ndarray:
    """B re-sampled at n points of equal arc length from arc-length position start / n."""
    Q = np.vstack([B, B[:1]])
    s = pl.arclength(Q)
    t = (s[-1] * ((np.arange(n) + start) / n)) % s[-1]
    return np.column_stack([np.interp(t, s, Q[:, 0]), np.interp(t, s, Q[:, 1])])


def match_rings(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """B resampled (``len(A)`` points, same orientation) so that B[i] corresponds to A[i]: the
    cyclic start that maximises |Σ conj(a_i) b_{i+j}| (centred points); of equally good starts
    (symmetric shapes), the smallest turn.  Both are closed counter-clockwise polylines sampled at
    equal arc length."""
    return _resampled(B, _starts(A, B)[0], len(A))


def _whole_section_picks(terms: dict[str, list[complex]]) -> dict[str, int]:
    """Per outline, which of its equally good matches (``terms``: each one's Σ conj(a_i - c_k)
    (b_i - c_{k+1}) about the whole section's centroids) superposes the whole section best: the
    largest |Σ over outlines| (coordinate ascent from the smallest turns).  An ellipse matched on
    its own by its smallest turn (-80 deg) in a section turning by +100 deg was blended with its
    points reversed and shrank to nothing half-way."""
    pick = {n: 0 for n in terms}
    for _ in range(len(terms)):
        changed = False
        for n, t in terms.items():
            if len(t) < 2:
                continue
            rest = sum(terms[m][pick[m]] for m in terms if m != n)
            val = np.abs(rest + np.array(t))
            best = int(np.argmax(val))
            if val[best] > val[pick[n]] * (1.0 + 1e-9):
                pick[n], changed = best, True
        if not changed:
            break
    return pick


def _same_curve(base, cv: SplineCurve, f: bool, atol: float) -> tuple[SplineCurve, bool]:
    """(b, f) for the curve b of ``base`` equal to cv, (b, not f) for one equal to cv reversed (a
    station listing the two neighbours of an interface in the other order), else (cv, f)."""
    for b in base:
        if b.points.shape != cv.points.shape or b.degree != cv.degree:
            continue
        for flip, P in ((False, cv.points), (True, cv.points[::-1])):
            if np.allclose(b.points, P, rtol=0, atol=atol):
                return b, f != flip
    return cv, f


class SectionField:
    """Reference sections along x from stations (see the module docstring)."""

    def __init__(self, stations: list[tuple[float, Station]], fit_tolerance: float,
                 spline_degree: int) -> None:
        self.xs = np.array([x for x, _ in stations], dtype=float)
        self.stations = [st for _, st in stations]
        self.names = list(self.stations[0].loops)
        self.fit_tolerance = fit_tolerance
        self.degree = spline_degree
        self._why_not = ""                  # why the stations do not share their curves
        self.rings: list = []               # resampled outlines per station (``_register``), ...
        self.centres: list = []             # ... their area centroids ...
        self.theta: list = []               # ... and the rotation between neighbouring stations
        self.structured = self._share_equal_curves()
        self.reason = "" if self.structured else self._why_not
        if not self.structured:
            self._register()
        self._cache: dict = {}

    # ------------------------------------------------------------------ shared-curve mode
    def _share_equal_curves(self) -> bool:
        """Replace curves equal to station 0's by station 0's objects; True if every loop then has
        the same structure at every station with identical interfaces."""
        first = self.stations[0]
        base = {id(cv): cv for loop in first.loops.values() for cv, _ in loop}.values()
        size = max(np.ptp(first.polyline(n), axis=0).max() for n in self.names)
        self._why_not = ""
        for k, st in enumerate(self.stations[1:], start=1):
            for name in self.names:
                new = []
                for cv, f in st.loops[name]:
                    new.append(_same_curve(base, cv, f, 1e-12 * size))
                st.loops[name] = new
        users: dict[int, set] = {}
        for st in self.stations:
            for name, loop in st.loops.items():
                for cv, _ in loop:
                    users.setdefault(id(cv), set()).add(name)
        if not any(len(v) > 1 for v in users.values()):
            self._why_not = "no interfaces"
            return False
        for name in self.names:
            loops = [st.loops[name] for st in self.stations]
            if len({len(lp) for lp in loops}) != 1:
                self._why_not = f"outline {name} has {[len(lp) for lp in loops]} curves at the stations"
                return False
            for k in range(len(loops[0])):
                objs = [lp[k][0] for lp in loops]
                shared = [len(users[id(o)]) > 1 for o in objs]
                if any(shared) and not all(o is objs[0] for o in objs):
                    where = next(i for i, o in enumerate(objs) if o is not objs[0])
                    cname = next(o.name for o in objs if len(users[id(o)]) > 1)
                    self._why_not = (f"interface {cname.lstrip('-')} differs between the stations at "
                                     f"x = {self.xs[0]:g} m and x = {self.xs[where]:g} m")
                    return False
        return True

    # ------------------------------------------------------------------ registered mode
    def _register(self) -> None:
        """Matched rings of every outline at every station and the rotation between stations."""
        self.rings = [{n: pl.resample(pl.canonical_start(st.polyline(n)), RING) for n in self.names}
                      for st in self.stations]
        self.centres, self.theta = [], []
        for st, rings in zip(self.stations, self.rings):
            areas = np.array([pl.signed_area(rings[n]) for n in self.names])
            cents = np.array([pl.centroid(rings[n]) for n in self.names])
            self.centres.append(areas @ cents / areas.sum())
        for k in range(len(self.stations) - 1):
            A, B = self.rings[k], self.rings[k + 1]          # station k is already matched to k - 1
            ca, cb = self.centres[k], self.centres[k + 1]
            options = {n: [_resampled(B[n], j, RING) for j in _starts(A[n], B[n])] for n in self.names}
            terms = {n: [complex(np.sum(np.conj(_complex(A[n] - ca)) * _complex(Bn - cb))) for Bn in opts]
                     for n, opts in options.items()}
            pick = _whole_section_picks(terms)
            for n in self.names:
                B[n] = options[n][pick[n]]
            self.theta.append(float(np.angle(sum(terms[n][pick[n]] for n in self.names))))

    def _segment(self, x: float) -> tuple[int, float]:
        xs = self.xs
        if x <= xs[0]:
            return 0, 0.0
        if x >= xs[-1]:
            return len(xs) - 2, 1.0
        k = int(np.searchsorted(xs, x, side="right") - 1)
        return k, float((x - xs[k]) / (xs[k + 1] - xs[k]))

    def ring_at(self, name: str, x: float) -> np.ndarray:
        """Closed polyline of outline ``name`` at x (``RING`` points in registered mode; in
        shared-curve mode the loop's curves sampled 16 segments per piece)."""
        if self.structured:
            loop = self.loop_at(name, x)
            return np.vstack([(cv.reversed() if f else cv).sample(16)[:-1] for cv, f in loop])
        k, s = self._segment(x)
        A, B = self.rings[k][name], self.rings[k + 1][name]
        ca, cb, th = self.centres[k], self.centres[k + 1], self.theta[k]
        R = lambda t: np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
        inner = (1.0 - s) * (A - ca) + s * (B - cb) @ R(-th).T
        return (1.0 - s) * ca + s * cb + inner @ R(s * th).T

    def loop_at(self, name: str, x: float) -> list[tuple[SplineCurve, bool]]:
        """The loop of outline ``name`` at x: station loops at the stations, interpolated between."""
        k, s = self._segment(x)
        if s == 0.0 or s == 1.0:
            return self.stations[k + (s == 1.0)].loops[name]
        key = (name, round(x, 15))
        if key in self._cache:
            return self._cache[key]
        if self.structured:
            out = []
            for (ca, fa), (cb, fb) in zip(self.stations[k].loops[name], self.stations[k + 1].loops[name]):
                if ca is cb:
                    out.append((ca, fa))
                    continue
                n = 8 * max(len(ca.points), len(cb.points))
                Pa = pl.resample((ca.reversed() if fa else ca).sample(16), n, closed=False)
                Pb = pl.resample((cb.reversed() if fb else cb).sample(16), n, closed=False)
                blend = (1.0 - s) * Pa + s * Pb
                name_k = ca.name.lstrip("-")
                out += [(c, False) for c in fit_segment(blend, False, self.degree, self.fit_tolerance,
                                                         name_k, np.inf)]
        else:
            ring = pl.canonical_start(self.ring_at(name, x))
            Q = np.vstack([ring, ring[:1]])
            out = [(c, False) for c in fit_segment(Q, True, self.degree, self.fit_tolerance, name,
                                                    pl.perimeter(ring) / 12.0)]
        self._cache[key] = out
        return out
