"""A researcher's session through the Python API (ancf_petsc/api.py): parts of a parsed spec
edited before ``solve`` are solved as the config that says them would be, or refused as it
would be, with an InputError naming the key."""
import pytest
import yaml

from helpers import CONFIGS, petsc_init


def _spec(name: str, out):
    petsc_init()
    import ancf_petsc as ap
    spec = ap.load_config(f"{CONFIGS}/{name}")
    spec.output.dir = str(out)
    return ap, spec


def _probe_of_config(ap, name: str, edit, out, probe: str = "tip"):
    """Probe ``probe`` at every level of config ``name`` with ``edit(raw)`` applied to its YAML."""
    from ancf_petsc.config.parse import parse_config
    raw = yaml.safe_load(open(f"{CONFIGS}/{name}"))
    edit(raw)
    spec = parse_config(raw, base_dir=CONFIGS)
    spec.output.dir = str(out)
    assert ap.solve(spec, log=lambda *_: None).status == "completed"
    return ap.read_results(out).probe(probe)


def test_an_edited_node_of_a_probe_and_a_load_is_the_node_solved(tmp_path):
    """bending_neohookean at 2 elements (nodes 0..4 along the beam), its tip load moved to node 3
    and its probe to node 2 by editing ``node``: the answers of the config saying node 3 and 2.
    Before, resolve_nodes put both back to the config's 'last' (the probe reported the tip,
    the load stayed there) and the run completed with the unedited model's answers."""
    ap, spec = _spec("bending_neohookean.yaml", tmp_path / "edited")
    spec.beams[0].elements, spec.steps = 2, [0.5, 1.0]
    spec.loads[0].kind, spec.loads[0].node, spec.probes[0].node = "force", 3, 2
    assert ap.solve(spec, log=lambda *_: None).status == "completed"
    got = ap.read_results(tmp_path / "edited").probe("tip")

    def edit(raw):
        raw["beams"][0]["elements"], raw["steps"] = 2, [0.5, 1.0]
        raw["loads"][0] = {"beam": "beam", "node": 3, "force": raw["loads"][0]["traction_force"]}
        raw["probes"][0]["node"] = 2
    want = _probe_of_config(ap, "bending_neohookean.yaml", edit, tmp_path / "parsed")
    assert abs(want[-1][2]) > 1e-3                    # the beam bends
    assert got == pytest.approx(want, rel=1e-12, abs=1e-15)
    assert spec.probes[0].node == 2 and spec.loads[0].node == 3


def test_an_edited_node_the_beam_does_not_have_is_refused(tmp_path):
    """A probe's node edited past the beam's last node: InputError naming probes[0].node."""
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "out")
    spec.probes[0].node = 9
    with pytest.raises(ap.InputError) as err:
        ap.solve(spec, log=lambda *_: None)
    assert err.value.path == "probes[0].node" and "node 9 does not exist" in err.value.message


def _paper_tendon(ap, out, raw_edit=None):
    """The paper's ψ = 45° tendon at 1 element per subtendon, 10 and 100 N: its spec, or (with
    ``raw_edit``) that of its YAML edited."""
    from ancf_petsc.config.parse import parse_config
    raw = yaml.safe_load(open(f"{CONFIGS}/achilles_type3_psi45.yaml"))
    for beam in raw["beams"]:
        beam["elements"] = 1
    raw["steps"] = [10, 100]
    if raw_edit is not None:
        raw_edit(raw)
    spec = parse_config(raw, base_dir=CONFIGS)
    spec.output.dir = str(out)
    return spec


def test_friction_added_through_the_api_is_the_configs_friction(tmp_path):
    """Coulomb friction (μ = 0.3) set on the paper's sliding tendon as spec.contact.tangential:
    the answers of the config that says it.  Before, the parsed spec kept the pressure space and
    fade keys of the frictionless config (quadratic along the beam, fade 'newton', forces 'auto'),
    which the config with friction does not take, and the run completed with the soleus 1.047 mm
    long at 100 N against the config's 1.444 mm (its pressing force 132 N against 0.245 N)."""
    petsc_init()
    import ancf_petsc as ap
    from ancf_petsc.config.specs import TangentialSpec
    spec = _paper_tendon(ap, tmp_path / "edited")
    spec.contact.tangential = TangentialSpec(law="coulomb", friction=0.3)
    assert ap.solve(spec, log=lambda *_: None).status == "completed"
    config = _paper_tendon(ap, tmp_path / "config", lambda raw: raw["contact"].update(
        tangential={"law": "coulomb", "friction": 0.3}))
    assert ap.solve(config, log=lambda *_: None).status == "completed"
    got, want = ap.read_results(tmp_path / "edited"), ap.read_results(tmp_path / "config")
    for name in ("soleus", "medial_gastrocnemius", "lateral_gastrocnemius"):
        assert got.probe(name) == pytest.approx(want.probe(name), rel=1e-12, abs=1e-15)
    assert spec.contact == config.contact
    import h5py
    with h5py.File(tmp_path / "edited" / "results.h5", "r") as h5:
        stored = yaml.safe_load(h5["model"].attrs["config_yaml"])
    assert stored["contact"]["tangential"] == {"law": "coulomb", "friction": 0.3, "supported_ends": "merge"}


@pytest.mark.parametrize("key,value,path", [
    ("mode", "bonded", "contact.mode"),                       # a KeyError before
    ("axial_points", 1, "contact.axial_points"),              # ran before
    ("search_margin", -1.0, "contact.search_margin"),         # ran before
    ("fade", "foo", "contact.fade"),                          # ran before
    ("scaling", 0.0, "contact.scaling"),                      # a ZeroDivisionError before
    ("interfaces", [(0, 7, None, None)], "contact.interfaces[0].b"),   # an IndexError before
    ("tangential", {"law": "coulomb", "friction": -1.0}, "contact.tangential.friction"),
])
def test_an_edited_contact_is_checked_as_the_configs(tmp_path, key, value, path):
    """A contact key edited to what its config refuses: that InputError, naming the key."""
    petsc_init()
    import ancf_petsc as ap
    spec = _paper_tendon(ap, tmp_path / "out")
    setattr(spec.contact, key, value)
    with pytest.raises(ap.InputError) as err:
        ap.solve(spec, log=lambda *_: None)
    assert err.value.path == path
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("edit,path", [
    (lambda s: setattr(s.loads[0], "beam", 7), "loads[0].beam"),             # an IndexError before
    (lambda s: setattr(s.loads[0], "force", (1.0, 0.0)), "loads[0].force"),  # numpy's broadcast error
    (lambda s: setattr(s.loads[0], "kind", "foo"), "loads[0].kind"),         # ran as a point force
    (lambda s: setattr(s.probes[0], "vector", "foo"), "probes[0].vector"),   # a ValueError before
    (lambda s: setattr(s.probes[1], "name", "soleus"), "probes[1].name"),    # one probe lost
    (lambda s: setattr(s.boundary_conditions[0], "dofs", [(9, 0)]), "boundary_conditions[0].fix"),
    (lambda s: setattr(s.beams[1], "name", "soleus"), "beams[1].name"),      # results.h5's OutputError
    (lambda s: s.beams.pop(), "boundary_conditions[2].beam"),                # an IndexError before
    (lambda s: setattr(s.boundary_conditions[0], "displacement", [(0, 0, "x")]),
     "boundary_conditions[0].displacement"),                                  # a ValueError in the build
    (lambda s: setattr(s, "name", None), "name"),                             # an OutputError
])
def test_edited_supports_loads_and_probes_are_checked_as_the_configs(tmp_path, edit, path):
    """A support, load or probe (or a beam they name) edited to what a config cannot say: an
    InputError naming it, before anything is written."""
    petsc_init()
    import ancf_petsc as ap
    spec = _paper_tendon(ap, tmp_path / "out")
    edit(spec)
    with pytest.raises(ap.InputError) as err:
        ap.solve(spec, log=lambda *_: None)
    assert err.value.path == path
    assert not (tmp_path / "out").exists()


def test_a_load_moved_to_a_beam_by_name_is_that_beams_load(tmp_path):
    """The paper's tendon with its 100 N moved from the soleus to the lateral gastrocnemius by
    name (spec.loads[0].beam = 'lateral_gastrocnemius', a numpy force): the config's answers."""
    import numpy as np
    petsc_init()
    import ancf_petsc as ap
    spec = _paper_tendon(ap, tmp_path / "edited")
    spec.loads[0].beam, spec.loads[0].force = "lateral_gastrocnemius", np.array([1.0, 0.0, 0.0])
    assert ap.solve(spec, log=lambda *_: None).status == "completed"
    config = _paper_tendon(ap, tmp_path / "config", lambda raw: raw["loads"][0].update(beam="lateral_gastrocnemius"))
    assert ap.solve(config, log=lambda *_: None).status == "completed"
    got, want = ap.read_results(tmp_path / "edited"), ap.read_results(tmp_path / "config")
    assert want.probe("lateral_gastrocnemius")[-1][0] > 1e-4
    assert got.probe("lateral_gastrocnemius") == pytest.approx(want.probe("lateral_gastrocnemius"), rel=1e-12)


def test_results_read_a_file_the_session_holds_open_with_h5py(tmp_path):
    """results.h5 open in the same process through h5py's default (locked) h5py.File, as a
    notebook exploring it holds it: Results.nodal_vectors reads the level.  Before, HDF5 refused
    to open it again without the lock ('file locking flag values don't match') and the reader
    said 'not a whole results.h5; run ancf-solve again'."""
    import h5py
    import numpy as np
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "out")
    spec.steps = [0.5, 1.0]
    assert ap.solve(spec, log=lambda *_: None).status == "completed"
    run = ap.read_results(tmp_path / "out")
    with h5py.File(tmp_path / "out" / "results.h5", "r") as held:
        last = run.nodal_vectors(-1)
        assert np.array_equal(last, held["steps/step_0002/nodal_vectors"][()])
        assert np.array_equal(run.nodal_vectors(0), held["model/reference_nodal_vectors"][()])
    # the tip's r moved by the probe's displacement
    assert last[-1, 0] - run.nodal_vectors(0)[-1, 0] == pytest.approx(run.probe("tip")[-1], rel=1e-12)


def test_the_apis_own_arguments_are_refused_by_name(tmp_path):
    """solve(log=None) runs without a report (it was "'NoneType' object is not callable" after
    the output directory was made); a log that is no function, a level 1.5 (numpy's and
    h5py's 'Unknown format code') and a probe field 'force' (a bare KeyError) are refused
    saying what is expected."""
    import numpy as np
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "out")
    spec.steps = [0.5, 1.0]
    with pytest.raises(TypeError, match="log must be a function"):
        ap.solve(spec, log="quiet")
    assert ap.solve(spec, log=None).status == "completed"
    run = ap.read_results(tmp_path / "out")
    assert run.probe("tip")[-1][0] == pytest.approx(run.nodal_vectors(np.int64(2))[-1, 0, 0] - 0.1, rel=1e-12)
    with pytest.raises(TypeError, match="step must be an integer level"):
        run.nodal_vectors(1.5)
    with pytest.raises(ValueError, match="what must be one of displacement, value; got 'force'"):
        run.probe("tip", "force")


def test_probes_made_in_code_are_placed_as_a_configs(tmp_path):
    """ProbeSpec('end', 0, 'last') appended to a parsed spec (it raised a TypeError in the build:
    'last' was never resolved) reports the tip, and ProbeSpec('mid', 0, 2) the middle node of the
    2-element bar: half the tip's displacement in this homogeneous stretch."""
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "out")
    from ancf_petsc.config.specs import ProbeSpec
    spec.beams[0].elements, spec.steps = 2, [1.0]
    spec.probes += [ProbeSpec("end", 0, "last"), ProbeSpec("mid", 0, 2)]
    assert ap.solve(spec, log=None).status == "completed"
    run = ap.read_results(tmp_path / "out")
    assert run.probe("end")[-1] == pytest.approx(run.probe("tip")[-1], rel=1e-14, abs=1e-18)
    assert run.probe("mid")[-1][0] == pytest.approx(run.probe("tip")[-1][0] / 2, rel=1e-9)


@pytest.mark.parametrize("part,name,near", [
    (lambda s: s, "twist", "twist_deg"),
    (lambda s: s.beams[0], "n_elements", "elements"),
    (lambda s: s.loads[0], "forces", "force"),
    (lambda s: s.solver, "max_cutback", "max_cutbacks"),
])
def test_a_misspelt_field_is_refused_not_ignored(tmp_path, part, name, near):
    """spec.twist = 30 (for twist_deg) was kept as a new attribute that nothing reads, and the
    paper's tendon was solved at ψ = 45° with no word: now AttributeError naming the field meant;
    the fields themselves are set as before."""
    petsc_init()
    import ancf_petsc as ap
    spec = _paper_tendon(ap, tmp_path / "out")
    with pytest.raises(AttributeError, match=f"has no field '{name}' \\(did you mean '{near}'\\?\\)"):
        setattr(part(spec), name, 30)
    setattr(part(spec), near, getattr(part(spec), near))


@pytest.mark.parametrize("edit,path", [
    ({"probe": "foo"}, "accuracy.probe"),               # a KeyError in the ladder before
    ({"component": "w"}, "accuracy.component"),         # a ValueError before
    ({"rtol": -1.0}, "accuracy.rtol"),                  # the whole ladder, 'accuracy not met'
    ({"level": 7.0}, "accuracy.level"),                 # the same: 7 is none of the steps
])
def test_an_edited_accuracy_is_checked_as_the_configs(tmp_path, edit, path):
    """accuracy: set or edited through the API (an AccuracySpec, or a config's mapping, which
    raised an AttributeError) is read as the config's, after the edited steps."""
    from dataclasses import replace

    from ancf_petsc.api import check_edited
    from ancf_petsc.config.specs import AccuracySpec
    ap, spec = _spec("pretwisted_bar.yaml", tmp_path / "out")
    spec.accuracy = {"probe": "tip", "rtol": 1e-2}
    check_edited(spec)
    assert spec.accuracy == AccuracySpec(probe="tip", rtol=1e-2)
    spec.accuracy = replace(spec.accuracy, **edit)
    with pytest.raises(ap.InputError) as err:
        ap.solve(spec, log=None)
    assert err.value.path == path
    assert not (tmp_path / "out").exists()


def test_a_config_parsed_from_a_relative_directory_is_solved_as_loaded(tmp_path, monkeypatch):
    """parse_config(raw, base_dir='configs') (the repository's root the working directory) of
    the paper's tendon, then the working directory changed, then solve: the answers of
    load_config.  Before, solve read the sections again joining base_dir a second time and
    refused 'configs/configs/data/achilles_type3_sections.yaml: file not found'."""
    import os

    from ancf_petsc.config.parse import parse_config
    petsc_init()
    import ancf_petsc as ap
    monkeypatch.chdir(os.path.dirname(CONFIGS))
    raw = yaml.safe_load(open("configs/achilles_type3_psi45.yaml"))
    for beam in raw["beams"]:
        beam["elements"] = 1
    raw["steps"] = [10, 100]
    spec = parse_config(raw, base_dir="configs")
    spec.output.dir = str(tmp_path / "relative")
    monkeypatch.chdir(tmp_path)
    assert ap.solve(spec, log=None).status == "completed"
    loaded = _paper_tendon(ap, tmp_path / "loaded")
    assert ap.solve(loaded, log=None).status == "completed"
    got, want = ap.read_results(tmp_path / "relative"), ap.read_results(tmp_path / "loaded")
    assert got.probe("soleus") == pytest.approx(want.probe("soleus"), rel=1e-12)


def test_build_model_builds_the_model_solve_would_solve(tmp_path):
    """ancf_petsc.build_model of uniaxial_neohookean edited from 1 element to 3 (nodes 0..6):
    the tip load and probe on node 6, the end.  Before, the exported build_model built the spec
    as it stood: both on node 2, inside the bar."""
    import numpy as np
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "out")
    spec.beams[0].elements = 3
    model = ap.build_model(spec)
    last = model.n_nodes - 1
    assert set(np.nonzero(model.f_ext)[0] // model.dofs_per_node) == {last}
    assert model.probes["tip"][0] == last
    spec.beams[0].material["mu"] = -1.0
    with pytest.raises(ap.InputError, match="mu"):
        ap.build_model(spec)


def test_an_output_directory_under_home_is_the_home_directorys(tmp_path, monkeypatch):
    """spec.output.dir = '~/runs/bar' wrote the run into ./~/runs/bar, a directory named '~'
    in the working directory, with no word; now into the home directory, where read_results
    and solve(restart=) find it by the same words."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    (tmp_path / "work").mkdir()
    monkeypatch.chdir(tmp_path / "work")
    ap, spec = _spec("uniaxial_neohookean.yaml", "~/runs/bar")
    spec.steps = [0.5]
    result = ap.solve(spec, log=None)
    assert result.status == "completed"
    assert result.output_dir == str(tmp_path / "home" / "runs" / "bar")
    assert not (tmp_path / "work" / "~").exists()
    spec.steps = [0.5, 1.0]
    assert ap.solve(spec, log=None, restart="~/runs/bar").status == "completed"
    assert list(ap.read_results("~/runs/bar").load_factors) == [0.5, 1.0]


def test_a_probe_moved_through_the_api_is_stored_as_solved(tmp_path):
    """The paper's ψ = 45° tendon with its soleus probe edited to node 0 (the held root: 0 mm):
    results.h5's config says node 0, and ancf-report --existing does not compare the run with
    Table 1.  Before, the stored config kept 'last' and the report called the run the paper's
    reproduction, its soleus elongation 0."""
    import h5py

    from helpers import report_existing
    ap, spec = _spec("achilles_type3_psi45.yaml", tmp_path / "run")
    spec.steps = [10]
    spec.probes[0].node = 0
    assert ap.solve(spec, log=None).status == "completed"
    with h5py.File(tmp_path / "run" / "results.h5", "r") as h5:
        stored = yaml.safe_load(h5["model"].attrs["config_yaml"])
    assert stored["probes"][0] == {"name": "soleus", "beam": "soleus", "node": 0, "vector": "r"}
    assert stored["probes"][1]["node"] == "last"
    text = report_existing([str(tmp_path / "run")], tmp_path / "rep")
    assert "is not compared with the paper: its probe 'soleus' is vector r at node 0" in text


@pytest.mark.parametrize("steps", [
    "arange",            # list(np.arange(1, 3)): 'steps[0]: expected a number; got 1' before
    "linspace",          # an array: 'steps: expected a list; got array([0.5, 1. ])' before
    "tuple",             # (0.5, 1.0): 'steps: expected a list' before
])
def test_numpy_steps_and_counts_are_taken_as_numbers(tmp_path, steps):
    """Load factors and an element count as numpy makes them solve as the same Python numbers."""
    import numpy as np
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "out")
    spec.steps = {"arange": lambda: list(np.arange(1, 3)), "linspace": lambda: np.linspace(0.5, 1.0, 2),
                  "tuple": lambda: (0.5, 1.0)}[steps]()
    spec.beams[0].elements = np.int32(2)
    assert ap.solve(spec, log=None).status == "completed"
    want = {"arange": [1.0, 2.0], "linspace": [0.5, 1.0], "tuple": [0.5, 1.0]}[steps]
    assert list(ap.read_results(tmp_path / "out").load_factors) == want
    assert spec.steps == want and type(spec.beams[0].elements) is int
