"""Support presets (config/specs.py FIX_PRESETS): the components each fixes, and the root on a
frictionless plane against the closed-form uniaxial bar (issue 41)."""
import numpy as np
import pytest

from ancf_petsc.config.parse import parse_config
from ancf_petsc.config.specs import FIX_PRESETS
from ancf_petsc.config.values import ConfigError
from ancf_petsc.physics.elements import ELEMENTS
from ancf_petsc.physics.materials import NeoHookean
from ancf_petsc.physics.reference_solutions import uniaxial_stretches
from helpers import CONFIGS, load_raw, run_inline


BLOCK = ELEMENTS["3363"].block
VECTORS = BLOCK.names


def _preset(name: str) -> list[tuple[int, int]]:
    """A preset's (vector, component) pairs on 3363's node block."""
    return FIX_PRESETS[name](BLOCK)


def _named(pairs) -> dict[str, str]:
    """[(vector, component)] → {vector name: "xz"}, the config's own spelling."""
    out = {}
    for v, c in sorted(pairs):
        out[VECTORS[v]] = out.get(VECTORS[v], "") + "xyz"[c]
    return out


def test_each_preset_fixes_exactly_the_documented_components():
    assert _named(_preset("clamped")) == {v: "xyz" for v in VECTORS}
    assert _named(_preset("reduced")) == {"r": "xyz", "r_y": "xz", "r_z": "xy", "r_yy": "xyz",
                                              "r_zz": "xyz", "r_yz": "xyz"}
    assert _named(_preset("plane")) == {"r": "xyz", "r_y": "xz", "r_z": "x", "r_yy": "x",
                                            "r_zz": "x", "r_yz": "x"}
    plane, reduced, clamped = (set(_preset(k)) for k in ("plane", "reduced", "clamped"))
    assert plane < reduced < clamped and len(clamped) == 18
    # what reduced clamps beyond the plane: the section's in-plane shear and quadratic modes
    assert _named(reduced - plane) == {"r_z": "y", "r_yy": "yz", "r_zz": "yz", "r_yz": "yz"}


def test_the_plane_preset_is_the_mapping_it_stands_for():
    raw = load_raw("uniaxial_neohookean.yaml")
    specs = []
    for fix in ("plane", {"r": "xyz", "r_y": "xz", "r_z": "x", "r_yy": "x", "r_zz": "x", "r_yz": "x"}):
        raw["boundary_conditions"][0]["fix"] = fix
        specs.append(parse_config(raw, base_dir=CONFIGS).boundary_conditions[0].dofs)
    assert specs[0] == specs[1]


def test_an_unknown_preset_names_every_preset():
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["boundary_conditions"][0]["fix"] = "pinned"
    with pytest.raises(ConfigError, match="boundary_conditions.0..fix.*use clamped, reduced, plane or"):
        parse_config(raw, base_dir=CONFIGS)


@pytest.mark.parametrize("elements", [1, 3])
def test_a_bar_on_a_plane_root_matches_the_closed_form(tmp_path, elements):
    """Homogeneous uniaxial tension of a nearly incompressible neo-Hookean bar whose root slides
    on the plane x = 0: elongation and lateral contraction equal the closed form at every level."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["elements"] = elements
    raw["boundary_conditions"][0]["fix"] = "plane"
    raw["output"]["vtk"] = False
    raw["probes"] += [{"name": f"{v}_{n}", "beam": "bar", "node": n, "vector": v}
                      for v in ("r_y", "r_z") for n in ("first", "last")]
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed"
    area = next(iter(s["sections"].values()))["area"]
    mat = NeoHookean(1.0e6, 50.0e6)
    L, force = raw["geometry"]["length"], raw["loads"][0]["traction_force"][0]
    for step in s["steps"]:
        lam, lt = uniaxial_stretches(mat, step["load_factor"] * force / area)
        u = np.array(step["probes"]["tip"]["displacement"])
        assert u[0] == pytest.approx((lam - 1.0) * L, rel=1e-6)
        assert np.abs(u[1:]).max() < 1e-12
        for v, k in (("r_y", 1), ("r_z", 2)):       # the section contracts, at the root too
            for n in ("first", "last"):
                d = np.array(step["probes"][f"{v}_{n}"]["displacement"])
                assert d[k] == pytest.approx(lt - 1.0, rel=1e-6)
                assert np.abs(np.delete(d, k)).max() < 1e-10
