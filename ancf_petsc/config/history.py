"""``history:`` of a config: loads that follow their own curves over frames (a gait cycle).

    history:
      file: data/stride_walking.sto    # CSV or OpenSim storage (.sto/.mot), relative to the config;
      # table: {time: [...], soleus: [...]}   or the columns written inline
      time: time                       # the clock column [s] (default: time)
      scale: 1.0                       # multiplies every column a load reads (e.g. 1000 for kN);
                                       # a prescribed displacement's column is read as written [m]
    loads:
      - {beam: soleus, node: last, traction_force: [1, 0, 0], column: soleus_r}

Frame k (row k of the table, k = 1 … N) is solved at load factor λ = k, each frame a quasi-static
equilibrium continued from the one before (friction and contact history carried, adaptive
sub-steps in between): a load with ``column: c`` is its config value times c_k · scale at frame
k, piecewise linear in λ between frames and rising from rest (λ = 0, every load zero) to frame 1.
Every frame is a reported step; a load follows a column or its own ``curve`` over frame numbers
(λ = frame, e.g. a pressing load held over the frames); one with neither is refused, as it
would grow with the frame number.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from .load_tables import LoadTable, inline_table, read_load_table
from .values import ConfigError, mapping, number, shown, string

HISTORY_KEYS = ("file", "table", "time", "scale")


@dataclass
class HistorySpec:
    """Frames of a load history: their times [s] and the columns loads may follow (scaled)."""
    source: str
    time_column: str
    times: np.ndarray
    columns: dict[str, np.ndarray]
    scale: float = 1.0

    @property
    def n_frames(self) -> int:
        return len(self.times)

    def frame_of(self, load_factor: float) -> int:
        """The frame (1 … N) a reported load factor is."""
        return int(round(load_factor))

    def time_of(self, load_factor: float) -> float:
        """The time [s] of the frame a load factor reports (between frames: interpolated)."""
        return float(np.interp(load_factor, np.arange(1, self.n_frames + 1), self.times))

    def curve(self, column: str, path: str, scaled: bool = True) -> tuple:
        """The multiplier curve ((λ, m), ...) of a load that reads ``column``: 0 at rest, then
        the column's value × scale at every frame (``scaled`` False: × 1, a displacement's)."""
        have = ", ".join(c for c in self.columns if c != self.time_column)
        if column not in self.columns:
            raise ConfigError(path, f"no column {column!r} in {self.source} (columns: {have})")
        if column == self.time_column:
            raise ConfigError(path, f"{column!r} is the history's clock (history.time, seconds), not "
                                    f"a load: name a load column ({have})")
        values = (self.scale if scaled else 1.0) * self.columns[column]
        return ((0.0, 0.0),) + tuple((float(k + 1), float(v)) for k, v in enumerate(values))


def parse_history(value, base_dir: str) -> HistorySpec:
    """Validate ``history`` and read its table."""
    p = "history"
    mapping(value, p, optional=HISTORY_KEYS)
    if ("file" in value) == ("table" in value):
        raise ConfigError(p, "give the load table as file (CSV or OpenSim .sto/.mot) or as table "
                             "(columns written inline), one of the two")
    if "file" in value:
        name = string(value["file"], f"{p}.file")
        path = name if os.path.isabs(name) else os.path.normpath(os.path.join(base_dir, name))
        table: LoadTable = read_load_table(path, f"{p}.file")
        source = os.path.basename(path)
    else:
        table = inline_table(value["table"], f"{p}.table")
        source = "history.table"
    time_column = column_name(value.get("time", "time"), f"{p}.time")
    if time_column not in table.columns:
        raise ConfigError(f"{p}.time", f"no column {time_column!r} in {source} (columns: "
                                       f"{', '.join(table.columns)}); name the clock column")
    times = table.columns[time_column]
    if np.any(np.diff(times) <= 0.0):
        k = int(np.flatnonzero(np.diff(times) <= 0.0)[0])
        raise ConfigError(f"{p}.time", f"the times of {source} must increase from frame to frame; "
                                       f"frame {k + 2} ({times[k + 1]:g} s) follows {times[k]:g} s")
    scale = number(value.get("scale", 1.0), f"{p}.scale", positive=True,
                   hint=" (multiplies every load column, e.g. 1000 for a table in kN; not a displacement's)")
    return HistorySpec(source, time_column, times.copy(), dict(table.columns), scale)


def check_frames(steps, history: HistorySpec) -> list[float]:
    """The load factors of a history spec whose ``steps`` were edited through the Python API:
    the frames 1, 2, … (its first frames, or all).  Decreasing steps stopped the stepping with an
    UnboundLocalError; 2.5 was reported as frame 2 and 7 of a 6-frame table as frame 7, the
    loads held at frame 6's."""
    n = history.n_frames
    if not isinstance(steps, (list, tuple)) or not 1 <= len(steps) <= n or \
            any(isinstance(s, bool) or s != k for k, s in enumerate(steps, start=1)):
        raise ConfigError("steps", f"with history every frame of {history.source} is a reported step "
                                   f"(load factor k = frame k): give 1, 2, … up to at most {n} (the first "
                                   f"frames), or leave the steps as parsed; got {shown(steps)}")
    return [float(s) for s in steps]


def check_scale(spec) -> None:
    """A history ``scale`` that no load reads (every load on its own curve, or only a prescribed
    displacement on a column: read as written, in metres) was ignored without a word."""
    h = spec.history
    if h is not None and h.scale != 1.0 and not any(ld.column is not None for ld in spec.loads):
        raise ConfigError("history.scale", "multiplies the columns loads read, and no load reads one (a "
                                           "prescribed displacement's column is read as written, in metres; "
                                           f"a curve as written): remove it; got {shown(h.scale)}")


def check_history_edits(spec) -> None:
    """A history edited through the Python API after parsing (``spec.history.scale = 1000``, a
    column changed) was ignored: the loads' curves were made from the table as parsed, and the
    run solved those; so was a history removed (``spec.history = None``: the stride again, frame for
    frame).  Raises ConfigError naming the first load or support whose column now gives another
    curve or none."""
    items = [(ld, True) for ld in spec.loads] + [(bc, False) for bc in spec.boundary_conditions]
    for item, scaled in items:
        if item.column is None:
            continue
        if spec.history is None:        # removed: its curves stayed, and the run was the history's
            raise ConfigError("history", f"removed after parsing, but the curve of {item.path} was made from "
                                         f"its column {item.column!r} and would still be followed; remove the "
                                         "history and the loads' columns in the config and parse it again")
        if item.curve != spec.history.curve(item.column, f"{item.path}.column", scaled):
            raise ConfigError("history", f"edited after parsing (its scale or table): the curve of {item.path} "
                                         f"(column {item.column!r}) was made from the table as parsed, and the "
                                         "edit would be ignored; edit the config's history and parse it again")


def history_curve(item: dict, history: HistorySpec | None, path: str, curve, scaled: bool = True) -> tuple | None:
    """The curve of a load or prescribed displacement (``item`` its config mapping): its
    ``column`` of the history, its own ``curve``, or None (proportional to λ).  ``scaled``:
    history.scale multiplies the column (a load's: forces in kN; not a displacement's, which
    the kN scale made 1000 times too long)."""
    if "column" in item:
        if history is None:
            raise ConfigError(f"{path}.column", "a column names a load table's column: add "
                                                "history: {file: ...} (docs/gait.md), or remove it")
        if "curve" in item:
            raise ConfigError(path, "give column (a history's) or curve, not both")
        return history.curve(column_name(item["column"], f"{path}.column"), f"{path}.column", scaled)
    if history is not None and curve is None:
        raise ConfigError(path, f"with history every load follows a column of {history.source} "
                                f"(e.g. column: {shown(next(iter(_load_columns(history)), 'name'))}) or its own "
                                "curve over frame numbers; one with neither would grow with the frame number")
    return curve


def column_name(value, path: str) -> str:
    """A column's name; a number (YAML reads column: 1 as one) is refused with the quoting to write."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        raise ConfigError(path, f"expected a column name; got the number {shown(value)}: a column "
                                f"named by digits is quoted in YAML (column: \"{shown(value)}\")")
    return string(value, path)


def _load_columns(history: HistorySpec) -> list[str]:
    return [c for c in history.columns if c != history.time_column]
