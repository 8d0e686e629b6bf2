"""The whole measured tendon: every station built, sections at any x, twist-axis rules.

:class:`TendonGeometry` is what ``model.build.build_model`` asks for loops (x = 0, or any x when the
sections vary along the tendon), outline rings for the output, the junction where all outlines
meet, and the report printed at the start of a run.
"""
from __future__ import annotations

import numpy as np

from ..config.sections import SectionsSpec
from ..config.values import ConfigError
from ..physics.spline import SplineCurve
from . import polyline as pl
from .build import Station, build_station
from .stations import SectionField

__all__ = ["TendonGeometry", "build_tendon"]


class TendonGeometry:
    """Spline loops of every outline at every station and the field between them."""

    def __init__(self, spec: SectionsSpec, stations: list[tuple[float | None, Station]]) -> None:
        self.spec = spec
        self.stations = stations
        self.names = spec.names
        self.field: SectionField | None = None
        if spec.varies:
            fit_tol = min(st.fit_tolerance for _, st in stations)
            self.field = SectionField([(x, st) for x, st in stations], fit_tol, spec.spline_degree)

    @property
    def varies(self) -> bool:
        return self.field is not None

    def loop(self, name: str, x: float = 0.0) -> list[tuple[SplineCurve, bool]]:
        """The loop of outline ``name`` at x (counter-clockwise (curve, reversed) pairs)."""
        if self.field is None:
            return self.stations[0][1].loops[name]
        return self.field.loop_at(name, x)

    def ring(self, name: str, x: float, n: int = 48) -> np.ndarray:
        """Closed polyline of outline ``name`` at x: ``n`` points at equal arc length, matched
        from one x to the next (output surfaces)."""
        if self.field is None:
            return pl.resample(self.stations[0][1].polyline(name), n)
        return pl.resample(self.field.ring_at(name, x), n)

    def junctions(self, names: list[str]) -> np.ndarray:
        """Junctions (x = 0) through which every loop in ``names`` passes, (k, 2)."""
        st = self._at_zero()
        keep = [k for k, who in enumerate(st.junction_loops) if set(names) <= who]
        return st.junctions[keep]

    def _at_zero(self) -> Station:
        return self.stations[0][1]

    def report(self) -> list[str]:
        lines = []
        for x, st in self.stations:
            lines += st.report
        if self.field is not None:
            mode = ("interfaces shared by every station, free curves blended" if self.field.structured
                    else "outlines registered (shift and rotation) and blended")
            rot = "" if self.field.structured else ", section rotation " + ", ".join(
                f"{np.rad2deg(t):+.2f} deg" for t in self.field.theta)
            xs = ", ".join(f"{x * 1e3:g}" for x, _ in self.stations)
            lines.append(f"sections vary along x: stations at x = {xs} mm; {mode}{rot}")
        return lines


def _check_mirror(stations, key: str) -> None:
    """Outlines go round the section in the same sense at every station (>= 3 outlines), else the
    axes of one station mirror it."""
    if len(stations[0][1].loops) < 3:
        return
    orders, first = [], next(iter(stations[0][1].loops))
    for _, st in stations:
        names = list(st.loops)
        cents = np.array([pl.centroid(st.polyline(n)) for n in names])
        c = cents.mean(axis=0)
        ang = np.arctan2(cents[:, 1] - c[1], cents[:, 0] - c[0])
        order = [names[i] for i in np.argsort(ang)]
        k = order.index(first)          # station 0's first outline (a station may list them otherwise)
        orders.append(order[k:] + order[:k])
    for i, o in enumerate(orders[1:], start=1):
        rev = [o[0]] + o[1:][::-1]
        if o != orders[0] and rev == orders[0]:
            raise ConfigError(f"{key}.stations[{i}]", f"this station is the mirror image of station 0 "
                              f"(its outlines go round as {', '.join(o)}, at station 0 as "
                              f"{', '.join(orders[0])}): wrong orientation; check its axes")


def build_tendon(spec: SectionsSpec) -> TendonGeometry:
    """Build every station of ``geometry.sections`` (errors are one-line ConfigErrors)."""
    stations = []
    for i, (x, src) in enumerate(spec.stations):
        label = f"station {i} (x = {x * 1e3:g} mm)" if x is not None else ""
        stations.append((0.0 if x is None else x, build_station(src, spec, label)))
    if spec.varies:
        _check_mirror(stations, spec.key)
    return TendonGeometry(spec, stations)
