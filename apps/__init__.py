"""Command-line programs over the ancf_petsc library.

Each program is one process per MPI rank doing small dense linear algebra (3 × 3 to 108 × 108
per Gauss or contact point): BLAS threads only compete with the other ranks and with each other.
Unless the user set them, OpenBLAS, OpenMP and MKL run one thread (before numpy is imported).
Measured on this 2-core machine under load: the ψ = 45° column took 12.8 s wall with OpenBLAS's
default threads and 3.1 s with one, the same 1.1 s of CPU.

OpenBLAS chooses its kernels from the CPU's family and model, and a CPU newer than the library
is taken for the oldest x86-64 it knows: Debian 12's OpenBLAS 0.3.21 runs this machine's Xeon
(family 6, model 207) on its SSE3 "Prescott" kernels.  Unless the user set OPENBLAS_CORETYPE, it
is chosen here from the instruction sets the CPU reports (``openblas_core``): the walking stride
took 4.89 s wall instead of 5.89 (farm-bench, 7 pairs, A/B 0.835).

A stdout or stderr closed at start (``2>&-`` in a batch script) is /dev/null for the program
(``interrupt.hold_standard_streams``): ancf-solve exited 1 there, also after a completed run."""
import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

from ancf_petsc.solving.interrupt import hold_standard_streams  # noqa: E402  (no numpy)

hold_standard_streams()                 # ancf-sweep S.yaml 2>&- : exit codes as with a stderr


def openblas_core(flags: set[str]) -> str | None:
    """OpenBLAS's kernel family for a CPU with these /proc/cpuinfo ``flags``: SKYLAKEX with
    AVX-512 (F, CD, BW, DQ, VL), HASWELL with AVX2 and FMA, None otherwise (OpenBLAS's choice)."""
    if {"avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"} <= flags:
        return "SKYLAKEX"
    if {"avx2", "fma"} <= flags:
        return "HASWELL"
    return None


def cpu_flags(path: str = "/proc/cpuinfo") -> set[str]:
    """The first processor's flags (empty where there is no /proc/cpuinfo)."""
    try:
        with open(path) as fh:
            for line in fh:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


_core = openblas_core(cpu_flags())
if _core is not None:
    os.environ.setdefault("OPENBLAS_CORETYPE", _core)
