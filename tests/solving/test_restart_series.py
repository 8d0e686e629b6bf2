"""A run killed (SIGKILL) while it writes a level's ParaView files restarts to a series with
every level's VTU listed once: a level is on disk (results.h5) only with its VTUs."""
import os
import re
import subprocess
import sys

from helpers import CONFIGS, MPI_ENV, ROOT, load_raw, paper_column, solve_cli, write_config

_KILL_AT = """
import os, sys
sys.path.insert(0, {root!r})
import ancf_petsc.io.vtk as vtk
real = vtk.write_vtu
def write(path, *a, **k):
    if path.endswith({name!r}):
        os._exit(137)                         # SIGKILL's effect: no handler, no clean-up
    return real(path, *a, **k)
vtk.write_vtu = write
from apps.ancf_solve import main
sys.exit(main([{cfg!r}, "--output-dir", {out!r}, "--quiet"]))
"""


def _pvd(path):
    with open(path) as fh:
        return re.findall(r'timestep="([^"]+)" part="0" file="([^"]+)"', fh.read())


def test_a_run_killed_while_writing_a_levels_vtu_restarts_to_a_full_series(tmp_path):
    """The paper's column at 2 elements and 6 levels, killed as it wrote contact_0003.vtu
    (surface_0003.vtu written, level 3 already in results.h5), restarted from level 3 and its
    series lacked contact_0003.vtu for good: contact.pvd listed 6 of the 7 states, skipping
    30 N.  Now a level goes into results.h5 only after its VTUs: the restart solves it again."""
    raw = paper_column()
    for b in raw["beams"]:
        b["elements"] = 2
    raw["steps"] = raw["steps"][:6]
    cfg = write_config(dict(raw, output={"dir": str(tmp_path / "unused")}), tmp_path / "c.yaml")
    out = str(tmp_path / "out")
    script = _KILL_AT.format(root=ROOT, name="contact_0003.vtu", cfg=cfg, out=out)
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=ROOT,
                       env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode == 137, p.stderr
    p = solve_cli(cfg, extra=["--restart", out, "--quiet"])
    assert p.returncode == 0, p.stderr
    times = [0.0] + [float(x) for x in raw["steps"]]
    for series in ("surface", "contact"):
        listed = _pvd(os.path.join(out, f"{series}.pvd"))
        assert listed == [(f"{t:.10g}", f"{series}_{k:04d}.vtu") for k, t in enumerate(times)], listed
        assert all(os.path.getsize(os.path.join(out, f)) > 0 for _, f in listed)


def test_a_restart_that_turns_vtk_on_says_which_states_the_series_lacks(tmp_path):
    """The bar solved to 0.2 with output.vtk false and restarted to 0.4 with it on: surface.pvd
    listed 0.3 and 0.4 alone, its rest state and first levels missing without a word.  Now a
    warning (printed, and in summary.json) says which states have no ParaView files."""
    from ancf_petsc.api import solve
    from ancf_petsc.config.parse import parse_config
    raw = dict(load_raw("uniaxial_neohookean.yaml"), steps=[0.1, 0.2, 0.3, 0.4])
    for steps, vtk, restart in (([0.1, 0.2], False, None), (raw["steps"], True, str(tmp_path))):
        spec = parse_config(dict(raw, steps=steps, output={"dir": str(tmp_path), "vtk": vtk}), base_dir=CONFIGS)
        res = solve(spec, log=lambda *_: None, restart=restart)
    assert res.status == "completed" and [f for _, f in _pvd(tmp_path / "surface.pvd")] == \
        ["surface_0003.vtu", "surface_0004.vtu"]
    assert "output.vtk: 3 state(s) before the restart (0-2; 0 is the rest state) have no ParaView files" \
        in " ".join(res.summary["warnings"]), res.summary["warnings"]
