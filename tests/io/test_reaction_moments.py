"""The supports' moments (``reaction_moments``, petsc/reactions.py) against closed forms and
the equilibrium of moments."""
import os

import h5py
import numpy as np
import pytest

from helpers import CONFIGS, cantilever, load_raw, petsc_init, run_inline


def test_a_cantilevers_root_moment_is_its_end_force_times_its_length(tmp_path):
    """A clamped neo-Hookean cantilever (L = 0.1 m) with a small end force P along z: the
    root's moment about y is P L to discretisation error; it was not written at all."""
    raw = cantilever([1e-3])
    P = raw["loads"][0]["traction_force"][2] * 1e-3
    s = run_inline(raw, tmp_path)
    M = np.array(s["steps"][-1]["reaction_moments"]["beam.0"])
    assert abs(M[1] - P * 0.1) < 1e-3 * P * 0.1, (M, P * 0.1)
    assert abs(M[0]) < 1e-9 * P * 0.1 and abs(M[2]) < 1e-9 * P * 0.1
    with h5py.File(tmp_path / "results.h5") as h5:
        d = h5["steps/step_0001/reaction_moments"]
        assert np.allclose(d[()][0], M, rtol=0, atol=1e-15)
        assert d.attrs["units"].startswith("N m") and list(d.attrs["supports"]) == ["beam.0"]


def _moment_balance(config: dict, out) -> list[tuple[np.ndarray, float]]:
    """Per level: the moment about the origin of every load and reaction (their sum) and the
    loads' moment's size."""
    petsc_init()
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.io.reader import read_results
    from ancf_petsc.model.build import build_model
    model = build_model(parse_config(config, base_dir=CONFIGS))
    res = read_results(str(out))
    rows = []
    for k, st in enumerate(res.summary["steps"], start=1):
        q = res.nodal_vectors(k)
        f = sum(g.multiplier(st["load_factor"]) * g.forces for g in model.loading).reshape(q.shape)
        loads = np.cross(q, f).sum(axis=(0, 1))
        total = loads + sum(np.cross(q[s.node, 0], st["reactions"][s.name]) + st["reaction_moments"][s.name]
                            for s in model.supports)
        rows.append((total, float(np.linalg.norm(loads))))
    return rows


def test_reaction_moments_balance_the_loads_in_large_bending(tmp_path):
    """The cantilever bent to 40 % of its length: the root moment balances the end traction's
    moment about the origin (its arm the deformed tip's) to 1e-10."""
    raw = cantilever([0.5, 1.0])
    run_inline(raw, tmp_path)
    for total, size in _moment_balance(raw, tmp_path):
        assert np.abs(total).max() < 1e-10 * size, (total, size)


def test_reaction_moments_balance_the_load_on_the_contact_tendon(tmp_path):
    """The paper's tendon (ψ = 45°, 2 elements, reduced supports, sliding contact) at 100 and
    400 N: the three roots' forces and moments balance the soleus pull's moment to 1e-9."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
        b["elements"] = 2
    raw["steps"] = [100, 400]
    raw["output"] = {"vtk": False}
    run_inline(raw, tmp_path)
    for total, size in _moment_balance(raw, tmp_path):
        assert size > 0.1 and np.abs(total).max() < 1e-9 * size, (total, size)


def test_centroid_moment_of_a_turned_section():
    """Forces ±f on the section's r_y (a couple over y): the moment is r_y × f about the centroid,
    wherever the centroid is."""
    from ancf_petsc.petsc.reactions import centroid_moment
    q = np.zeros((6, 3))
    q[0], q[1], q[2] = [5.0, 1.0, 2.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]
    f = np.zeros((6, 3))
    f[0], f[1] = [0.0, 0.0, 7.0], [3.0, 0.0, 0.0]
    assert np.allclose(centroid_moment(q, f), np.cross(q[1], f[1]))


@pytest.mark.mpi
def test_reaction_moments_on_two_ranks_are_the_serial_ones(tmp_path):
    """The cantilever clamped at its last node (owned by rank 1 on 2 ranks), pulled at its
    first: the support's force and moment equal the serial ones to 1e-9."""
    from helpers import assert_same_as_serial, run_on_ranks
    raw = cantilever([0.5, 1.0])
    raw["boundary_conditions"][0]["node"] = "last"
    raw["loads"][0]["node"] = "first"
    raw["probes"][0]["node"] = "first"
    runs = run_on_ranks(raw, tmp_path, ranks=(1, 2))
    assert_same_as_serial({n: np.array([st["reactions"]["beam.8"] + st["reaction_moments"]["beam.8"]
                                        for st in s["steps"]]) for n, (_, s) in runs.items()})
