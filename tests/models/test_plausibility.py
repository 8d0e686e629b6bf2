"""Issue 25: lengths in mm by mistake (``length: 70`` for 0.07) gave no warning, 552 Newton
iterations and exit 3.  Implausible sizes are named in the run header; a first level strained
beyond 50 % is named on stderr at the end of the run (and in summary.json)."""
import glob
import os

import pytest
import yaml

from helpers import CONFIGS, load_raw, run_inline, solve_cli

from ancf_petsc.config.parse import parse_config
from ancf_petsc.model.build import build_model


def _warnings(raw):
    return [line for line in build_model(parse_config(raw, base_dir=CONFIGS)).describe()
            if line.startswith("warning")]


@pytest.mark.parametrize("path", sorted(glob.glob(os.path.join(CONFIGS, "*.yaml"))))
def test_shipped_configs_give_no_warning(path):
    assert _warnings(load_raw(os.path.basename(path))) == []


def test_length_in_mm_is_named():
    raw = load_raw("achilles_type3_psi0.yaml")
    raw["geometry"]["length"] = 70
    w, file_length = _warnings(raw)
    assert "geometry.length is 70 m" in w and "write length: 0.07" in w
    assert "gives length_m 0.07 m" in file_length


def test_a_length_other_than_the_sections_files_is_named(tmp_path):
    """The sections file's length_m is the source's, not read by the model: a config at another
    length ran silently at the config's."""
    raw = load_raw("achilles_type3_psi0.yaml")
    raw["geometry"]["length"] = 0.06
    (w,) = _warnings(raw)
    assert w.startswith("warning: geometry.length: 0.06 m") and "length_m 0.07 m" in w
    # a traced subject's file may leave out the source's length and moduli altogether
    with open(os.path.join(CONFIGS, "data", "achilles_type3_sections.yaml")) as f:
        data = yaml.safe_load(f)
    del data["length_m"], data["c10_MPa"]
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    for b in raw["beams"]:
        b["section"]["file"] = str(tmp_path / "s.yaml")
    assert _warnings(raw) == []


def test_section_in_mm_is_named():
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["section"]["semi_axes"] = [6, 4]            # mm meant
    (w,) = _warnings(raw)
    assert w.startswith("warning: beams[0].section: the section of beam bar is 12 m wide")
    assert "divide them by 1000" in w


def test_bundle_radius_in_mm_is_named():
    raw = load_raw("bundle_hex7.yaml")
    raw["bundle"]["radius"] = 0.6
    (w,) = _warnings(raw)
    assert w.startswith("warning: bundle.radius: the section of beam fascicle0 is 1.2 m wide (and 6 more")


@pytest.mark.parametrize("key,value,expected", [
    ("mu", 103.1, "beams[0].material.mu: 103.1 Pa for beam soleus is softer than any tendon"),
    ("bulk_modulus", 3.7, "a small-strain Poisson ratio of -0.9999998, negative (auxetic)"),
    ("bulk_modulus", 1e15, "incompressible beyond K/mu = 1e+06")])
def test_implausible_moduli_are_named(key, value, expected):
    """A modulus written in MPa as Pa, or a bulk modulus far off (in the fuzzing of configs:
    bulk_modulus 3.7 failed after hundreds of Newton iterations with no word of the material)."""
    raw = load_raw("achilles_type3_psi0.yaml")
    raw["beams"][0]["material"][key] = value
    (w,) = _warnings(raw)
    assert expected in w and "units" in w


def test_twist_axis_in_mm_and_more_than_a_turn_are_named():
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["geometry"]["twist_axis"] = [5.896, -2.9837]               # mm meant
    (w,) = _warnings(raw)
    assert w.startswith("warning: geometry.twist_axis: the axis is 6.6 m from the nearest section centroid (635 x")
    assert "divide them by 1000" in w
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["geometry"]["twist_deg"] = 1000
    w, resolution = _warnings(raw)                   # 250 deg per element: also under-resolved
    assert "geometry.twist_deg: 1000 deg is more than a full turn" in w
    assert resolution.startswith("warning: beams[0].elements: the pretwist (1000 deg over 4 element(s))")


def _twisted(twist, elements, axial_points=3):
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["geometry"]["twist_deg"] = twist
    for b in raw["beams"]:
        b["elements"], b["axial_points"] = elements, axial_points
    return raw


@pytest.mark.parametrize("twist,elements,axial_points,error", [
    (180, 1, 3, "24 %"), (180, 1, 2, "22 %"), (180, 2, 3, "2.1 %"), (90, 1, 2, "1.9 %")])
def test_an_under_resolved_pretwist_is_named(twist, elements, axial_points, error):
    """180 deg over one 3363 element shrank the interpolated reference section (its directors
    r_y, r_z interpolated quadratically between nodes half a turn apart) and the soleus
    elongated 7.567 mm at 400 N against 6.717-6.836 mm at 2-16 elements, completed, no word."""
    (w,) = _warnings(_twisted(twist, elements, axial_points))
    assert w.startswith(f"warning: beams[0].elements: the pretwist ({twist} deg over {elements} element(s)) "
                        "is under-resolved in beam soleus (and 2 more beam(s))")
    assert f"shrinks the reference section's area by {error} at x = " in w and "beyond 1 %" in w
    need = int(w.split("use elements: ")[1].split()[0])
    assert _warnings(_twisted(twist, need, axial_points)) == []     # the fix it names is enough
    assert need == 1 or _warnings(_twisted(twist, need - 1, axial_points))


@pytest.mark.parametrize("twist,elements", [(180, 4), (180, 8), (135, 4), (90, 2), (45, 1)])
def test_a_resolved_pretwist_is_not_named(twist, elements):
    """The gait envelope's cells (4 and 8 elements, twists up to 180 deg) stay silent."""
    assert _warnings(_twisted(twist, elements)) == []


def test_implausible_slenderness_is_named():
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["geometry"]["length"] = 0.0001                         # 0.1 mm long, 12 mm wide
    (w,) = _warnings(raw)
    assert "length / sqrt(section area) = 0.0115" in w and "beams[0].section (too large?)" in w


def test_mm_length_warning_is_in_the_run_header(tmp_path):
    """--check prints the run's model header: the warning is there, once, on rank 0's stdout."""
    raw = load_raw("achilles_type3_psi0.yaml")
    raw["geometry"]["length"] = 70
    raw["beams"] = [dict(b, section=dict(b["section"], file=os.path.join(CONFIGS, b["section"]["file"])))
                    for b in raw["beams"]]
    path = tmp_path / "mm.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    p = solve_cli(str(path), extra=["--check", "--output", str(tmp_path / "g.png")])
    assert p.returncode == 0, p.stderr
    assert p.stdout.count("[ancf]   warning: geometry.length is 70 m") == 1


def test_first_level_strain_is_named(tmp_path):
    """A shear modulus 10 x too small: 60 % axial strain at the first level."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.2]
    raw["beams"][0]["material"].update(mu=1.0e5, bulk_modulus=5.0e6)
    (w,) = run_inline(raw, tmp_path / "soft")["warnings"]
    assert w.startswith("warning: at the first converged level (load factor 0.2) beam bar's axis is 60 % longer")
    raw["beams"][0]["material"].update(mu=1.0e6, bulk_modulus=5.0e7)
    assert run_inline(raw, tmp_path / "right")["warnings"] == []


def test_first_level_strain_warning_on_stderr(tmp_path):
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.2]
    raw["beams"][0]["material"].update(mu=1.0e5, bulk_modulus=5.0e6)
    path = tmp_path / "soft.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    p = solve_cli(str(path), extra=["--output-dir", str(tmp_path / "out"), "--quiet"])
    assert p.returncode == 0, p.stderr
    assert p.stderr.count("ancf-solve: warning: at the first converged level") == 1
    # and right after the first level's progress line, not only at the end
    p = solve_cli(str(path), extra=["--output-dir", str(tmp_path / "out2")])
    lines = p.stdout.splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("[ancf] step 1/"))
    assert lines[k + 1].startswith("[ancf]   warning: at the first converged level"), lines[k:k + 2]


@pytest.mark.parametrize("config,material,expected", [
    ("achilles_type3_psi45_goh.yaml", {"k1": 3.7859},
     "beams[0].material.k1: 3.7859 Pa for beam soleus: fibres this soft add next to nothing"),
    ("achilles_type3_psi45_goh.yaml", {"k1": 996.6}, "if you meant 996.6 MPa, write 996.6e6"),
    ("elastica_svk.yaml", {"E": 1.2}, "beams[0].material.E: 1.2 Pa for beam beam is softer than any tendon")])
def test_fibre_and_svk_moduli_written_in_mpa_as_pa_are_named(config, material, expected):
    """k1: 3.7859 (the paper's set in MPa, written as Pa) and an SVK E: 1.2 ran to 'completed' with no
    word (the GOH bar as soft as its matrix); k1: 0 (fibres off) is not named."""
    raw = load_raw(config)
    raw["beams"][0]["material"].update(material)
    (w,) = _warnings(raw)
    assert expected in w and "units" in w
    if "k1" in material:
        raw["beams"][0]["material"]["k1"] = 0.0
        assert _warnings(raw) == []


def test_a_bundles_material_is_named_once_by_its_key():
    """A bundle's fascicles share bundle.material: mu 100 Pa on bundle_hex7 gave 7 alike warnings
    keyed beams[0..6].material.mu (keys the config does not have), k2 1e6 7 more."""
    raw = load_raw("bundle_hex7.yaml")
    raw["bundle"]["material"] = {"model": "goh", "mu": 100.0, "bulk_modulus": 1.0e9, "k1": 2.0e6, "k2": 1.0e6}
    w = _warnings(raw)
    assert len(w) == 2, w
    assert w[0].startswith("warning: bundle.material.k2: 1e+06: the fibre term e^(k2 E^2) of beam fascicle0 "
                           "(and every other fascicle) overflows")
    assert w[1].startswith("warning: bundle.material.mu: 100 Pa for beam fascicle0 (and every other fascicle) "
                           "is softer than any tendon")


def test_paper_column_runs_without_warnings(tmp_path):
    s = run_inline(load_raw("achilles_type3_psi0.yaml"), tmp_path / "psi0")
    assert s["status"] == "completed" and s["warnings"] == []


def test_a_fibre_exponent_that_overflows_is_warned_of_and_leaks_no_numpy_warning(tmp_path):
    """Issue 39: k2 = 1e6 overflows e^(k2 Ē²) from a fibre stretch of 1.013: one warning naming
    the key; the run's outputs (VTU in single precision, results.h5) leak no numpy warning."""
    import warnings
    from helpers import load_raw, run_inline
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["material"] = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 50.0e6, "k1": 2.0e6,
                                   "k2": 1.0e6, "fibres": {"follow": "axis"}}
    raw["steps"] = [0.1, 1.0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = run_inline(raw, tmp_path)
    assert s["status"] == "completed"
    note = [w for w in s["warnings"] if "k2" in w]
    assert len(note) == 1 and note[0].startswith("warning: beams[0].material.k2: 1e+06:")
    assert "fibre stretch of 1.013" in note[0]
    raw["beams"][0]["material"]["k2"] = 524.6                  # the largest published set: no warning
    assert not [w for w in run_inline(raw, tmp_path / "b")["warnings"] if "k2" in w]
    raw["beams"][0]["material"].update(k1=0.0, k2=1.0e6)       # fibres off: nothing overflows
    assert not [w for w in _warnings(raw) if "k2" in w]


def test_a_model_nothing_moves_is_named():
    """Every load zero (forces, or a history column of zeros) and no prescribed displacement:
    the reference state is the answer, which the run completes with; one warning says so.  A
    single nonzero load or displacement silences it."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for ld in raw["loads"]:
        ld[[k for k in ld if k.endswith("force")][0]] = [0.0, 0.0, 0.0]
    (w,) = _warnings(raw)
    assert w.startswith("warning: loads: every load and prescribed displacement is zero")
    raw["boundary_conditions"].append({"beam": "soleus", "node": "last", "displacement": {"r": {"x": 1e-4}}})
    assert _warnings(raw) == []
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.pop("steps")
    raw["history"] = {"table": {"time": [0.0, 0.1], "pull": [0.0, 0.0]}}
    raw["loads"][0]["column"] = "pull"
    (w,) = _warnings(raw)
    assert "zero at every level" in w
    raw["history"]["table"]["pull"] = [0.0, 2.0]
    assert _warnings(raw) == []


def test_a_history_column_that_turns_negative_is_named():
    """A load whose history column is negative at some frames pushes the tendon's end (muscle
    forces pull only): one warning naming the load, the frames and the lowest value; positive
    columns give none."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.pop("steps")
    raw["history"] = {"table": {"time": [0.0, 0.1, 0.2, 0.3, 0.4], "pull": [1.0, -2.0, -5.0, 3.0, -1.0]}}
    raw["loads"][0]["column"] = "pull"
    (w,) = _warnings(raw)
    assert w.startswith("warning: loads[0]: its history column is negative at frame(s) 2-3, 5 (down to -5")
    raw["history"]["table"]["pull"] = [1.0, 2.0, 0.0, 3.0, 1.0]
    assert _warnings(raw) == []


def test_the_push_warning_follows_the_force_on_the_end_not_the_columns_sign():
    """OpenSim forces written negative and mapped with a vector pointing the other way pull the
    tendon (its end moves +24.6 mm at 45 N, as with both signs positive), yet were warned 'a pull
    turned into a push'; a positive column under a vector pointing into the beam pushes it (the
    bar buckles: 3 negative eigenvalues) and was not warned; a lateral load changing sign was
    warned as a push.  Now the warning names the frames where the force on an end section
    points into its beam."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.pop("steps")
    raw["history"] = {"table": {"time": [0.0, 0.1, 0.2], "pull": [-10.0, -45.0, 5.0]}}
    raw["loads"][0].update(column="pull", traction_force=[-1.0, 0.0, 0.0])
    (w,) = _warnings(raw)
    assert w.startswith("warning: loads[0]: its traction_force points into beam bar at its last node "
                        "(x component -1): the column positive at frame(s) 3 (up to 5) pushes"), w
    raw["history"]["table"]["pull"] = [-10.0, -45.0, -5.0]
    assert _warnings(raw) == []
    raw["loads"][0]["traction_force"] = [0.0, 0.0, 1.0]             # lateral: no pull, no push
    assert _warnings(raw) == []
    raw["loads"][0].update(node="first", traction_force=[1.0, 0.0, 0.0])
    raw["boundary_conditions"][0]["node"] = "last"
    assert _warnings(raw) == []                                     # -x on the first end: a pull
    raw["history"]["table"]["pull"] = [-10.0, 45.0, -5.0]
    raw["loads"][0]["traction_force"] = [-1.0, 0.0, 0.0]
    (w,) = _warnings(raw)
    assert w.startswith("warning: loads[0]: its history column is negative at frame(s) 1, 3 (down to -10"), w


@pytest.mark.parametrize("element,degree,warned", [("3363", 2, True), ("3363", 3, True), ("3363", 4, False),
                                                   ("3333", 2, False)])
def test_a_section_rule_that_under_integrates_the_element_is_named(element, degree, warned):
    """3363's quadratic section field needs a rule of degree 4 (2 x its order; 33103 and 33153 are
    raised to theirs).  At degree 2 or 3 the run went on with no word: a 2 x 2 rectangle rule has
    spurious section modes (the bending scene stalls 3 % off, docs/studies.md), and at degree 3 the
    elastica on a square differed by 2e-4 between the rectangle and the same square as an outline."""
    raw = load_raw("bending_neohookean.yaml")
    raw["beams"][0]["element"] = element
    raw["beams"][0]["section"]["cubature_degree"] = degree
    expected = [f"warning: beams[0].section.cubature_degree: {degree} under-integrates element 3363's "
                "order-2 section field (spurious section modes; docs/studies.md): use 4 or more"]
    assert _warnings(raw) == (expected if warned else [])


def test_a_bundles_section_rule_is_named_once_at_its_own_key():
    raw = load_raw("bundle_hex7.yaml")
    raw["bundle"]["cubature_degree"] = 3
    w = [line for line in _warnings(raw) if "cubature_degree" in line]
    assert len(w) == 1 and w[0].startswith("warning: bundle.cubature_degree: 3 under-integrates element 3363")
