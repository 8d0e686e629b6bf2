import faulthandler
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile

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
    if not hasattr(config, "workerinput"):        # the controller (or a run without workers)
        os.environ["ANCF_TEST_FAULTS"] = tempfile.mkdtemp(prefix="ancf-test-faults-")


def pytest_sessionstart(session):
    """A parallel worker writes a fatal signal's traceback (faulthandler) to a file of its own:
    pytest-xdist shows a crashed worker's stderr whole, where Python's list of extension modules
    pushes the traceback out of a CI log's tail; the controller prints it last (below)."""
    worker = getattr(session.config, "workerinput", {}).get("workerid")
    if worker is not None and os.path.isdir(os.environ.get("ANCF_TEST_FAULTS", "")):
        path = os.path.join(os.environ["ANCF_TEST_FAULTS"], f"{worker}-{os.getpid()}.log")
        session.config._ancf_fault_file = open(path, "w")
        faulthandler.enable(file=session.config._ancf_fault_file, all_threads=True)


_RUNNER_FRAME = re.compile(r"/(_pytest|pluggy|xdist|execnet)/")


def pytest_terminal_summary(terminalreporter, config):
    """The tracebacks of crashed workers, without the list of extension modules."""
    where = os.environ.get("ANCF_TEST_FAULTS", "")
    if hasattr(config, "workerinput") or not os.path.isdir(where):
        return
    for path in sorted(glob.glob(os.path.join(where, "*.log"))):
        with open(path, errors="replace") as fh:
            lines = [ln.rstrip() for ln in fh if not ln.startswith("Extension modules")
                     and not _RUNNER_FRAME.search(ln)]
        if any(lines):
            terminalreporter.section(f"fatal signal in worker {os.path.basename(path)[:-4]}", sep="-")
            for ln in lines:
                terminalreporter.line(ln)
    shutil.rmtree(where, ignore_errors=True)


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
