"""Memory of many solves in one process (issue 15): a study must not grow with the models it solves.

    python scripts/bench_memory.py                    # 50 Achilles models (contact), 1 rank
    python scripts/bench_memory.py --models 20 --config configs/bundle_hex7.yaml

Solves the same model ``--models`` times in this process, each time the way a study does
(``workflows.study.solve_raw``: parse, build, solve, write), and prints after every solve the
resident memory (VmRSS) and PETSc's own count of the bytes it holds (``PetscMallocGetCurrentUsage``,
with ``-malloc_debug``: every PETSc object not destroyed shows up there).  At the end it
fits the growth per model over the second half of the runs (the first ones warm caches: imports,
MUMPS's and the BLAS's buffers) and prints it against the memory of one model.
"""
from __future__ import annotations

import argparse
import gc
import os
import sys
import tempfile
import time

import numpy as np
import yaml

from ancf_verify import paths

ROOT = paths.ROOT


def rss_mb() -> float:
    """Resident set size of this process [MB]."""
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def petsc_malloc_mb() -> float:
    """Bytes PETSc's allocator holds now [MB] (PetscMallocGetCurrentUsage)."""
    import ctypes

    import petsc4py
    base = os.path.join(petsc4py.get_config()["PETSC_DIR"], "lib")
    name = sorted((f for f in os.listdir(base) if f.startswith("libpetsc") and ".so" in f), key=len)[0]
    lib = ctypes.CDLL(os.path.join(base, name), mode=os.RTLD_NOLOAD | os.RTLD_LAZY)
    value = ctypes.c_double(0.0)
    lib.PetscMallocGetCurrentUsage(ctypes.byref(value))
    return value.value / 2**20


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", type=int, default=50)
    ap.add_argument("--config", default=os.path.join(ROOT, "configs", "achilles_type3_psi45.yaml"))
    ap.add_argument("--elements", type=int, default=2, help="elements per beam (default 2)")
    args = ap.parse_args()

    from mpi4py import MPI  # noqa: F401
    import petsc4py
    petsc4py.init([sys.argv[0], "-malloc_debug"])
    try:
        from ancf_petsc.workflows.study import solve_raw
    except ImportError:                           # the layout before issue 15 (--baseline runs)
        from ancf_petsc.study import solve_raw

    with open(args.config) as fh:
        raw = yaml.safe_load(fh)
    for b in raw["beams"]:
        b["elements"] = args.elements
    base = os.path.dirname(os.path.abspath(args.config))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.models):
            t0 = time.perf_counter()
            res, _ = solve_raw(raw, base, os.path.join(tmp, f"run{k}"))
            gc.collect()
            rows.append((k + 1, rss_mb(), petsc_malloc_mb(), time.perf_counter() - t0, res.status))
            print(f"model {k + 1:3d}  {res.status:9s}  RSS {rows[-1][1]:8.1f} MB  PETSc malloc "
                  f"{rows[-1][2]:8.2f} MB  {rows[-1][3]:.2f} s", flush=True)
    n = np.array([r[0] for r in rows], dtype=float)
    half = n >= max(2, args.models // 2)
    slope_rss = np.polyfit(n[half], [r[1] for r in rows if r[0] >= max(2, args.models // 2)], 1)[0]
    slope_petsc = np.polyfit(n[half], [r[2] for r in rows if r[0] >= max(2, args.models // 2)], 1)[0]
    first = rows[0][1]
    print(f"\ngrowth per model over models {int(n[half][0])}..{args.models}: RSS {1024 * slope_rss:+.1f} KB, "
          f"PETSc malloc {1024 * slope_petsc:+.2f} KB; after the first model RSS {first:.1f} MB, "
          f"PETSc malloc {rows[0][2]:.2f} MB; after the last PETSc malloc {rows[-1][2]:.2f} MB")
    return 0
