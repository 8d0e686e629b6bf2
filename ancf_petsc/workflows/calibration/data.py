"""Measured data: CSV files of load level → measured value (and its uncertainty), each read as one
quantity of the model (``quantities.py``).

    data:
      - file: ../data/paper_table1_elongation.csv   # relative to the fit file; '#' lines are comments
        load: load_N            # column of load levels
        load_scale: 1.0         # load column x this = the model's load factor (default 1)
        value: psi0_mm          # column of measured values
        value_scale: 1e-3       # value column x this = SI (mm -> m)
        sigma: 2.9e-7           # the uncertainty: an SI number, or
        # sigma_column: sd_mm   #   a column (in the value column's unit), or
        # relative_sigma: 0.01  #   a fraction of |value|
        quantity: elongation    # a name of quantities.QUANTITIES, with its own keys:
        probe: soleus
"""
from __future__ import annotations

import csv
import io
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...config.values import plain_number
from .errors import CalibrationError, expect, number
from .quantities import QUANTITIES

DATA_KEYS = ("file", "name", "load", "load_scale", "value", "value_scale", "sigma", "sigma_column",
             "relative_sigma", "quantity")


@dataclass
class DataSet:
    """One data file read as one quantity: levels (load factors), values and sigmas in SI."""
    name: str
    file: str
    quantity: str
    options: dict
    levels: np.ndarray
    values: np.ndarray
    sigmas: np.ndarray
    load_column: str = ""
    value_column: str = ""
    value_scale: float = 1.0
    extra_levels: list = field(default_factory=list)     # levels the quantity needs besides these

    @property
    def all_levels(self) -> list[float]:
        return list(self.levels) + list(self.extra_levels)


@dataclass
class Table:
    """A CSV file's columns (header name → cells) and the file line of each data row."""
    path: str
    columns: dict[str, list[str]]
    lines: list[int]


def read_table(path: str, where: str) -> Table:
    """Columns of a CSV file with a header line ('#' lines are comments; a UTF-8 byte-order mark,
    as spreadsheets write it, is dropped)."""
    expect(os.path.isfile(path), where, f"no such file: {path}")
    try:
        with open(path, encoding="utf-8-sig") as fh:
            lines = [(k, line) for k, line in enumerate(fh, start=1) if not line.lstrip().startswith("#")]
    except (OSError, UnicodeDecodeError) as exc:
        raise CalibrationError(where, f"{path}: cannot read it as text ({exc.__class__.__name__})") from None
    rows = [(k, r) for k, line in lines for r in csv.reader(io.StringIO(line)) if any(c.strip() for c in r)]
    expect(len(rows) >= 2, where, f"{path}: expected a header line and at least one row")
    header = [h.strip() for h in rows[0][1]]
    dup = next((h for h in header if header.count(h) > 1), None)
    expect(dup is None, where, f"{path}: column {dup!r} appears twice in the header line: rename one")
    expect(not all(np.isfinite(plain_number(h)) for h in header), where,
           f"{path}: its header line (line {rows[0][0]}) {','.join(header)!r} is numbers, not column names: "
           "a table with no header line would lose its first row; add a line naming the columns")
    cols = {h: [] for h in header}
    for k, row in rows[1:]:
        expect(len(row) == len(header), where, f"{path}: line {k} has {len(row)} fields, "
                                               f"the header {len(header)}")
        for h, c in zip(header, row):
            cols[h].append(c.strip())
    return Table(path, cols, [k for k, _ in rows[1:]])


def _column(table: Table, name: Any, where: str) -> np.ndarray:
    """A column as finite numbers; an empty, non-numeric, NaN or infinite cell is refused with its
    line and column."""
    cols, base = table.columns, os.path.basename(table.path)
    expect(isinstance(name, str) or not isinstance(name, (int, float)) or isinstance(name, bool), where,
           f"expected a column name; got the number {name!r}: a column named by digits is quoted in "
           f"YAML ('{name}')")
    expect(isinstance(name, str) and name in cols, where,
           f"no column {name!r} in {base} (columns: {', '.join(cols)})")
    out = []
    for line, cell in zip(table.lines, cols[name]):
        value = plain_number(cell)             # float() without '1_0' = 10
        expect(np.isfinite(value), where,
               f"{base}, line {line}, column {name!r}: {cell!r} is not a finite number; "
               "give a measured value there or remove the row")
        out.append(value)
    return np.array(out)


def _sigmas(item: dict, where: str, table: Table, values: np.ndarray, scale: float) -> np.ndarray:
    given = [k for k in ("sigma", "sigma_column", "relative_sigma") if k in item]
    expect(len(given) == 1, where, "give one uncertainty: sigma (SI), sigma_column (a column in "
                                   "the value's unit) or relative_sigma (a fraction of |value|)")
    key = given[0]
    if key == "sigma":
        s = np.full(len(values), number(item["sigma"], f"{where}.sigma", positive=True))
    elif key == "sigma_column":
        s = _column(table, item["sigma_column"], f"{where}.sigma_column") * abs(scale)
    else:
        s = number(item["relative_sigma"], f"{where}.relative_sigma", positive=True) * np.abs(values)
    expect(bool(np.all(s > 0)), f"{where}.{key}", "every uncertainty must be > 0")
    return s


def _data_set(item: Any, i: int, here: str, raw: dict) -> DataSet:
    where = f"data[{i}]"
    expect(isinstance(item, dict), where, "expected a mapping with file, load, value, sigma and quantity")
    for k in item:
        if k not in DATA_KEYS and k not in {x for q in QUANTITIES.values() for x in q.keys}:
            raise CalibrationError(f"{where}.{k}", "unknown key; allowed: " + ", ".join(DATA_KEYS)
                                   + " and the quantity's own keys")
    expect(isinstance(item.get("file"), str), f"{where}.file", "missing: the CSV file (relative to the fit file)")
    path = os.path.normpath(os.path.join(here, item["file"]))
    table = read_table(path, f"{where}.file")
    load_scale = number(item.get("load_scale", 1.0), f"{where}.load_scale", positive=True)
    value_scale = number(item.get("value_scale", 1.0), f"{where}.value_scale")
    expect(value_scale > 0, f"{where}.value_scale", f"must be > 0 (the value column's unit in SI, "
           f"e.g. 1e-3 for mm); got {value_scale:g}; for data of the opposite sign negate the column")
    levels = _column(table, item.get("load"), f"{where}.load") * load_scale
    low = [line for line, lv in zip(table.lines, levels) if lv <= 0]
    expect(not low, f"{where}.load", f"{os.path.basename(path)}, line {low[0] if low else 0}: every "
           "load level must be > 0 (0 is the reference)")
    values = _column(table, item.get("value"), f"{where}.value") * value_scale
    sigmas = _sigmas(item, where, table, values, value_scale)
    qname = item.get("quantity")
    expect(qname in QUANTITIES, f"{where}.quantity",
           f"must be one of {', '.join(QUANTITIES)}; got {qname!r}")
    q = QUANTITIES[qname]
    for k in item:
        expect(k in DATA_KEYS or k in q.keys, f"{where}.{k}",
               f"not a key of quantity {qname} (its keys: {', '.join(q.keys) or 'none'})")
    options = q.check({k: item[k] for k in q.keys if k in item}, where, raw, levels, load_scale)
    name = item.get("name", f"{qname}_{i}")
    expect(isinstance(name, str) and name, f"{where}.name", "expected a name")
    order = np.argsort(levels, kind="stable")     # repeated trials at a level: one residual each
    return DataSet(name, path, qname, options, levels[order], values[order], sigmas[order],
                   str(item["load"]), str(item["value"]), value_scale, q.extra_levels(options, levels))


def parse_data(items: Any, here: str, raw: dict) -> list[DataSet]:
    expect(isinstance(items, list) and items, "data",
           "expected a list of data sets, e.g. [{file: x.csv, load: load_N, value: u_mm, ...}]")
    out = [_data_set(item, i, here, raw) for i, item in enumerate(items)]
    names = [d.name for d in out]
    for i, n in enumerate(names):
        expect(names.index(n) == i, f"data[{i}].name", f"{n!r} names two data sets")
    return out
