"""``make test`` runs the tests without the ``mpi`` mark on parallel pytest-xdist workers and the
marked ones one at a time (Makefile), so a test that starts mpirun with 2 or more ranks must carry
the mark: conftest.py refuses the launch in an unmarked test.  Checked here: the rank count read
from a command line, and the refusal (no process is started)."""
import subprocess

import pytest

from helpers import mpirun_ranks


@pytest.mark.parametrize("cmd,ranks", [
    (["mpirun", "--oversubscribe", "-n", "3", "ancf-solve", "c.yaml"], 3),
    (["/usr/bin/mpiexec", "-np", "2", "python"], 2),
    (["mpirun", "python"], 2),
    (["mpirun", "-n", "1", "ancf-solve"], 1),
    (["ancf-solve", "-n", "2"], 1),
    ("mpirun -n 2 ancf-solve", 1),
])
def test_the_rank_count_of_a_command_line(cmd, ranks):
    assert mpirun_ranks(cmd) == ranks


def test_an_unmarked_test_may_not_start_mpirun_with_two_ranks():
    with pytest.raises(AssertionError, match="mark it @pytest.mark.mpi"):
        subprocess.run(["mpirun", "-n", "2", "true"], capture_output=True)
    assert subprocess.run(["true"]).returncode == 0          # any other command starts
