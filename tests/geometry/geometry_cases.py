"""Synthetic cross-sections with known answers for the geometry-input tests (no downloads).

* :func:`strip_tendon` — an elliptic tendon cut by two curved borders into three subtendons
  left | middle | right (left and right do not touch: no triple point), with the exact outline of
  each region and :func:`trace`, which retraces an outline the way a person does: its own start
  point and spacing, white noise plus a slow drift of the border (so two traces of one border
  differ by tens of micrometres and overlap in places).
* label images of discs, ellipses and half-discs (:func:`disc_mask` ...).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

A_MM, B_MM = 4.0, 2.5                          # ellipse semi-axes [mm]
BORDERS = ((-1.3, 0.0), (1.2, 1.0))            # (centre y, phase) of the two borders


def border_y(k: int, z):
    c, ph = BORDERS[k]
    return c + 0.25 * np.sin(1.3 * np.asarray(z) + ph)


def _hits(k: int) -> tuple[float, float]:
    """z of the border's bottom and top intersections with the ellipse."""
    f = lambda z: (border_y(k, z) / A_MM) ** 2 + (z / B_MM) ** 2 - 1.0
    return brentq(f, -B_MM, 0.0), brentq(f, 0.0, B_MM)


def _arc(th0: float, th1: float, n: int) -> np.ndarray:
    th = np.linspace(th0, th1, n)
    return np.column_stack([A_MM * np.cos(th), B_MM * np.sin(th)])


def _angle(y, z) -> float:
    return float(np.arctan2(z / B_MM, y / A_MM))


def _border(k: int, z0: float, z1: float, n: int) -> np.ndarray:
    z = np.linspace(z0, z1, n)
    return np.column_stack([border_y(k, z), z])


def strip_tendon(n: int = 4000) -> dict[str, np.ndarray]:
    """Exact counter-clockwise outlines [mm] of left, middle, right (closed, first point not repeated)."""
    (b0, t0), (b1, t1) = _hits(0), _hits(1)
    th_b0, th_t0 = _angle(border_y(0, b0), b0), _angle(border_y(0, t0), t0)
    th_b1, th_t1 = _angle(border_y(1, b1), b1), _angle(border_y(1, t1), t1)
    left = np.vstack([_arc(th_t0, th_b0 + 2 * np.pi, n)[:-1], _border(0, b0, t0, n)[:-1]])
    middle = np.vstack([_border(0, t0, b0, n)[:-1], _arc(th_b0 + 2 * np.pi, th_b1 + 2 * np.pi, n)[:-1],
                        _border(1, b1, t1, n)[:-1], _arc(th_t1, th_t0, n)[:-1]])
    right = np.vstack([_arc(th_b1, th_t1, n)[:-1], _border(1, t1, b1, n)[:-1]])
    return {"left": left, "middle": middle, "right": right}


def border_points(k: int, n: int = 4000) -> np.ndarray:
    """The exact border k between the ellipse intersections [mm]."""
    b, t = _hits(k)
    return _border(k, b, t, n)


def area(P: np.ndarray) -> float:
    y, z = P[:, 0], P[:, 1]
    return 0.5 * float(np.sum(y * np.roll(z, -1) - np.roll(y, -1) * z))


def centroid(P: np.ndarray) -> np.ndarray:
    y, z = P[:, 0], P[:, 1]
    y1, z1 = np.roll(y, -1), np.roll(z, -1)
    cr = y * z1 - y1 * z
    return np.array([np.sum((y + y1) * cr), np.sum((z + z1) * cr)]) / (3.0 * cr.sum())


def trace(P: np.ndarray, rng: np.random.Generator, spacing: float = 0.1, noise: float = 0.004,
          drift: float = 0.012) -> np.ndarray:
    """A hand tracing of the closed outline P [mm]: random start, spacing ±20 %, normal offsets of
    white noise (``noise``) plus a smooth drift of amplitude ``drift`` (three random sinusoids)."""
    Q = np.vstack([P, P[:1]])
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(Q, axis=0), axis=1))]
    L = s[-1]
    steps = spacing * rng.uniform(0.8, 1.2, size=int(2 * L / spacing))
    t = (rng.uniform(0, L) + np.cumsum(steps)[np.cumsum(steps) < L]) % L
    pts = np.column_stack([np.interp(t, s, Q[:, 0]), np.interp(t, s, Q[:, 1])])
    tang = np.column_stack([np.interp(t + 1e-3, s, Q[:, 0], period=L), np.interp(t + 1e-3, s, Q[:, 1], period=L)]) - \
        np.column_stack([np.interp(t - 1e-3, s, Q[:, 0], period=L), np.interp(t - 1e-3, s, Q[:, 1], period=L)])
    tang /= np.linalg.norm(tang, axis=1)[:, None]
    normal = np.column_stack([tang[:, 1], -tang[:, 0]])
    k = rng.integers(2, 6, size=3)
    ph = rng.uniform(0, 2 * np.pi, size=3)
    slow = drift * np.mean([np.sin(2 * np.pi * kk * t / L + p) for kk, p in zip(k, ph)], axis=0) * np.sqrt(2)
    return pts + normal * (slow + noise * rng.standard_normal(len(t)))[:, None]


# ------------------------------------------------------------------------------ label images
def disc_mask(shape, centre_px, radius_px, label=1, out=None) -> np.ndarray:
    rows, cols = np.mgrid[0:shape[0], 0:shape[1]]
    m = (cols - centre_px[0]) ** 2 + (rows - centre_px[1]) ** 2 <= radius_px ** 2
    out = np.zeros(shape, dtype=np.int64) if out is None else out
    out[m] = label
    return out


def ellipse_mask(shape, centre_px, semi_px, label, out) -> np.ndarray:
    rows, cols = np.mgrid[0:shape[0], 0:shape[1]]
    m = ((cols - centre_px[0]) / semi_px[0]) ** 2 + ((rows - centre_px[1]) / semi_px[1]) ** 2 <= 1.0
    out[m] = label
    return out
