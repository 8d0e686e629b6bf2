"""A unilateral run that fails, solved through the Python API with its result kept to the end of
the script: the complementarity predictor's MUMPS factor (a compact-factor Python preconditioner)
was left to PETSc's final clean-up, after Python had finalised: a SEGV and MPI_ABORT (exit 59)
after a normal end."""
import os
import subprocess
import sys

from helpers import ROOT

SCRIPT = """
import sys
sys.path.insert(0, {tests!r})
from helpers import petsc_init
petsc_init()
from ancf_petsc.api import solve
from ancf_petsc.config.parse import parse_config
H, B = 1e-3, 5e-3
def beam(name, z0, shared):
    pts = [[-B / 2, z0], [B / 2, z0], [B / 2, z0 + H], [-B / 2, z0 + H]]
    names = [name + s for s in ("_bottom", "_right", "_top", "_left")]
    names[shared] = "interface"
    return {{"name": name, "elements": 2, "material": {{"model": "neo-hookean", "mu": 0.5e6, "bulk_modulus": 1e6}},
            "section": {{"shape": "outline", "curves": [{{"name": n, "points": [pts[i], pts[(i + 1) % 4]]}}
                                                     for i, n in enumerate(names)]}}}}
raw = {{"name": "lifted", "units": "SI", "geometry": {{"length": 0.02, "twist_axis": "origin"}},
       "beams": [beam("lower", -H, 2), beam("upper", 0.0, 0)],
       "boundary_conditions": [{{"beam": "lower", "node": 0, "fix": "clamped"}},
                               {{"beam": "upper", "node": 0, "fix": {{"r": "xy"}}}},
                               {{"beam": "upper", "node": "last", "fix": {{"r": "y"}}}}],
       "loads": [{{"beam": "upper", "node": "last", "force": [0.0, 0.0, 1e-4]}}],
       "steps": [1.0], "solver": {{"min_increment": 0.3}},
       "contact": {{"mode": "unilateral", "fade_forces": "variational"}},
       "output": {{"dir": sys.argv[1], "vtk": False}}}}
result = solve(parse_config(raw, base_dir="."), log=lambda *_: None)
print("status", result.status, flush=True)
"""


def test_a_failed_unilateral_run_kept_to_the_end_exits_cleanly(tmp_path):
    """The upper of two stacked strips, held by unilateral contact alone along z and pulled off it,
    has a free rigid motion: the run fails (status 'failed').  The script then ends with exit 0,
    not a SEGV: the stepper's destroy frees the predictor's factor, its Python context first."""
    script = tmp_path / "lifted.py"
    script.write_text(SCRIPT.format(tests=os.path.join(ROOT, "tests")))
    p = subprocess.run([sys.executable, str(script), str(tmp_path / "out")], capture_output=True,
                       text=True, cwd=ROOT, timeout=600, env=dict(os.environ, PYTHONPATH=ROOT))
    assert "status failed" in p.stdout, p.stdout + p.stderr
    assert p.returncode == 0 and "SEGV" not in p.stderr and "MPI_ABORT" not in p.stderr, p.stderr[-2000:]
