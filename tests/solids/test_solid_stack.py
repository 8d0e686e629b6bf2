"""The solid stack's imports (ancf_verify.stack.import_stack) leave the session as found."""
import subprocess
import sys

SCRIPT = """
import signal
from ancf_verify.stack import import_stack
import_stack()
try:
    signal.raise_signal(signal.SIGINT)
except KeyboardInterrupt:
    print("KeyboardInterrupt")
"""


def test_importing_the_solid_stack_keeps_ctrl_c_a_keyboard_interrupt():
    """``import gmsh`` sets SIGINT to SIG_DFL (gmsh.finalize puts it back): after import_stack
    (the solids' session fixture) a Ctrl-C killed the Python process (exit 130, no
    KeyboardInterrupt, no clean-up: an API solve's summary.json left 'running'); a later test
    of the same xdist worker that raised SIGINT ended the worker."""
    out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=300)
    assert (out.returncode, out.stdout.strip()) == (0, "KeyboardInterrupt"), out.stderr[-2000:]



PARTITION = """
import json, sys
sys.path.insert(0, {tests!r})
from helpers import bundle_owners, petsc_init
petsc_init()
from ancf_verify.stack import import_stack
import_stack()                       # dolfinx: Debian's METIS 5.1 loaded RTLD_GLOBAL
print(json.dumps(bundle_owners()))
"""


def test_pymetis_after_the_solid_stack_runs_its_own_metis():
    """dolfinx loads Debian's METIS 5.1 (32-bit indices) RTLD_GLOBAL; pymetis imported after it
    had its exported METIS_* calls taken over and segfaulted on its 64-bit arrays (an xdist worker
    that had run the solid tests crashed in test_fieldsplit's whole-beam partition).
    partition.load_pymetis binds pymetis to its own METIS: exit 0 and this process's owners."""
    import json
    import os
    from helpers import bundle_owners
    tests = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = subprocess.run([sys.executable, "-c", PARTITION.format(tests=tests)],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, (out.returncode, out.stderr[-2000:])
    assert json.loads(out.stdout.strip().splitlines()[-1]) == bundle_owners()
