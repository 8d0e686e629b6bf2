"""PETSc objects of a solve are destroyed when it ends: many models in one process (a study, an
accuracy ladder) do not grow PETSc's memory (issue 15; scripts/bench_memory.py charts it)."""
import os
import re
import subprocess
import sys

from helpers import MPI_ENV, ROOT


def test_many_solves_in_one_process_keep_petsc_memory_flat():
    p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "bench_memory.py"), "--models", "5",
                        "--elements", "1"], capture_output=True, text=True, timeout=600,
                       env=dict(os.environ, **MPI_ENV), cwd=ROOT)
    assert p.returncode == 0, p.stdout + p.stderr
    held = [float(x) for x in re.findall(r"PETSc malloc +([\d.]+) MB", p.stdout)]
    statuses = re.findall(r"model +\d+ +(\w+)", p.stdout)
    assert statuses == ["completed"] * 5, p.stdout
    # before objects were destroyed, every Achilles model left ~1.1 MB behind in PETSc
    assert held[0] > 0.0 and max(held) - held[1] < 0.01, p.stdout
