"""Command-line programs over the ancf_petsc library.

Each program is one process per MPI rank doing small dense linear algebra (3 × 3 to 108 × 108
per Gauss or contact point): BLAS threads only compete with the other ranks and with each other.
Unless the user set them, OpenBLAS, OpenMP and MKL run one thread (before numpy is imported).
Measured on this 2-core machine under load: the ψ = 45° column took 12.8 s wall with OpenBLAS's
default threads and 3.1 s with one, the same 1.1 s of CPU."""
import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")
