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
