"""Process environment for the command-line programs, set before MPI and PETSc are imported."""
from __future__ import annotations

import os

#: set by mpirun/mpiexec (Open MPI, MPICH, PMIx) or srun in each process they start
LAUNCHER_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE", "SLURM_STEP_ID")


def prepare_environment() -> None:
    """Single-threaded BLAS (small dense kernels: threads only contend with MPI ranks) and, for a
    process started without an MPI launcher (a singleton), Open MPI's ob1 messaging layer: the
    default UCX layer probes network devices a singleton never uses (0.33 -> 0.14 s to start
    MPI here).  Values already in the environment win."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    if not any(v in os.environ for v in LAUNCHER_VARIABLES):
        os.environ.setdefault("OMPI_MCA_pml", "ob1")
