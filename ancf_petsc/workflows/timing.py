"""Wall-clock timing for the benchmark scripts and studies (never asserted by tests)."""
from __future__ import annotations

import time


def best_times(fns, repeat: int) -> list[float]:
    """Shortest of ``repeat`` timed calls of each function, the calls interleaved (each called
    once first, untimed: caches and lazy set-up out of the way)."""
    best = [float("inf")] * len(fns)
    for fn in fns:
        fn()
    for _ in range(repeat):
        for k, fn in enumerate(fns):
            t = time.perf_counter()
            fn()
            best[k] = min(best[k], time.perf_counter() - t)
    return best
