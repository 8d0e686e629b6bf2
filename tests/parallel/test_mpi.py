"""-n 1, -n 2 and -n 3 --oversubscribe give the serial answer on every probe of every step."""
import pytest

from helpers import load_raw, read_summary, solve_cli, write_config
from helpers import assert_same_as_serial, probes_table, two_beam_twisted


def _cases():
    uni = load_raw("uniaxial_neohookean.yaml")
    elastica = load_raw("elastica_svk.yaml")
    elastica["beams"][0]["elements"] = 12
    twisted = load_raw("pretwisted_bar.yaml")
    two = two_beam_twisted()
    two["probes"].append({"name": "second_tip", "beam": "second", "node": "last"})
    two["loads"].append({"beam": "second", "node": "last", "force": [0.0, 0.05, 0.02]})
    mixed = two_beam_twisted()                  # element 3333 (ecm) beside 3363
    mixed["beams"][1].update({"element": 3333, "section": dict(mixed["beams"][1]["section"], cubature_degree=3)})
    mixed["probes"] = two["probes"]
    mixed["loads"] = two["loads"]
    return {"uniaxial-1-element": uni, "elastica": elastica, "pretwisted": twisted, "two-beams": two,
            "two-beams-3363-3333": mixed}


CASES = _cases()


@pytest.mark.mpi
@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_ranks_agree_with_serial(tmp_path, name):
    raw = CASES[name]
    tables = {}
    for n in (1, 2, 3):
        raw["output"] = {"dir": str(tmp_path / f"n{n}"), "vtk": n == 2}
        p = solve_cli(write_config(raw, tmp_path / f"c{n}.yaml"), ranks=n)
        assert p.returncode == 0, p.stdout + p.stderr
        s = read_summary(tmp_path / f"n{n}")
        assert s["status"] == "completed" and s["ranks"] == n
        tables[n] = probes_table(s)
    assert_same_as_serial(tables)
