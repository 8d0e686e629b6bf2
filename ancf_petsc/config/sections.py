"""``geometry.sections`` of a config → a validated :class:`SectionsSpec` (no file is opened here
except the YAML geometry files themselves; outline files are read at build time).

A geometry description says what it is: ``units`` (m, mm, um, or px with ``pixel_size``) and
``axes`` (which tendon axes the file's first and second coordinates point along; ``image`` means
columns to the right = y and rows downwards = -z).  It holds geometry only: one ``outlines`` entry
per subtendon, taken from inline points, a loop of named ``curves``, or a file of one of the
formats of ``outline_formats`` (its extension says which; the keys that format reads are checked
here).  The user guide is docs/geometry.md.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field

import numpy as np
import yaml

from .. import yamlio
from ..outline_formats import FORMATS, Importer, format_of, known_types, outline_keys

from .values import ConfigError, integer, key_path, mapping, number, sequence, shown, spline_degree, string

__all__ = ["OutlineSource", "GeometrySource", "SectionsSpec", "parse_sections", "UNITS"]

#: micrometres as um, the micro sign (U+00B5) or the Greek mu (U+03BC), which look alike: units: μm was
#: refused as "must be one of m, mm, um, µm, px; got 'μm'"
UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "\u00b5m": 1e-6, "\u03bcm": 1e-6}
AXIS_NAMES = ("y", "-y", "z", "-z")
NOT_GEOMETRY = ("length", "length_m", "material", "materials", "c10", "c10_MPa", "mu",
                "bulk_modulus", "twist_deg", "twist_axis", "triple_point_px", "scale_m_per_px")
FILE_KEYS = ("units", "pixel_size", "axes", "source", "slice", "outlines", "curves", "description")
#: an outline's keys: inline points or curves, or a file and the keys its format reads
OUTLINE_KEYS = ("points", "file", "curves") + tuple(outline_keys())
OPTION_KEYS = ("merge_tolerance", "smoothing", "fit_tolerance", "spline_degree")


@dataclass
class OutlineSource:
    """Where one subtendon's outline comes from: inline ``points``, a loop of named ``curves``,
    or a ``file`` of the format ``kind`` (a name of outline_formats.FORMATS) with the values of
    the keys that format reads (``keys``); ``key`` is its key path for error messages."""
    name: str
    kind: str                                 # "points", "curves" or a format's name
    key: str
    points: list | None = None
    file: str | None = None
    keys: dict = field(default_factory=dict)
    curves: list[str] | None = None


@dataclass
class GeometrySource:
    """One measured cross-section: units, axes and the outlines of every subtendon."""
    key: str                                  # config key path (+ file) for messages
    where: str                                # 'config' or the geometry file path
    units: str
    scale: tuple[float, float] | None         # metres per file unit (u, v); None: NIfTI header
    axes: np.ndarray                          # (2, 2): (y, z) = axes @ (u, v)
    outlines: dict[str, OutlineSource]
    curves: dict[str, list] = field(default_factory=dict)
    slice: tuple[int, int] | None = None      # NIfTI: (axis, index)

    def err(self, key: str, msg: str) -> ConfigError:
        """A ConfigError at this source (config key, or file + key inside it)."""
        if self.where == "config":
            return ConfigError(key_path(self.key, key) if key else self.key, msg)
        return ConfigError(self.key, f"{os.path.basename(self.where)}: {key + ': ' if key else ''}{msg}")


@dataclass
class SectionsSpec:
    """``geometry.sections``: one section (``stations`` = [(None, source)]) or stations along x."""
    stations: list[tuple[float | None, GeometrySource]]
    merge_tolerance: float | None = None      # None: auto (50 um, 1.5 px for images)
    smoothing: float | None = None            # None: auto (2 px for images, 0 otherwise)
    fit_tolerance: float | None = None        # None: auto (0.5 px for images, tol / 4 otherwise)
    spline_degree: int = 3
    key: str = "geometry.sections"

    @property
    def names(self) -> list[str]:
        return list(self.stations[0][1].outlines)

    @property
    def varies(self) -> bool:
        return len(self.stations) > 1


def _abs(path: str, base_dir: str) -> str:
    return path if os.path.isabs(path) else os.path.normpath(os.path.join(base_dir, path))


def _length_with_unit(value, path: str) -> float:
    """'0.05 mm' / '20 um' / '1.2e-5 m' → metres."""
    m = re.fullmatch(r"\s*([-+0-9.eE]+)\s*([a-z\u00b5\u03bc]+)\s*", str(value)) if isinstance(value, str) else None
    if m is None or m.group(2) not in UNITS:
        raise ConfigError(path, f"expected a length with its unit, e.g. '0.05 mm' (units: m, mm, um); "
                                f"got {shown(value)}")
    v = number(m.group(1), path, positive=True)
    return v * UNITS[m.group(2)]


def _axes(value, path: str) -> np.ndarray:
    if value == "image":
        value = ["y", "-z"]
    if not isinstance(value, list) or len(value) != 2 or not all(v in AXIS_NAMES for v in value) \
            or {v.lstrip("-") for v in value} != {"y", "z"}:
        raise ConfigError(path, "give the tendon axis of the file's first and second coordinate, e.g. "
                                "[y, z], [y, -z] or image (= [y, -z]: columns right, rows down); "
                                f"got {shown(value)}")
    M = np.zeros((2, 2))
    for col, v in enumerate(value):
        M["yz".index(v[-1]), col] = -1.0 if v.startswith("-") else 1.0
    return M


def _pairs(value, key: str) -> list[list[float]]:
    """A list of [u, v] number pairs."""
    out = []
    for j, p in enumerate(sequence(value, key)):
        if not isinstance(p, list) or len(p) != 2:
            raise ConfigError(key_path(key, j), f"expected a [u, v] pair; got {shown(p)}")
        out.append([number(x, key_path(key_path(key, j), c)) for c, x in enumerate(p)])
    return out


def _format_of(path: str, key: str) -> Importer:
    fmt = format_of(path)
    if fmt is None:
        raise ConfigError(key, f"unknown file type {shown(os.path.basename(path))}; use {known_types()}")
    return fmt


def _one_source_hint() -> str:
    return ", ".join(f"{k} for {' and '.join(f.title + 's' for f in fs)}" for k, fs in outline_keys().items())


def _format_keys(fmt: Importer, value: dict, key: str) -> dict:
    """The validated values of the per-outline keys ``fmt`` reads; a key of another format is
    an error naming the formats it belongs to."""
    for k, owners in outline_keys().items():
        if k in value and fmt not in owners:
            exts = "/".join(e for f in owners for e in f.extensions)
            raise ConfigError(key_path(key, k), f"{k} belongs to {' and '.join(f.title + 's' for f in owners)} "
                                                f"({exts}), not to a {fmt.title}")
    out = {}
    for k in fmt.keys:
        if k.name not in value:
            if k.required:
                raise ConfigError(key, f"a {fmt.title} needs {k.meaning}")
            continue
        kp = key_path(key, k.name)
        out[k.name] = integer(value[k.name], kp, lo=k.minimum) if k.type is int else string(value[k.name], kp)
    return out


def _outline(name: str, value, key: str, default_file: str | None, base_dir: str) -> OutlineSource:
    if isinstance(value, list):
        value = {"points": value}
    mapping(value, key, optional=OUTLINE_KEYS)
    given = [k for k in ("points", "curves") if k in value]
    if len(given) > 1 or (given and any(k in value for k in ("file",) + tuple(outline_keys()))):
        raise ConfigError(key, f"give one source: points, curves, or a file (with {_one_source_hint()})")
    if "points" in value:
        return OutlineSource(name, "points", key, points=_pairs(value["points"], key_path(key, "points")))
    if "curves" in value:
        refs = sequence(value["curves"], key_path(key, "curves"))
        return OutlineSource(name, "curves", key, curves=[string(str(r), key_path(key, "curves")) for r in refs])
    f = value.get("file", default_file)
    if f is None:
        raise ConfigError(key, "no source: give points, curves, or a file (or a top-level 'source' file)")
    f = _abs(string(f, key_path(key, "file")), base_dir)
    if not os.path.isfile(f):
        raise ConfigError(key_path(key, "file") if "file" in value else key,
                          f"file not found: {f} (paths are relative to the file that names them)")
    fmt = _format_of(f, key_path(key, "file"))
    return OutlineSource(name, fmt.name, key, file=f, keys=_format_keys(fmt, value, key))


def _source(value, key: str, where: str, base_dir: str) -> GeometrySource:
    """Validate one geometry description (the contents of a geometry file or the inline keys)."""
    if not isinstance(value, dict):
        raise ConfigError(key, f"expected a mapping with keys {', '.join(FILE_KEYS)}; got {shown(value)}")
    bad = [k for k in value if k in NOT_GEOMETRY]
    inner = key if where == "config" else ""

    def err(k, msg):
        if where == "config":
            return ConfigError(key_path(key, k) if k else key, msg)
        return ConfigError(key, f"{os.path.basename(where)}: {k + ': ' if k else ''}{msg}")

    if bad:
        raise err(bad[0], "a geometry description holds geometry only: give the length in "
                          "geometry.length, materials per beam, the twist in geometry.twist_deg/twist_axis")
    try:
        mapping(value, inner, required=("units", "axes", "outlines"), optional=FILE_KEYS)
        units = string(value["units"], key_path(inner, "units"), tuple(UNITS) + ("px",))
        scale = None
        if units == "px":
            if "pixel_size" not in value:
                raise ConfigError(key_path(inner, "pixel_size"), "units: px needs the pixel size, e.g. "
                                  "pixel_size: 0.05 mm (or [0.05 mm, 0.06 mm] for u, v; or header for NIfTI)")
            ps = value["pixel_size"]
            if ps == "header":
                scale = None
            elif isinstance(ps, list) and len(ps) == 2:
                scale = tuple(_length_with_unit(v, key_path(key_path(inner, "pixel_size"), i)) for i, v in enumerate(ps))
            else:
                s = _length_with_unit(ps, key_path(inner, "pixel_size"))
                scale = (s, s)
        else:
            if "pixel_size" in value:
                raise ConfigError(key_path(inner, "pixel_size"), f"pixel_size needs units: px (the units are {units})")
            scale = (UNITS[units], UNITS[units])
        axes = _axes(value["axes"], key_path(inner, "axes"))
        default_file = None
        if "source" in value:
            default_file = _abs(string(value["source"], key_path(inner, "source")), base_dir)
            if not os.path.isfile(default_file):
                raise ConfigError(key_path(inner, "source"), f"file not found: {default_file}")
            _format_of(default_file, key_path(inner, "source"))
        raw_out = value["outlines"]
        if not isinstance(raw_out, dict) or not raw_out:
            raise ConfigError(key_path(inner, "outlines"), "expected a mapping subtendon name -> source, "
                                                        "e.g. {soleus: {label: 1}}")
        outlines = {}
        for name, v in raw_out.items():
            name = str(name)
            if name.startswith("-") or "/" in name or ":" in name:
                raise ConfigError(key_path(key_path(inner, "outlines"), name),
                                  "outline names may not start with '-' or contain '/' or ':'")
            outlines[name] = _outline(name, v, key_path(key_path(inner, "outlines"), name), default_file,
                                      base_dir)
        kinds = {o.kind for o in outlines.values()}
        if "curves" in kinds and len(kinds) > 1:
            raise ConfigError(key_path(inner, "outlines"), "use either loops of named curves or traced "
                                                        "outlines in one description, not both")
        curves = {}
        if "curves" in value:
            if not isinstance(value["curves"], dict):
                raise ConfigError(key_path(inner, "curves"), "expected a mapping name -> list of [u, v] points")
            for cname, pts in value["curves"].items():
                curves[str(cname)] = _pairs(pts, key_path(key_path(inner, "curves"), str(cname)))
        for o in outlines.values():
            for ref in o.curves or []:
                if ref.lstrip("-").strip() not in curves:
                    raise ConfigError(key_path(o.key, "curves"), f"unknown curve {shown(ref)}; define it under "
                                      f"curves (known: {', '.join(curves) or 'none'})")
        slc = None
        if "slice" in value:
            sk = key_path(inner, "slice")
            mapping(value["slice"], sk, required=("axis", "index"))
            ax = value["slice"]["axis"]
            ax = {"i": 0, "j": 1, "k": 2}.get(ax, ax)
            slc = (integer(ax, key_path(sk, "axis"), lo=0, hi=2), integer(value["slice"]["index"], key_path(sk, "index"), lo=0))
        formats = [FORMATS.get(k) for k in kinds]
        sliced = [f for f in formats if f is not None and f.needs_slice]
        if sliced and slc is None:
            raise ConfigError(key_path(inner, "slice"), f"a {sliced[0].title} needs the slice: {{axis: 2, index: 40}} "
                                                     "(axis 0/1/2 or i/j/k, 0-based index)")
        _check_frame(formats, units, slc, inner)
        if scale is None and not all(f is not None and f.header_scale for f in formats):
            headers = " or ".join(f.title for f in FORMATS.values() if f.header_scale)
            raise ConfigError(key_path(inner, "pixel_size"), f"pixel_size: header reads the voxel size from the "
                                                          f"header of a {headers}; give the size for other sources")
    except ConfigError as exc:
        if where == "config":
            raise
        raise ConfigError(key, f"{os.path.basename(where)}: {exc}") from None
    return GeometrySource(key, where, units, scale, axes, outlines, curves, slc)


def _check_frame(formats: list, units: str, slc, inner: str) -> None:
    """Images are in pixels and only volumes are sliced: a mask read with units: mm took each pixel
    for 1 mm (a 0.05 mm pixel image 400 x larger in area), a slice beside a PNG was unread."""
    images = [f for f in formats if f is not None and f.pixels]
    if images and units != "px":
        raise ConfigError(key_path(inner, "units"), f"a {images[0].title} is in pixels: give units: px and its "
                                                    f"pixel_size (e.g. 0.05 mm); got {units}")
    if slc is not None and not any(f is not None and f.needs_slice for f in formats):
        volumes = " or ".join(f.title for f in FORMATS.values() if f.needs_slice)
        raise ConfigError(key_path(inner, "slice"), f"only a {volumes} is sliced, none of these outlines comes "
                                                    f"from one: remove it; got {{axis: {slc[0]}, index: {slc[1]}}}")


def _load_file(f: str, key: str, base_dir: str) -> GeometrySource:
    path = _abs(f, base_dir)
    if not os.path.isfile(path):
        raise ConfigError(key, f"geometry file not found: {path} (paths are relative to the config file)")
    try:
        data = yamlio.load(yamlio.read_text(path))
    except UnicodeDecodeError:
        raise ConfigError(key, f"{os.path.basename(path)}: not a text (UTF-8) YAML file") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or ""
        raise ConfigError(key, f"{os.path.basename(path)}: YAML syntax error{where}"
                               + (f": {problem}" if problem else "")) from None
    return _source(data, key, path, os.path.dirname(path))


def _station(value, key: str, base_dir: str, with_x: bool) -> tuple[float | None, GeometrySource]:
    if not isinstance(value, dict):
        raise ConfigError(key, f"expected a mapping (file: ... or units/axes/outlines); got {shown(value)}")
    x = None
    rest = dict(value)
    if with_x:
        if "x" not in rest:
            raise ConfigError(key_path(key, "x"), "missing value (required): the station's position along "
                                               "the tendon [m]")
        x = number(rest.pop("x"), key_path(key, "x"), nonneg=True, hint=" (metres from the x = 0 end)")
    if "file" in rest:
        extra = [k for k in rest if k != "file"]
        if extra:
            raise ConfigError(key_path(key, extra[0]), "give either file: or the keys inline, not both")
        return x, _load_file(string(rest["file"], key_path(key, "file")), key_path(key, "file"), base_dir)
    return x, _source(rest, key, "config", base_dir)


def parse_sections(value, key: str, base_dir: str, length: float) -> SectionsSpec:
    """Validate ``geometry.sections``."""
    if not isinstance(value, dict):
        raise ConfigError(key, "expected a mapping: file: <geometry file>, or the keys units/axes/"
                               "outlines inline, or stations: [{x, file}, ...]")
    opts = {k: value[k] for k in OPTION_KEYS if k in value}
    rest = {k: v for k, v in value.items() if k not in OPTION_KEYS}
    spec = SectionsSpec(stations=[], key=key)
    for k, v in opts.items():
        if k == "spline_degree":
            spec.spline_degree = spline_degree(v, key_path(key, k), hi=5)
        elif v != "auto":
            setattr(spec, k, number(v, key_path(key, k), nonneg=(k == "smoothing"), positive=(k != "smoothing"),
                                    hint=" (metres, or auto)"))
    if "stations" in rest:
        if len(rest) > 1:
            other = [k for k in rest if k != "stations"][0]
            raise ConfigError(key_path(key, other), "with stations, every station names its own file "
                                                 "or keys; move this key into the stations")
        st = sequence(rest["stations"], key_path(key, "stations"))
        if len(st) < 2:
            raise ConfigError(key_path(key, "stations"), "give at least two stations (or one section "
                                                      "without stations)")
        for i, s in enumerate(st):
            spec.stations.append(_station(s, key_path(key_path(key, "stations"), i), base_dir, True))
        xs = [x for x, _ in spec.stations]
        if any(b <= a for a, b in zip(xs, xs[1:])):
            raise ConfigError(key_path(key, "stations"), f"station positions x must increase strictly; got {xs}")
        if xs[-1] > length * (1 + 1e-12):
            raise ConfigError(key_path(key_path(key, "stations"), len(xs) - 1) + ".x",
                              f"x = {xs[-1]:g} m lies beyond the tendon (geometry.length = {length:g} m)")
        names = spec.stations[0][1].outlines.keys()
        for i, (_, s) in enumerate(spec.stations[1:], start=1):
            if s.outlines.keys() != names:
                raise ConfigError(key_path(key_path(key, "stations"), i),
                                  f"outlines {sorted(s.outlines)} differ from station 0's {sorted(names)}; "
                                  "every station needs the same subtendons")
    else:
        spec.stations.append(_station(rest, key, base_dir, False))
    if all(src.curves for _, src in spec.stations):
        for k in ("smoothing", "merge_tolerance"):
            if getattr(spec, k) is not None:
                raise ConfigError(key_path(key, k), "loops of named curves are taken exactly as given (no smoothing "
                                                    f"or merging): remove it; got {shown(opts[k])}")
    return spec
