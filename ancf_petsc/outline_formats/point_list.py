"""Point lists: a CSV/TXT file (two numeric columns u, v; an optional header row; comma,
semicolon, tab or space separated; MATLAB's ';' row ends) or a YAML file (a list of [u, v] pairs,
or {points: ...}), in the description's units."""
from __future__ import annotations

import csv
import re

import numpy as np

from .base import Description, Importer, OutlineReadError, RawOutline, file_name

__all__ = ["IMPORTER", "PointList", "read_point_list"]

YAML_EXT = (".yaml", ".yml")


def _yaml_points(text: str, path: str) -> np.ndarray:
    import yaml

    from .. import yamlio
    try:
        data = yamlio.load(text)
    except yaml.YAMLError as exc:
        problem = getattr(exc, "problem", None)
        raise OutlineReadError(f"{file_name(path)} is not valid YAML"
                               + (f" ({problem})" if problem else "")) from None
    if isinstance(data, dict) and "points" in data:
        extra = [str(k) for k in data if k not in ("points", "description")]
        if extra:     # axes: [y, -z] beside the points was ignored: the section came out mirrored
            raise OutlineReadError(f"{file_name(path)} holds points (and a description) only; its "
                                   f"{', '.join(extra)} would not be read: units and axes belong to the geometry "
                                   "description that names the file; remove them here")
        data = data["points"]
    for k, pair in enumerate(data if isinstance(data, list) else []):
        bad = [v for v in (pair if isinstance(pair, list) else []) if isinstance(v, bool)
               or (isinstance(v, str) and "_" in v)]
        if bad:       # YAML reads yes/no/on/off as true/false (1, 0); float('1_0') is 10
            raise OutlineReadError(f"{file_name(path)} point {k + 1}: {bad[0]!r} is not a number "
                                   "(u, v are numbers: yes/no/on/off are YAML's true/false; write 10, not 1_0)")
    try:
        P = np.array(data, dtype=float)
    except (TypeError, ValueError):
        P = np.zeros((0, 0))
    if P.ndim != 2 or P.shape[1] != 2:
        raise OutlineReadError(f"{file_name(path)} must hold a list of [u, v] pairs (or points: [...])")
    return P


def _csv_points(text: str, path: str) -> np.ndarray:
    # MATLAB ends each row with ';' ("1.5, 2.0;" or "1.5 2.0;"): a row terminator, not a column
    lines = [ln.rstrip() for ln in text.splitlines()]
    lines = [ln[:-1] if ln.endswith(";") else ln for ln in lines]
    try:
        delim = csv.Sniffer().sniff("\n".join(lines)[:4096], delimiters=",;\t ").delimiter
    except csv.Error:
        delim = ","
    rows, header = [], None
    for k, row in enumerate(csv.reader(lines, delimiter=delim)):
        row = [c.strip() for c in row if c.strip()]
        row = row[:next((i for i, c in enumerate(row) if c.startswith("#")), len(row))]   # a comment ends it
        if not row:
            continue
        try:
            vals = [float(c) for c in row]
        except ValueError:
            if not rows and header is None:
                header = k                     # one header line, before the numbers
                continue
            comma = " (decimal commas are not read: write 1.5, not 1,5)" if any(
                re.fullmatch(r"[+-]?\d*,\d+", c) for c in row) else ""
            raise OutlineReadError(
                f"{file_name(path)} line {k + 1}: {row!r} is not two numbers u, v (one header "
                "line is allowed, before the numbers; columns separated by a comma, "
                f"semicolon, tab or spaces){comma}") from None
        if any("_" in c for c in row):        # float('1_0') is 10: a typing slip, not a number
            raise OutlineReadError(f"{file_name(path)} line {k + 1}: {row!r} is not two numbers u, v "
                                   "(an underscore in a number: write 10 or 1.0, not 1_0)")
        if len(vals) != 2:
            # an index column or a third coordinate was read as u, v (index, u) with no word
            raise OutlineReadError(f"{file_name(path)} line {k + 1}: {len(vals)} columns {row!r}; a point list "
                                   "has two columns u, v: remove the others (an index, a constant coordinate)")
        rows.append(vals)
    return np.array(rows, dtype=float).reshape(-1, 2)


def read_point_list(path: str) -> RawOutline:
    """Points from a CSV/TXT or YAML file (see the module docstring); at least 3, all finite."""
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise OutlineReadError(f"cannot read {file_name(path)} ({exc.strerror})") from None
    try:        # Excel's "CSV UTF-8" starts with a BOM, which made the first point a header (dropped)
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise OutlineReadError(f"{file_name(path)} line {line}: byte {data[exc.start]:#04x} is not UTF-8 text; "
                               "save the file as UTF-8 (e.g. Excel's 'CSV UTF-8')") from None
    P = _yaml_points(text, path) if path.lower().endswith(YAML_EXT) else _csv_points(text, path)
    if len(P) < 3:
        raise OutlineReadError(f"{file_name(path)} has {len(P)} points; an outline needs at least 3")
    if not np.all(np.isfinite(P)):
        raise OutlineReadError(f"{file_name(path)} has non-finite coordinates")
    return RawOutline(P, closed=False)


class PointList(Importer):
    name = "point_list"
    title = "point list"
    extensions = (".csv", ".txt") + YAML_EXT

    def read(self, path: str, keys: dict, desc: Description) -> RawOutline:
        return read_point_list(path)


IMPORTER = PointList()
