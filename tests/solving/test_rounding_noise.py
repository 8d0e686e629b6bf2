"""A level that fails because |F| sits at the residual's rounding, above the run's own absolute
tolerance (continuity.rounding_noise): an elastic interface of k_t = 1e12 Pa/m between bars of
E = 1 MPa stalls at |F| ~1e-10 N while the tolerance, set from the rounding at rest, is 3e-12 N.
It was reported as "-snes_atol 3.1e-12, given in the run's options" (it was not given), as "a
discontinuity of the discrete model (please report it)" and as a critical point at rest."""
import re

from helpers import load_raw, read_summary, solve_cli, write_config


def _sandwich(tmp_path, name):
    raw = load_raw("shear_lag_sandwich.yaml")
    for b in raw["beams"]:
        b["elements"] = 4
    raw["contact"]["tangential"]["stiffness"] = 1.0e12
    raw["solver"] = {"max_cutbacks": 1}
    raw["output"] = {"dir": str(tmp_path / name), "vtk": False}
    return write_config(raw, tmp_path / f"{name}.yaml")


def test_a_residual_at_its_rounding_names_the_tolerance_to_give(tmp_path):
    p = solve_cli(_sandwich(tmp_path, "stiff"))
    assert p.returncode == 3, p.stdout + p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert "|F| is at the residual's rounding there" in line, line
    for wrong in ("given in the run's options", "discontinuity", "critical point", "limit or bifurcation"):
        assert wrong not in line, line
    assert read_summary(tmp_path / "stiff")["failure_cause"] == "rounding_noise"
    atol = re.search(r"give -snes_atol (\S+) or more", line).group(1)
    assert 1e-11 < float(atol) < 1e-8, atol
    # the tolerance it names is reached
    q = solve_cli(_sandwich(tmp_path, "given"), extra=["-snes_atol", atol])
    assert q.returncode == 0, q.stdout + q.stderr
    assert read_summary(tmp_path / "given")["status"] == "completed"
