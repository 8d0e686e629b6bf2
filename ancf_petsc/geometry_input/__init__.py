"""Subject-specific cross-sections: geometry files, border merge, stations along x.

``config.sections`` validates ``geometry.sections`` of a config (units, axes, sources); here
``build`` turns one measured section into spline loops (the outline files read by their format,
``outline_formats`` → ``polyline`` checks and
smoothing → ``merge`` of neighbours traced apart → ``fit``); ``stations`` interpolates sections
measured at several stations along the tendon; ``tendon`` builds them for a model.  User guide:
docs/geometry.md.
"""
from .build import Station, build_station

__all__ = ["Station", "build_station"]
