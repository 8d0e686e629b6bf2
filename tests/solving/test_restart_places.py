"""A restart refused for a changed load, support, prescribed displacement, length or pretwist
names the config entry and the place (beam, node, nodal vector, component), not an index into
the model's DOFs."""
import copy
import re

import pytest

from ancf_petsc.errors import InputError

from helpers import CONFIGS, load_raw


def _run(raw, out, restart=False):
    from ancf_petsc.api import solve
    from ancf_petsc.config.parse import parse_config
    spec = parse_config(dict(raw, output={"dir": str(out), "vtk": False}), base_dir=CONFIGS)
    return solve(spec, log=lambda *_: None, restart=str(out) if restart else None)


def _pulled(raw):
    """The bar pulled by a prescribed end displacement of 1 mm instead of its traction."""
    raw["loads"] = []
    raw["boundary_conditions"].append({"beam": "bar", "node": "last", "displacement": {"r": {"x": 1.0e-3}}})
    return raw


@pytest.mark.parametrize("edit,words", [
    (lambda r: r["loads"][0].update(traction_force=[50.0, 0.0, 0.0]),
     "loads (loads[0] at beam bar node 2, r x: 45 → 50)"),
    (lambda r: r["boundary_conditions"][0].update(fix="clamped"),
     "supported_dofs (boundary_conditions[0] at beam bar node 0, r_y y: now held)"),
    (lambda r: r["geometry"].update(twist_deg=10.0), "geometry.twist_deg (0 → 10)"),
    (lambda r: r["geometry"].update(length=0.11), "geometry.length (0.1 → 0.11)"),
    (lambda r: _pulled(r)["boundary_conditions"][1]["displacement"]["r"].update(x=2.0e-3),
     "prescribed_displacements (boundary_conditions[1] at beam bar node 2, r x: 0.001 → 0.002)")])
def test_a_refused_restart_names_the_config_entry_and_place(tmp_path, edit, words):
    """The bar solved to 0.1, restarted with the edit: the refusal said 'loads (largest change at
    entry 36: 45 → 50)', 'supported_dofs (shape (16,) → (18,))', 'reference_nodal_vectors
    (largest change at entry 41: 0 → 0.173648178)' for a pretwist of 10 deg and
    'beams/bar/x_nodes (...)' for the length: indices into the model's DOFs, not the config."""
    raw = load_raw("uniaxial_neohookean.yaml")
    first = _pulled(copy.deepcopy(raw)) if "prescribed" in words else copy.deepcopy(raw)
    _run(dict(first, steps=[0.1]), tmp_path)
    edited = copy.deepcopy(raw)
    edit(edited)
    with pytest.raises(InputError, match="written by another model: " + re.escape(words) + " differs"):
        _run(dict(edited, steps=[0.1, 0.2]), tmp_path, restart=True)
