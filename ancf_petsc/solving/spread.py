"""Independent work items (a calibration's samples) spread over the MPI ranks of the program.

Rank r does items r, r + size, r + 2 size, ... one after another (each on its own communicator of
one rank, ``SampleSolver``), then every rank gets every result (an allgather).  A rank never
raises alone: a signal (SIGINT/SIGTERM, ``interrupt.py``) stops its remaining items and is
reported to all; an exception in one rank's item is re-raised on every rank after the gather,
naming the rank, with its traceback text.
"""
from __future__ import annotations

import traceback
from dataclasses import dataclass
from typing import Any, Callable

from mpi4py import MPI

from . import interrupt
from .interrupt import RunInterrupted


@dataclass
class Spread:
    """Every item's result in order (None for items not done) and the signal that stopped any
    rank (0: none)."""
    results: list
    signum: int = 0


class RankFailure(RuntimeError):
    """An item raised on some rank: raised on every rank, with that rank's traceback."""


def world() -> tuple[int, int]:
    """(rank, size) of the program's MPI world."""
    comm = MPI.COMM_WORLD
    return comm.Get_rank(), comm.Get_size()


def spread(items: list, work: Callable[[Any], Any]) -> Spread:
    """``work(item)`` for every item, the items dealt round-robin over the ranks (collective)."""
    comm = MPI.COMM_WORLD
    rank, size = comm.Get_rank(), comm.Get_size()
    done: dict[int, Any] = {}
    signum, error = 0, None
    for i in range(rank, len(items), size):
        if interrupt.pending():
            signum = interrupt.pending()
            break
        try:
            done[i] = work(items[i])
        except RunInterrupted as exc:
            signum = exc.signum
            break
        except Exception:                      # a bug: reported on every rank below
            error = traceback.format_exc()
            break
    gathered = comm.allgather((done, signum, error)) if size > 1 else [(done, signum, error)]
    failed = [(r, e) for r, (_, _, e) in enumerate(gathered) if e]
    if failed:
        r, text = failed[0]
        raise RankFailure(f"rank {r} of {size} failed in a calibration sample:\n{text}")
    results: list = [None] * len(items)
    for part, _, _ in gathered:
        for i, value in part.items():
            results[i] = value
    return Spread(results, max(s for _, s, _ in gathered))


def agree(value: Any) -> Any:
    """Rank 0's ``value`` on every rank (a broadcast; collective)."""
    comm = MPI.COMM_WORLD
    return comm.bcast(value, root=0) if comm.Get_size() > 1 else value
