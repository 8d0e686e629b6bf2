"""Tables of loads over time: CSV files and OpenSim storage files (.sto / .mot).

A load history (config/history.py) reads its muscle forces from a table of columns: a CSV file
with a header line ('#' lines are comments; an Excel "CSV UTF-8" byte-order mark is accepted), or
an OpenSim storage file (a header of ``key=value`` lines closed by ``endheader``, then a line of
tab- or space-separated column names and rows of numbers: what OpenSim's static optimisation or
computed muscle control writes, e.g. ``*_StaticOptimization_force.sto``).  A separator ending
every line (MATLAB's or Excel's exports) and rows of separators only are dropped.  Every value must
be a finite number; an error names the file, the data row (and its line) and the column.
"""
from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass

import numpy as np

from .values import ConfigError, number, plain_number

#: OpenSim storage files by extension (anything else is read as CSV)
STORAGE = (".sto", ".mot")


@dataclass
class LoadTable:
    """Columns of numbers by name (in file order) and where they came from."""
    path: str
    columns: dict[str, np.ndarray]

    @property
    def n_rows(self) -> int:
        return len(next(iter(self.columns.values())))


def _storage_body(lines: list[str], path: str, where: str) -> tuple[list[str], int, dict]:
    """The lines after an OpenSim header (``endheader``), the line number of the first, and the
    header's ``key=value`` entries (key: (value, line number))."""
    for k, line in enumerate(lines):
        if line.strip().lower() == "endheader":
            meta = {ln.split("=", 1)[0].strip(): (ln.split("=", 1)[1].strip(), n + 1)
                    for n, ln in enumerate(lines[:k]) if "=" in ln}
            return lines[k + 1:], k + 2, meta
    raise ConfigError(where, f"{path}: no 'endheader' line: not an OpenSim storage file "
                             "(.sto/.mot); give a CSV file with a header line instead")


def _rows(path: str, text: str, where: str) -> tuple[list[list[str]], list[int], dict]:
    """Header and data rows (fields as strings) with their line numbers, and an OpenSim header's
    entries (empty for a CSV file)."""
    lines = text.splitlines()
    first_line, meta = 1, {}
    if os.path.splitext(path)[1].lower() in STORAGE:
        lines, first_line, meta = _storage_body(lines, path, where)
        rows = [(first_line + k, [f.strip() for f in _storage_fields(ln)]) for k, ln in enumerate(lines)
                if ln.strip()]
    else:
        rows = []
        for k, ln in enumerate(lines):
            if ln.strip() and not ln.lstrip().startswith("#"):
                rows.append((first_line + k, [f.strip() for f in next(csv.reader(io.StringIO(ln)))]))
        _check_csv_form(path, text, rows[0][1] if rows else [], where)
    rows = _without_trailing_separators(rows)
    if len(rows) < 2:
        raise ConfigError(where, f"{path}: expected a line of column names and at least one row of numbers")
    return [r for _, r in rows], [n for n, _ in rows], meta


def _storage_fields(line: str) -> list[str]:
    """The fields of an OpenSim line: tab-separated where it has a tab (column names may hold
    spaces), else separated by spaces (a row written with spaces under a tab-separated header)."""
    return line.split("\t") if "\t" in line else line.split()


def _without_trailing_separators(rows: list[tuple[int, list[str]]]) -> list[tuple[int, list[str]]]:
    """Rows without the empty fields a separator at the end of every line leaves (a MATLAB or
    Excel export: 'time,soleus,' or a tab after each value), and without rows of separators only
    (',,,'); an empty field under a named column stays (a missing value, refused by name)."""
    rows = [(n, r) for n, r in rows if any(r)]
    if not rows:
        return rows
    header = rows[0][1]
    width = len(header)
    while width and not header[width - 1]:
        width -= 1
    return [(n, r[:width] if len(r) > width and not any(r[width:]) else r) for n, r in rows]


def _check_csv_form(path: str, text: str, header: list[str], where: str) -> None:
    """A file read as CSV that is not comma-separated: an OpenSim table under another extension,
    or fields separated by semicolons or tabs (a header of one column holding them)."""
    if any(ln.strip().lower() == "endheader" for ln in text.splitlines()):
        raise ConfigError(where, f"{path}: an OpenSim storage file (it has an 'endheader' line): give "
                                 "it the extension .sto or .mot, or write its table as CSV")
    if len(header) == 1:
        for sep, name in ((";", "semicolons"), ("\t", "tabs"), ("|", "bars")):
            if sep in header[0]:
                raise ConfigError(where, f"{path}: the header line is one column {header[0]!r}: its "
                                         f"fields are separated by {name}; a CSV file here separates "
                                         "them by commas (and uses '.' as the decimal point)")


def _check_storage_size(path: str, meta: dict, rows: list[list[str]], where: str) -> None:
    """The sizes an OpenSim header states (nRows/nColumns, or datarows/datacolumns of older
    files) against the table: a file cut short would otherwise be a shorter history."""
    for keys, have, what in ((("nrows", "datarows"), len(rows) - 1, "data rows"),
                             (("ncolumns", "datacolumns"), len(rows[0]), "columns")):
        key = next((k for k in meta if k.lower() in keys), None)
        stated, line = meta.get(key, ("", 0))
        if key is not None and not (stated.isascii() and stated.isdigit()):
            raise ConfigError(where, f"{path}: header line {line} '{key}={stated}' is not a count of "
                                     f"{what}: write it as a whole number ({key}={have} for this table), "
                                     "or remove the line")
        if key is not None and int(stated) != have:
            why = ("a file cut short? (complete it, or correct {})" if have < int(stated) else
                   "more than it states: correct {}").format(key)
            raise ConfigError(where, f"{path}: its header says {key}={stated}, the table has {have} "
                                     f"{what}: {why}")


def read_load_table(path: str, where: str) -> LoadTable:
    """The columns of ``path`` (CSV or OpenSim storage); ``where`` the config key for errors."""
    if not os.path.isfile(path):
        raise ConfigError(where, f"no such file: {path}")
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise ConfigError(where, f"{path}: cannot read: {exc.strerror}") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        utf16 = ", UTF-16: Excel Unicode text" if data[:2] in (b"\xff\xfe", b"\xfe\xff") else ""
        raise ConfigError(where, f"{path}: not UTF-8 text (byte 0x{data[exc.start]:02x} in line {line}{utf16}): "
                                 "save it as UTF-8 (Excel: CSV UTF-8)") from None
    rows, line_no, meta = _rows(path, text, where)
    _check_storage_size(path, meta, rows, where)
    header = rows[0]
    empty = [k for k, h in enumerate(header) if not h]
    if empty:
        raise ConfigError(where, f"{path}: column {empty[0] + 1} of the header line has no name: "
                                 "name it, or remove the column")
    if all(math.isfinite(plain_number(h)) for h in header):
        raise ConfigError(where, f"{path}: its header line (line {line_no[0]}) {','.join(header)!r} is numbers, "
                                 "not column names: a table with no header line would lose its first frame; "
                                 "add a line naming the columns (e.g. time,soleus_r)")
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise ConfigError(where, f"{path}: column {dup[0]!r} appears twice in the header line")
    values = np.empty((len(rows) - 1, len(header)))
    for i, (row, line) in enumerate(zip(rows[1:], line_no[1:]), start=1):
        if len(row) != len(header):
            raise ConfigError(where, f"{path}: data row {i} (line {line}) has {len(row)} fields, the "
                                     f"header {len(header)}")
        for j, field in enumerate(row):
            v = plain_number(field)
            if not math.isfinite(v):
                raise ConfigError(where, f"{path}: data row {i} (line {line}), column {header[j]!r}: "
                                         f"{field!r} is not a finite number")
            values[i - 1, j] = v
    return LoadTable(path, {h: values[:, j].copy() for j, h in enumerate(header)})


def inline_table(value: dict, where: str) -> LoadTable:
    """``table: {time: [...], soleus: [...], ...}`` written in the config: columns of numbers of
    one length."""
    if not isinstance(value, dict) or not value:
        raise ConfigError(where, "expected a mapping of column names to lists of numbers, e.g. "
                                 "{time: [0, 0.01], soleus: [0, 120]}")
    cols, n = {}, None
    for name, col in value.items():
        p = f"{where}.{name}"
        if not isinstance(col, (list, tuple)) or not col:
            raise ConfigError(p, "expected a non-empty list of numbers")
        out = [number(v, f"{p}[{k}]") for k, v in enumerate(col)]   # 1e3: a string to PyYAML
        if n is not None and len(out) != n:
            raise ConfigError(p, f"has {len(out)} values, the first column {n}: every column needs one "
                                 "value per frame")
        n = len(out)
        cols[str(name)] = np.array(out)
    return LoadTable("config", cols)
