import os
import subprocess
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# the programs' process environment, before numpy is imported (apps/__init__.py): single-threaded
# BLAS (honest timings, no oversubscription under mpirun) and OpenBLAS's kernels for this CPU
import apps  # noqa: E402,F401
from helpers import mpirun_ranks  # noqa: E402

_POPEN_INIT = subprocess.Popen.__init__


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: takes more than about 3 s (make test-fast skips it)")
    config.addinivalue_line("markers", "mpi: starts mpirun (2 or 3 ranks)")


@pytest.fixture(autouse=True)
def _mpirun_only_in_mpi_tests(request, monkeypatch):
    """A test that starts mpirun with 2 or more ranks (from its own process, through subprocess)
    carries the ``mpi`` mark: ``make test`` runs the other tests on parallel workers and the marked
    ones one at a time (Makefile)."""
    if request.node.get_closest_marker("mpi") is not None:
        return

    def guarded(self, args, *rest, **kwargs):
        if mpirun_ranks(args) > 1:
            raise AssertionError(f"{request.node.nodeid} starts `{' '.join(map(str, args[:4]))} ...`:"
                                 " mark it @pytest.mark.mpi")
        _POPEN_INIT(self, args, *rest, **kwargs)
    monkeypatch.setattr(subprocess.Popen, "__init__", guarded)
