"""The command-line programs run one BLAS thread per process unless the user says otherwise
(apps/__init__.py): OpenBLAS's default threads made the ψ = 45° column 4x slower in wall time on
this loaded 2-core machine."""
import os
import subprocess
import sys

from helpers import ROOT


def _threads(env):
    code = "import apps, os; print(os.environ['OPENBLAS_NUM_THREADS'], os.environ['OMP_NUM_THREADS'])"
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT, capture_output=True, text=True)
    return out.stdout.split()


def test_one_blas_thread_unless_set():
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    assert _threads(env) == ["1", "1"]
    assert _threads(dict(env, OPENBLAS_NUM_THREADS="4")) == ["4", "1"]
