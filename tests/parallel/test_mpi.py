"""-n 1, -n 2 and -n 3 --oversubscribe give the serial answer on every probe of every step."""
import os

import pytest

from helpers import CONFIGS, assert_same_as_serial, load_raw, probes_table, run_on_ranks, two_beam_twisted


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
    # the three subtendons with clamped roots: the roots' pressure functions folded into their
    # neighbours (contact/multipliers.py), multipliers shared by elements on two ranks
    tendon = load_raw("achilles_type3_psi45.yaml")
    for b in tendon["beams"]:
        b["elements"] = 4
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    for bc in tendon["boundary_conditions"]:
        bc["fix"] = "clamped"
    tendon["steps"] = [10.0, 100.0]
    return {"uniaxial-1-element": uni, "elastica": elastica, "pretwisted": twisted, "two-beams": two,
            "two-beams-3363-3333": mixed, "tendon-clamped-roots": tendon}


CASES = _cases()


@pytest.mark.mpi
@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_ranks_agree_with_serial(tmp_path, name):
    runs = run_on_ranks(CASES[name], tmp_path)
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})


@pytest.mark.mpi
@pytest.mark.slow
@pytest.mark.parametrize("forces", ["variational", "pointwise"])
def test_differentiated_fade_weights_give_the_serial_answer(tmp_path, forces):
    """The paper's ψ = 45° sliding column with ``contact.fade: newton`` (contact/weights.py): at
    400 N a point's partner sits in the fade band past the end of its interface curve (weight
    0.399 on every rank count); 1, 2 and 3 ranks give the serial probes and Newton counts, with
    the weights' forces variational (LDLᵀ) and pointwise (``contact.fade_forces``, LU)."""
    import meshio
    import numpy as np
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["contact"]["fade"] = "newton"
    raw["contact"]["fade_forces"] = forces
    runs = run_on_ranks(raw, tmp_path)
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
    assert len({s["newton_iterations"] for _, s in runs.values()}) == 1
    w = meshio.read(os.path.join(tmp_path, "n2", f"contact_{len(raw['steps']):04d}.vtu")).point_data["weight"]
    assert np.any((w > 0.05) & (w < 0.95))
