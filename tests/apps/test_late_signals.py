"""A SIGTERM or SIGINT that reaches ancf-solve after its run has ended (a time limit as the last
level is written, while PETSc and MPI finalize) keeps the run's exit code and prints nothing."""
import json
import os
import signal
import subprocess
import sys

import pytest

from helpers import CONFIGS, MPI_ENV, ROOT

_LATE = """
import os, sys
import ancf_petsc.parallel.launch as launch
real = launch.exit_process
def late(code):
    os.kill(os.getpid(), {sig})           # the signal arrives as the process finalizes
    real(code)
launch.exit_process = late
from apps.ancf_solve import cli
sys.argv = ["ancf-solve", {cfg!r}, "--output-dir", {out!r}, "--quiet"]
cli()
"""


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_after_the_run_has_ended_keeps_its_exit_code(tmp_path, sig):
    """The bar's run completed (summary.json 'completed') and its process then ended killed by
    SIGTERM (exit 143, 'Terminated') or with a KeyboardInterrupt traceback (exit 130): main()
    had put back the default handlers before PETSc's and MPI's finalize, so a sweep recorded
    the completed run as interrupted.  Now exit 0, stderr empty."""
    out = str(tmp_path / "out")
    script = _LATE.format(sig=int(sig), cfg=os.path.join(CONFIGS, "uniaxial_neohookean.yaml"), out=out)
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=ROOT,
                       env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    with open(os.path.join(out, "summary.json")) as fh:
        assert json.load(fh)["status"] == "completed"
    assert (p.returncode, p.stderr) == (0, ""), (p.returncode, p.stderr)
