"""results.h5's ``load_factor_units`` says what a level's load factor is: for a load history the
frame number, not 'the multiple of the config's loads' (frame 2's loads are the columns' values)."""
import h5py

from helpers import load_raw, solve_cli, write_config


def _units(raw: dict, tmp_path, name: str) -> tuple[float, str]:
    raw["output"] = {"vtk": False}
    p = solve_cli(write_config(raw, tmp_path / f"{name}.yaml"), extra=["--output-dir", str(tmp_path / name), "--quiet"])
    assert p.returncode == 0, p.stderr
    with h5py.File(tmp_path / name / "results.h5", "r") as h5:
        g = h5["steps/step_0002"]
        return float(g.attrs["load_factor"]), str(g.attrs["load_factor_units"])


def test_a_history_level_says_its_load_factor_is_the_frame(tmp_path):
    """The uniaxial bar on a history of 10 and 30 N (traction 1 N x the column): level 2 has load
    factor 2 and 30 N, where the attribute read 'the multiple of the config's loads' (2 N)."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.pop("steps")
    raw["history"] = {"table": {"time": [0.0, 0.5], "f": [10.0, 30.0]}}
    raw["loads"][0].update(traction_force=[1.0, 0.0, 0.0], column="f")
    lam, units = _units(raw, tmp_path, "history")
    assert lam == 2.0 and "frame number" in units and "multiple" not in units
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.5, 1.0]
    raw["loads"][0]["curve"] = [[0.0, 0.0], [1.0, 2.0]]
    assert "curve" in _units(raw, tmp_path, "curve")[1]
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.5, 1.0]
    assert _units(raw, tmp_path, "plain")[1] == "1 (the multiple of the config's loads and displacements)"
