"""A pretwisted GOH beam (helical fibres, two families) solved on 1 and 2 ranks: the same answer."""
import pytest

from helpers import assert_same_as_serial, load_raw, probes_table, run_on_ranks


@pytest.mark.mpi
@pytest.mark.slow
def test_goh_pretwisted_bar_ranks_agree_with_serial(tmp_path):
    raw = load_raw("pretwisted_bar.yaml")
    raw["beams"][0]["material"] = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 50.0e6, "k1": 2.0e6,
                                   "k2": 5.0, "kappa": 0.1,
                                   "fibres": {"follow": "twist", "angle_deg": [15.0, -15.0],
                                              "extra_twist_deg": 20.0}}
    raw["beams"][0]["elements"] = 6
    runs = run_on_ranks(raw, tmp_path, ranks=(1, 2))
    tables = {n: probes_table(s) for n, (_, s) in runs.items()}
    assert_same_as_serial(tables)
    assert abs(tables[1][-1]).max() > 1e-3          # the bar did move (mm scale)


def test_goh_restart_continues_and_refuses_other_fibres(tmp_path):
    """A GOH run restarted with more levels gives the uninterrupted answer; changed fibre angles
    are another model (the fibre directions are in the restart fingerprint)."""
    from helpers import read_summary, solve_cli, write_config
    raw = load_raw("pretwisted_bar.yaml")
    raw["beams"][0]["material"] = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 50.0e6, "k1": 2.0e6,
                                   "k2": 5.0, "kappa": 0.1, "fibres": {"follow": "twist", "angle_deg": 10.0}}
    raw["output"] = {"vtk": False}
    full = solve_cli(write_config(raw, tmp_path / "full.yaml"), extra=["--output-dir", str(tmp_path / "full"),
                                                                        "--quiet"])
    assert full.returncode == 0, full.stderr
    short = dict(raw, steps=raw["steps"][:2])
    p = solve_cli(write_config(short, tmp_path / "short.yaml"), extra=["--output-dir", str(tmp_path / "run"),
                                                                        "--quiet"])
    assert p.returncode == 0, p.stderr
    other = dict(raw, beams=[dict(raw["beams"][0], material=dict(raw["beams"][0]["material"],
                                                                 fibres={"follow": "twist", "angle_deg": 20.0}))])
    p = solve_cli(write_config(other, tmp_path / "other.yaml"), extra=["--restart", str(tmp_path / "run")])
    assert p.returncode == 2 and "beams/bar/fibres" in p.stderr, p.stderr
    p = solve_cli(str(tmp_path / "full.yaml"), extra=["--restart", str(tmp_path / "run"), "--quiet"])
    assert p.returncode == 0, p.stderr
    a, b = read_summary(tmp_path / "full"), read_summary(tmp_path / "run")
    assert len(a["steps"]) == len(b["steps"]) == len(raw["steps"])
    pa = probes_table(a)[-1]
    pb = probes_table(b)[-1]
    assert abs(pa - pb).max() <= 1e-10 * abs(pa).max()
