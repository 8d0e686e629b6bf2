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
