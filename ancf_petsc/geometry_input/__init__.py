"""Subject-specific cross-sections: geometry files, importers, border merge, stations along x.

``spec`` validates ``geometry.sections`` of a config (units, axes, sources); ``build`` turns one
measured section into spline loops (``importers`` → ``polyline`` checks and smoothing → ``merge``
of neighbours traced apart → ``fit``); ``stations`` interpolates sections measured at several
stations along the tendon; ``twist`` resolves the twist-axis rule.  User guide: docs/geometry.md.
"""
from .build import Station, build_station
from ..config.sections import SectionsSpec, parse_sections

__all__ = ["Station", "build_station", "SectionsSpec", "parse_sections"]
