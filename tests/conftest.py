import os
import sys

# Single-threaded BLAS keeps test timings honest and avoids oversubscription under mpirun.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: takes more than about 3 s (make test-fast skips it)")
    config.addinivalue_line("markers", "mpi: starts mpirun (2 or 3 ranks)")
