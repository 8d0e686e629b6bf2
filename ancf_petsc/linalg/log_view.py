"""Read PETSc's ``-log_view`` text output: per-event times and MPI traffic, summed over stages.

Used by the benchmark scripts (scripts/bench_scaling.py, bench_growth.py, project_scaling.py).  Times are
PETSc's "Max" column (the slowest rank); messages, lengths and reductions are its global counts.
"""
from __future__ import annotations

import re

_EVENT = re.compile(r"^(?P<name>\S.*?)\s+(?P<count>\d+)\s+[\d.]+\s+(?P<time>[\d.e+-]+)\s+[\d.]+\s+"
                    r"[\d.e+-]+\s+[\d.]+\s+(?P<mess>[\d.e+-]+)\s+(?P<len>[\d.e+-]+)\s+(?P<red>[\d.e+-]+)\s")
_TOTALS = (("messages", r"MPI Msg Count:\s+\S+\s+\S+\s+\S+\s+(\S+)"),
           ("bytes", r"MPI Msg Len \(bytes\):\s+\S+\s+\S+\s+\S+\s+(\S+)"),
           ("reductions", r"MPI Reductions:\s+(\S+)"))


def read_log_view(path: str) -> dict:
    """{"total": {messages, bytes, reductions}, "events": {name: {count, time, messages, bytes,
    reductions}}}; an event's entries in several stages are added up (bytes = messages × average
    length)."""
    text = open(path).read()
    total = {}
    for key, pattern in _TOTALS:
        m = re.search(pattern, text)
        total[key] = float(m.group(1)) if m else 0.0
    events: dict[str, dict] = {}
    body = text.split("Event                Count", 1)[-1].split("Object Type", 1)[0]
    for line in body.splitlines():
        m = _EVENT.match(line)
        if not m or m.group("name").startswith(("---", "Event", "Memory")):
            continue
        e = events.setdefault(m.group("name").strip(), dict.fromkeys(
            ("count", "time", "messages", "bytes", "reductions"), 0.0))
        mess = float(m.group("mess"))
        e["count"] += int(m.group("count"))
        e["time"] += float(m.group("time"))
        e["messages"] += mess
        e["bytes"] += mess * float(m.group("len"))
        e["reductions"] += float(m.group("red"))
    return {"total": total, "events": events}
