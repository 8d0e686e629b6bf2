"""Process environment for the command-line programs, set before MPI and PETSc are imported."""
from __future__ import annotations

import gc
import os
import sys
from typing import NoReturn

#: set by mpirun/mpiexec (Open MPI, MPICH, PMIx) or srun in each process they start
LAUNCHER_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE", "SLURM_STEP_ID")


def launch_rank() -> int:
    """This process's rank as the MPI launcher set it (Open MPI, MPICH, PMIx), read before MPI
    starts: 0 without a launcher.  Errors found before then are printed by rank 0 only."""
    for key in ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"):
        if os.environ.get(key, "").isdigit():
            return int(os.environ[key])
    return 0


def launch_size() -> int:
    """How many processes mpirun/mpiexec started (Open MPI, MPICH), read before MPI starts: 0
    without such a launcher."""
    for key in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE"):
        if os.environ.get(key, "").isdigit():
            return int(os.environ[key])
    return 0


def prepare_environment() -> None:
    """Single-threaded BLAS (small dense kernels: threads only contend with MPI ranks) and, for a
    process started without an MPI launcher (a singleton), Open MPI's ob1 messaging layer and no
    supporting daemon: the default UCX layer probes network devices a singleton never uses, and
    the daemon (orted) is only needed to spawn processes, which ancf-petsc never does (0.34 ->
    0.14 -> 0.04 s to start MPI here).  Values already in the environment win."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    if not any(v in os.environ for v in LAUNCHER_VARIABLES):
        os.environ.setdefault("OMPI_MCA_pml", "ob1")
        os.environ.setdefault("OMPI_MCA_ess_singleton_isolated", "1")


def freeze_imports() -> None:
    """Move every object alive now (the imported modules, classes and functions) out of the
    garbage collector's sight: its full collections then walk only what the run allocates
    (the Achilles column: 35 -> 16 ms of collection)."""
    gc.freeze()


def exit_process(code: int) -> NoReturn:
    """End a command-line program with ``code``: flush the streams, finalize PETSc (-log_view
    and -options_left print here) and MPI, then leave without the interpreter's teardown, whose
    collection and clean-up of every imported library took 80-120 ms of a 1.2 s Achilles column.
    Every file the run wrote is closed by then (results.h5 is opened per level).  Under a
    profiler or tracer (cProfile, coverage) it exits the ordinary way, so that they can write
    their reports."""
    if sys.getprofile() is not None or sys.gettrace() is not None:
        sys.exit(code)
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):        # a closed pipe: nothing more to say anyway
            pass
    petsc = sys.modules.get("petsc4py.PETSc")
    if petsc is not None:
        # parallel PETSc objects that a rank's garbage collector freed (from reference cycles, at
        # times that differ between ranks: rank 0 allocates more) wait in petsc4py's garbage; the
        # collective clean-up destroys them together.  Without it PetscFinalize hung on one rank
        # while the others waited in MPI_Finalize (a 2-rank unilateral GOH column that failed;
        # tests/parallel/test_exit.py makes such garbage on purpose)
        gc.collect()
        petsc.garbage_cleanup()
        petsc._finalize()
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None and mpi.Is_initialized() and not mpi.Is_finalized():
        mpi.Finalize()
    os._exit(code)
