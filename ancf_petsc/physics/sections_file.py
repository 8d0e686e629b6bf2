"""Outlines from config lists and from sections files (the Type III format of the paper's data)."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from .section import DEFAULT_CUBATURE_DEGREE, Section, make_outline
from .spline import DEFAULT_SPLINE_DEGREE, SectionError, SplineCurve


# --------------------------------------------------------------------------------------
# Config-style data
# --------------------------------------------------------------------------------------
def inline_loop(curves: Sequence[Mapping[str, Any]],
                spline_degree: int = DEFAULT_SPLINE_DEGREE) -> list[tuple[SplineCurve, bool]]:
    """Loop from config data ``[{name: str (optional), points: [[y, z], ...]}, ...]``.

    The curves are taken in order around a closed boundary; names default to ``curve<i>``
    (1-based); a curve that closes on itself is periodic (smooth there; a corner: split the curve
    there).  Returns the list of (SplineCurve, False) for :func:`make_outline`.
    """
    if isinstance(curves, (str, bytes, Mapping)) or not isinstance(curves, Sequence):
        raise SectionError("the outline curves must be a list of {name, points} entries")
    if not curves:
        raise SectionError("the outline has no curves; give at least one {points: [...]} entry")
    out = []
    for i, entry in enumerate(curves, start=1):
        if not isinstance(entry, Mapping) or "points" not in entry:
            raise SectionError(f"outline curve {i} must be a mapping with a 'points' list of "
                               "[y, z] pairs")
        unknown = set(entry) - {"name", "points"}
        if unknown:
            raise SectionError(f"outline curve {i} has unknown keys {sorted(unknown)}; only "
                               "'name' and 'points' are allowed")
        name = str(entry.get("name", f"curve{i}"))
        out.append((SplineCurve(entry["points"], spline_degree, name, periodic=True), False))
    return out


@dataclass
class SectionsFile:
    """Contents of a sections file (e.g. configs/data/achilles_type3_sections.yaml).

    ``curves``: each named curve built once (in metres, tendon frame), shared by both
    neighbours; ``loops``: per sub-section a list of (SplineCurve, reversed_flag);
    ``twist_axis``: the triple point [m]; ``length_m`` (None when not given) and ``c10_MPa``
    per sub-section (empty when not given), the source's data, which the model does not read
    (the config gives geometry.length and each beam's material); ``scale`` in metres per pixel.
    """

    path: str
    scale: float
    curves: dict[str, SplineCurve]
    loops: dict[str, list[tuple[SplineCurve, bool]]]
    twist_axis: np.ndarray
    length_m: float | None
    c10_MPa: dict[str, float]
    spline_degree: int = DEFAULT_SPLINE_DEGREE
    notes: list[str] = field(default_factory=list)

    def section(self, name: str, degree: int = DEFAULT_CUBATURE_DEGREE,
                compress: bool = True) -> Section:
        """The outline section of loop ``name`` (see :func:`make_outline`)."""
        if name not in self.loops:
            raise SectionError(f"the sections file has no loop '{name}'; choose one of "
                               f"{sorted(self.loops)}")
        return make_outline(self.loops[name], degree=degree, compress=compress)


def _px_to_m(value: Any, scale: float, what: str) -> np.ndarray:
    try:
        P = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise SectionError(f"{what} must be a list of [px_x, px_y] pairs") from None
    if P.ndim == 1:
        P = P.reshape(1, -1)
    if P.ndim != 2 or P.shape[1] != 2 or not np.all(np.isfinite(P)):
        raise SectionError(f"{what} must be a list of finite [px_x, px_y] pairs")
    return np.column_stack([P[:, 0] * scale, -P[:, 1] * scale])


def _positive_number(value: Any, what: str) -> float:
    if isinstance(value, bool):
        value = None
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = float("nan")
    if not (np.isfinite(v) and v > 0):
        raise SectionError(f"{what} must be a positive number, got {value!r}")
    return v


def load_sections_file(path: str | Path,
                       spline_degree: int = DEFAULT_SPLINE_DEGREE) -> SectionsFile:
    """Load a sections file: pixel control points (y = px_x * scale, z = -px_y * scale),
    named ``curves``, loops under ``subtendons`` ('-name' = reversed), ``triple_point_px``,
    ``scale_m_per_px``, and optionally the source's ``length_m`` and ``c10_MPa``.  Each curve becomes ONE SplineCurve of
    degree ``spline_degree`` (Sec. 2.2) shared by every loop that uses it."""
    import yaml

    from .. import yamlio

    p = Path(path)
    try:
        text = yamlio.read_text(str(p))
    except OSError as exc:
        raise SectionError(f"cannot read the sections file '{p}' ({exc.strerror}); "
                           "check the path") from None
    except UnicodeDecodeError as exc:     # a Latin-1 comment stopped the run with a traceback
        line = exc.object[:exc.start].count(b"\n") + 1
        raise SectionError(f"the sections file '{p}' is not UTF-8 text (byte {exc.object[exc.start]:#04x} "
                           f"on line {line}); save it as UTF-8") from None
    try:
        data = yamlio.load(text)
    except yaml.YAMLError as exc:
        raise SectionError(f"the sections file '{p}' is not valid YAML ({exc}); "
                           "fix its syntax") from None
    if not isinstance(data, Mapping):
        raise SectionError(f"the sections file '{p}' must be a YAML mapping with the keys "
                           "scale_m_per_px, triple_point_px, curves, subtendons (and optionally "
                           "c10_MPa, length_m)")
    # length_m and c10_MPa were required though nothing reads them: a traced subject's file had
    # to state a length and moduli that the config's geometry.length and materials override
    required = ["scale_m_per_px", "triple_point_px", "curves", "subtendons"]
    missing = [k for k in required if k not in data]
    if missing:
        raise SectionError(f"the sections file '{p}' lacks the key(s) {', '.join(missing)}; "
                           "add them (see configs/data/achilles_type3_sections.yaml)")
    scale = _positive_number(data["scale_m_per_px"], f"scale_m_per_px in '{p}'")
    length = _positive_number(data["length_m"], f"length_m in '{p}'") if "length_m" in data else None
    twist = _px_to_m(data["triple_point_px"], scale, f"triple_point_px in '{p}'")
    if twist.shape[0] != 1:
        raise SectionError(f"triple_point_px in '{p}' must be one [px_x, px_y] pair")

    raw_curves = data["curves"]
    if not isinstance(raw_curves, Mapping) or not raw_curves:
        raise SectionError(f"'curves' in '{p}' must be a non-empty mapping name -> list of "
                           "[px_x, px_y] points")
    curves: dict[str, SplineCurve] = {}
    for name, pts in raw_curves.items():
        name = str(name)
        if name.startswith("-"):
            raise SectionError(f"curve name '{name}' in '{p}' starts with '-', which marks "
                               "reversal in loops; rename the curve")
        P = _px_to_m(pts, scale, f"curve '{name}' in '{p}'")
        curves[name] = SplineCurve(P, spline_degree, name, periodic=True)

    raw_loops = data["subtendons"]
    if not isinstance(raw_loops, Mapping) or not raw_loops:
        raise SectionError(f"'subtendons' in '{p}' must be a non-empty mapping name -> list "
                           "of curve names")
    loops: dict[str, list[tuple[SplineCurve, bool]]] = {}
    for lname, refs in raw_loops.items():
        lname = str(lname)
        if isinstance(refs, (str, bytes)) or not isinstance(refs, Sequence) or not refs:
            raise SectionError(f"subtendon '{lname}' in '{p}' must list its boundary curves, "
                               "e.g. [a, -b, c]")
        loop = []
        for ref in refs:
            ref = str(ref).strip()
            flip = ref.startswith("-")
            key = ref[1:].strip() if flip else ref
            if key not in curves:
                raise SectionError(f"subtendon '{lname}' in '{p}' uses the unknown curve "
                                   f"'{key}'; define it under 'curves' (known: "
                                   f"{', '.join(sorted(curves))})")
            loop.append((curves[key], flip))
        loops[lname] = loop

    raw_c10 = data.get("c10_MPa", {})
    if not isinstance(raw_c10, Mapping):
        raise SectionError(f"'c10_MPa' in '{p}' must map subtendon names to moduli in MPa")
    c10: dict[str, float] = {}
    for k, v in raw_c10.items():
        k = str(k)
        if k not in loops:
            raise SectionError(f"'c10_MPa' in '{p}' names the unknown subtendon '{k}'; use "
                               f"one of {', '.join(sorted(loops))}")
        c10[k] = _positive_number(v, f"c10_MPa.{k} in '{p}'")

    return SectionsFile(path=str(p), scale=scale, curves=curves, loops=loops,
                        twist_axis=twist[0], length_m=length, c10_MPa=c10,
                        spline_degree=int(spline_degree))
