"""Geometry preview without solving (``ancf-solve --check``): every beam's cross-section, the
borders two outlines share, the contact interfaces and the twist axis, drawn in the tendon frame
(y, z at x = 0, mm), with each beam's area and centroid and each border's length as text.

Sections that vary along x are drawn at x = 0, L/2 and L; a pretwisted model also at x = L,
turned by ψ about the twist axis (both as thin dashed / dotted lines)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..config.specs import ModelSpec
from ..model.beams import Beam, Model
from ..model.build import build_model
from ..model.contact_setup import contact_for
from ..physics.geometry import place
from .figures import save_figure
from .surface_mesh import MM

__all__ = ["Border", "check_geometry", "check_lines", "draw_geometry", "find_borders"]


@dataclass
class Border:
    """A section curve two outlines share (their merged border), or one side of a contact pair."""
    name: str
    beams: tuple[str, ...]
    points: np.ndarray          # (k, 2) tendon frame at x = 0 [m]
    length: float               # [m]
    contact: str | None = None  # the contact interface on it, if any


def _curve_points(curve, beam: Beam) -> np.ndarray:
    pts = curve.sample(32)
    return pts + beam.section.shape_params.get("offset", np.zeros(2))


def _length(pts: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(pts, axis=0), axis=1)))


def find_borders(model: Model, interfaces: list | None = None) -> list[Border]:
    """Every curve shared by two beams' outlines, marked with the contact interface on it; a
    contact pair of two different curves (non-matching) gives one border per side."""
    owners: dict[int, list] = {}
    for beam in model.beams:
        for curve, _ in beam.section.loop or []:
            owners.setdefault(id(curve), [curve, beam, []])[2].append(beam.name)
    on = {}
    for itf in interfaces or []:
        on[id(itf.curve)] = itf.name
        if itf.curve_b is not itf.curve:
            on[id(itf.curve_b)] = itf.name
            owners.setdefault(id(itf.curve_b), [itf.curve_b, itf.b, [itf.b.name]])
            owners.setdefault(id(itf.curve), [itf.curve, itf.a, [itf.a.name]])
    out = []
    for key, (curve, beam, names) in owners.items():
        if len(names) < 2 and key not in on:
            continue
        pts = _curve_points(curve, beam)
        out.append(Border(curve.name or "border", tuple(names), pts, _length(pts), on.get(key)))
    return out


def check_lines(model: Model, borders: list[Border]) -> list[str]:
    """Per beam: area and centroid (SI and mm); per border: its beams, length and contact."""
    lines = []
    for b in model.beams:
        s, c = b.section, _clean(b.section.centroid)
        lines.append(f"beam {b.name}: area {s.area:.6e} m^2 ({s.area * 1e6:.4f} mm^2), centroid "
                     f"({c[0]:.6e}, {c[1]:.6e}) m = ({c[0] * MM:.4f}, {c[1] * MM:.4f}) mm"
                     + (" at x = 0" if b.ring_at is not None else ""))
    for br in borders:
        lines.append(f"border {br.name} ({'|'.join(br.beams)}): length {br.length:.6e} m "
                     f"({br.length * MM:.4f} mm), " + ("contact interface" if br.contact else "not in contact"))
    if not borders:
        lines.append("borders: no two outlines share a curve")
    return lines


def _clean(v) -> np.ndarray:
    """Round-off zeros (1e-20 m) shown as 0."""
    v = np.asarray(v, dtype=float)
    return np.where(np.abs(v) < 1e-15, 0.0, v)


def _stations(model: Model, beam: Beam) -> list[float]:
    L = model.spec.length
    if beam.ring_at is not None:
        return [0.0, 0.5 * L, L]
    return [0.0, L] if model.spec.twist_deg else [0.0]


def _ring(model: Model, beam: Beam, x: float) -> np.ndarray:
    """Closed outline of a beam's section at x, tendon-frame (y, z) after the pretwist [m]."""
    c = beam.section.centroid
    ring = (beam.ring_at(x) if beam.ring_at is not None else beam.section.boundary_polyline(16)) + c
    ring = np.vstack([ring, ring[:1]])
    return place(np.full(len(ring), x), ring, model.spec.length, model.spec.twist_deg,
                 model.spec.twist_axis)[:, 1:]


def draw_geometry(model: Model, borders: list[Border], out_png: str) -> str:
    """The preview picture (PNG, Agg); returns its path."""
    fig = Figure(figsize=(8.0, 6.5))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    cmap = colormaps["tab10" if len(model.beams) <= 10 else "tab20"]
    label_all = len(model.beams) <= 40
    for i, beam in enumerate(model.beams):
        colour = cmap(i % cmap.N)
        stations = _stations(model, beam)
        styles = ("-", "--", ":") if len(stations) == 3 else ("-", ":")
        for k, x in enumerate(stations):
            ring = MM * _ring(model, beam, x)
            if k == 0:
                ax.fill(ring[:, 0], ring[:, 1], color=colour, alpha=0.25, lw=0)
            ax.plot(ring[:, 0], ring[:, 1], styles[k], color=colour, lw=1.2 if k == 0 else 0.8)
        c = MM * beam.section.centroid
        ax.plot(*c, "+", color="k", ms=6)
        if label_all:
            ax.annotate(beam.name, c, fontsize=7 if len(model.beams) > 7 else 9, ha="center",
                        va="bottom", xytext=(0, 4), textcoords="offset points")
    for br in borders:
        pts = MM * br.points
        ax.plot(pts[:, 0], pts[:, 1], color="crimson" if br.contact else "k",
                lw=2.8 if br.contact else 2.0, solid_capstyle="round")
    a = MM * np.asarray(model.spec.twist_axis)
    ax.plot(*a, "o", mfc="none", mec="k", ms=11, mew=1.5)
    ax.plot(*a, "x", color="k", ms=8, mew=1.5)
    _legend(ax, model, borders)
    ax.set_aspect("equal")
    ax.set_xlabel("y [mm]")
    ax.set_ylabel("z [mm]")
    ax.grid(alpha=0.3)
    ax.set_title(f"{model.spec.name}: {len(model.beams)} section(s) at x = 0 (tendon frame), "
                 f"L = {model.spec.length * MM:g} mm", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, out_png)


def _legend(ax, model: Model, borders: list[Border]) -> None:
    spec = model.spec
    varies = any(b.ring_at is not None for b in model.beams)
    ax.plot([], [], "-", color="0.4", label="section at x = 0 (+: centroid)")
    if varies:
        ax.plot([], [], "--", color="0.4", lw=0.8, label="at x = L/2")
    if varies or spec.twist_deg:
        ax.plot([], [], ":", color="0.4", lw=0.8,
                label="at x = L" + (f" (turned by ψ = {spec.twist_deg:g}°)" if spec.twist_deg else ""))
    if any(br.contact is None for br in borders):
        ax.plot([], [], "-", color="k", lw=2.0, label="shared border (merged), no contact")
    if any(br.contact for br in borders):
        ax.plot([], [], "-", color="crimson", lw=2.8, label="contact interface")
    a = MM * _clean(spec.twist_axis)
    ax.plot([], [], "x", color="k", ms=8, mew=1.5, label=f"twist axis ({a[0]:.4g}, {a[1]:.4g}) mm")
    ax.legend(fontsize=7, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0))


def check_geometry(spec: ModelSpec, out_png: str | None) -> list[str]:
    """Build the model and its contact (no solve), draw it to ``out_png`` (None: no picture) and
    return the lines to print: the model's own header lines, then ``check_lines``.  Input errors
    are raised as ``InputError`` (key path and fix), a picture that cannot be written as OSError."""
    model = build_model(spec)
    said: list[str] = []
    contact = contact_for(model, spec.contact, said.append) if spec.contact else None
    borders = find_borders(model, contact.interfaces if contact else None)
    lines = model.describe() + [ln.replace("[ancf]   ", "", 1) for ln in said] + check_lines(model, borders)
    if out_png:
        draw_geometry(model, borders, out_png)
    return lines
