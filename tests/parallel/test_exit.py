"""A program on several ranks ends even when the ranks' garbage collectors freed different
parallel PETSc objects (parallel/launch.py ``exit_process``): found as a 2-rank run of a
soft-matrix GOH column that failed and then never exited (PetscFinalize spinning on rank 0, rank 1
waiting in MPI_Finalize).  Here rank 0 alone collects a reference cycle holding a parallel Vec
and Mat; before the collective clean-up the program hung."""
import os
import subprocess

import pytest

from helpers import MPI_ENV, ROOT, VENV_BIN

SCRIPT = """
import gc
import petsc4py
petsc4py.init()
from mpi4py import MPI
from petsc4py import PETSc
from ancf_petsc.parallel.launch import exit_process
gc.disable()
class Holder:
    pass
h = Holder()
h.me = h
h.vec = PETSc.Vec().createMPI(10, comm=PETSc.COMM_WORLD)
h.mat = PETSc.Mat().createAIJ([10, 10], comm=PETSc.COMM_WORLD)
h.mat.setUp()
h.mat.assemble()
del h
if MPI.COMM_WORLD.rank == 0:
    gc.collect()
import os
os.write(1, f"done {MPI.COMM_WORLD.rank}\\n".encode())   # one write: ranks' lines do not interleave
exit_process(7)
"""


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [2, 3])
def test_ranks_that_collected_different_garbage_still_exit(tmp_path, ranks):
    script = tmp_path / "garbage.py"
    script.write_text(SCRIPT)
    p = subprocess.run(["mpirun", "--oversubscribe", "-n", str(ranks), os.path.join(VENV_BIN, "python"), str(script)],
                       capture_output=True, text=True, timeout=120, cwd=ROOT,
                       env=dict(os.environ, PYTHONPATH=ROOT, **MPI_ENV))
    assert p.returncode == 7, p.stdout + p.stderr
    assert sorted(p.stdout.split("\n")[:-1]) == sorted(f"done {r}" for r in range(ranks))
