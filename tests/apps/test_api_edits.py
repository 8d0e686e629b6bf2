"""A spec changed through the Python API after parsing (ancf_petsc/api.py ``check_edited``):
'last' follows the beams' element counts as they are at ``solve``, edited steps are checked as
the config's, and the config stored with the results says what was solved."""
import h5py
import pytest
import yaml

from helpers import CONFIGS, petsc_init


def _spec(name: str, out):
    petsc_init()
    import ancf_petsc as ap
    spec = ap.load_config(f"{CONFIGS}/{name}")
    spec.output.dir = str(out)
    return ap, spec


def _parsed_tip(ap, name: str, edit: dict, tmp_path):
    """The tip of ``name`` with ``edit`` (beam 0's keys) written into the config and parsed, one
    level at 1 (the answer an edit of the parsed spec must give)."""
    from ancf_petsc.config.parse import parse_config
    raw = yaml.safe_load(open(f"{CONFIGS}/{name}"))
    raw["beams"][0].update(edit)
    parsed = parse_config(raw, base_dir=CONFIGS)
    parsed.steps, parsed.output.dir = [1.0], str(tmp_path / "parsed")
    ap.solve(parsed, log=lambda *_: None)
    return ap.read_results(tmp_path / "parsed").probe("tip")[-1]


def test_an_edited_element_count_moves_last_with_it(tmp_path):
    """uniaxial_neohookean with its 1 element edited to 3: the load, the support and the tip
    probe stay at the bar's end.  Before, they stayed at node 2, now an interior node, and the
    run completed with u_x 8.20e-3 m against the 2.4604e-2 m of the same bar parsed with 3
    elements; the other way (bending 8 -> 2 elements) raised an IndexError."""
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "edited")
    spec.steps = [1.0]
    spec.beams[0].elements = 3
    res = ap.solve(spec, log=lambda *_: None)
    assert res.status == "completed"
    assert spec.loads[0].node == spec.probes[0].node == 6            # 3 elements of 3 nodes
    u_edit = ap.read_results(tmp_path / "edited").probe("tip")[-1]
    u_parse = _parsed_tip(ap, "uniaxial_neohookean.yaml", {"elements": 3}, tmp_path)
    assert u_edit[0] == pytest.approx(u_parse[0], rel=1e-12) and u_parse[0] > 0.02
    with h5py.File(tmp_path / "edited" / "results.h5") as h5:
        stored = yaml.safe_load(h5["model"].attrs["config_yaml"])
    assert stored["beams"][0]["elements"] == 3 and stored["steps"] == [1.0]
    ap, spec = _spec("bending_neohookean.yaml", tmp_path / "fewer")
    spec.beams[0].elements = 2
    spec.steps = spec.steps[:1]
    assert ap.solve(spec, log=lambda *_: None).status == "completed"


def test_an_edited_index_the_beam_no_longer_has_is_a_config_error(tmp_path):
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "o")
    spec.beams[0].elements = 2                                # nodes 0..4
    spec.probes[0].given = 5
    with pytest.raises(ap.ConfigError, match=r"probes\[0\]\.node: node 5 does not exist"):
        ap.solve(spec, log=lambda *_: None)


def test_an_edit_that_puts_two_supports_on_one_component_is_a_config_error(tmp_path):
    """node 2 and node last are apart at 2 elements, one node at 1: the grip's displacement and
    the other support's fix of r_x met there and the later one's value was applied."""
    from ancf_petsc.config.parse import parse_config
    raw = yaml.safe_load(open(f"{CONFIGS}/uniaxial_neohookean.yaml"))
    raw["beams"][0]["elements"], raw["loads"] = 2, []
    raw["boundary_conditions"] += [{"beam": "bar", "node": 2, "name": "hold", "fix": {"r": "x"}},
                                   {"beam": "bar", "node": "last", "name": "grip", "displacement": {"r": {"x": 1e-3}}}]
    ap, _ = _spec("uniaxial_neohookean.yaml", tmp_path / "o")
    spec = parse_config(raw, base_dir=CONFIGS)
    spec.output.dir = str(tmp_path / "o")
    spec.beams[0].elements = 1
    with pytest.raises(ap.ConfigError, match=r"boundary_conditions\[2\]\.displacement\.r\.x: bar node last: "
                                             r"r\.x is also held by boundary_conditions\[1\] \('hold'\)"):
        ap.solve(spec, log=lambda *_: None)


@pytest.mark.parametrize("field,value,message", [
    ("elements", 0, r"beams\[0\]\.elements: must be >= 1; got 0"),              # was loads[0]: ... fixed component
    ("elements", 2.5, r"beams\[0\]\.elements: expected an integer; got 2\.5"),   # was a TypeError
    ("elements", "3", r"beams\[0\]\.elements: expected an integer; got '3'"),
    ("axial_points", 0, r"beams\[0\]\.axial_points: must be >= 2; got 0"),       # was a ValueError
    ("element", "bogus", r"beams\[0\]\.element: must be one of .*; got 'bogus'"),  # was a KeyError
    ("element", "33103", r"beams\[0\]\.element: changed after parsing from 3363, whose node block"),
])
def test_edited_beams_are_checked_as_the_configs(tmp_path, field, value, message):
    """33103 edited onto a parsed 3363 beam kept its 18 clamped DOFs of 30 (the bending tip
    44.0 mm against the parsed config's 40.7 mm): its node block is refused."""
    ap, spec = _spec("bending_neohookean.yaml", tmp_path / "o")
    setattr(spec.beams[0], field, value)
    with pytest.raises(ap.ConfigError, match=message):
        ap.solve(spec, log=lambda *_: None)
    assert not (tmp_path / "o" / "summary.json").exists()


@pytest.mark.parametrize("key,value,message", [
    ("mu", -1e6, r"beams\[0\]\.material\.mu: must be > 0 \(shear modulus in Pa\); got -1e\+06"),  # ran: 'unstable'
    ("model", "bogus", r"beams\[0\]\.material\.model: must be one of .*; got 'bogus'"),           # a KeyError
    ("c10", 5e5, r"beams\[0\]\.material: give either mu and bulk_modulus or the paper's c10 and d"),
])
def test_an_edited_material_is_checked_as_the_configs(tmp_path, key, value, message):
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "o")
    spec.beams[0].material[key] = value
    with pytest.raises(ap.ConfigError, match=message):
        ap.solve(spec, log=lambda *_: None)


def test_an_edited_goh_material_is_read_again_unchanged():
    """A parsed GOH material (fibres.angles_deg) reads again as itself."""
    from ancf_petsc.config.beams import check_edited_beams
    _, spec = _spec("achilles_type3_psi45_goh.yaml", "unused")
    before = [dict(b.material) for b in spec.beams]
    spec.beams[0].material["k1"] = 2.0 * before[0]["k1"]
    check_edited_beams(spec.beams)
    assert spec.beams[0].material == dict(before[0], k1=2.0 * before[0]["k1"])
    assert [b.material for b in spec.beams[1:]] == before[1:]


def test_an_edited_element_type_takes_its_own_locking_remedy(tmp_path):
    """bending_neohookean edited to element 3333 kept 3363's remedy 'none' instead of 3333's
    'ecm' and completed Poisson-locked, the tip u_z 3.27 mm against the parsed config's 41.57 mm;
    now the same answer to the last bit, and the stored config says 3333.  A numpy count is an
    integer (np.int64 ended in an OutputError: not JSON serializable)."""
    import numpy as np
    ap, spec = _spec("bending_neohookean.yaml", tmp_path / "edited")
    spec.beams[0].element, spec.beams[0].elements, spec.steps = "3333", np.int64(8), [1.0]
    assert ap.solve(spec, log=lambda *_: None).status == "completed"
    u_edit = ap.read_results(tmp_path / "edited").probe("tip")[-1]
    u_parse = _parsed_tip(ap, "bending_neohookean.yaml", {"element": 3333}, tmp_path)
    assert spec.beams[0].locking == "ecm" and np.array_equal(u_edit, u_parse) and u_parse[2] > 0.04
    with h5py.File(tmp_path / "edited" / "results.h5") as h5:
        stored = yaml.safe_load(h5["model"].attrs["config_yaml"])["beams"][0]
    assert (stored["element"], stored["elements"], stored.get("locking")) == ("3333", 8, None)


def test_edited_steps_are_checked_as_the_configs(tmp_path):
    """Decreasing steps set on a spec raised an UnboundLocalError in the load stepping and left
    INTERNAL_ERROR in summary.json; now the config's own error, before anything is written."""
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "o")
    spec.steps = [1.0, 0.5]
    with pytest.raises(ap.ConfigError, match="steps: load factors must increase strictly"):
        ap.solve(spec, log=lambda *_: None)
    assert not (tmp_path / "o" / "summary.json").exists()


def test_ctrl_c_in_a_python_session_is_an_interruption_not_a_bug(tmp_path):
    """Ctrl-C during ``solve`` in a Python session raises KeyboardInterrupt (no handler is
    installed there); the run is recorded as interrupted by SIGINT with its converged levels,
    not as a bug (it was ``failed``, INTERNAL_ERROR, 'KeyboardInterrupt: '), and the
    KeyboardInterrupt reaches the caller."""
    import json
    import signal
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "o")
    spec.steps = [0.1 * k for k in range(1, 11)]

    from ancf_petsc.solving import interrupt
    lines, sent = [], []

    def log(line):
        lines.append(line)
        if "step 3/" in line and not sent:      # in this thread: os.kill may reach another thread
            sent.append(signal.getsignal(signal.SIGINT))
            signal.raise_signal(signal.SIGINT)
    # a Python session's own handler (default_int_handler), whatever an earlier test of this
    # worker left: the full suite failed here twice in fresh clones, never alone
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    interrupt.reset()
    try:
        ap.solve(spec, log=log)
    except KeyboardInterrupt:
        pass
    else:
        pytest.fail(f"no KeyboardInterrupt: SIGINT sent {bool(sent)} (handler {sent}); log {lines[-4:]}")
    finally:
        signal.signal(signal.SIGINT, previous)
    s = json.load(open(tmp_path / "o" / "summary.json"))
    assert (s["status"], s["reason_code"]) == ("interrupted", "SIGINT")
    assert len(s["steps"]) == 3 and "after load factor 0.3" in s["message"]



def test_ancf_fit_called_in_process_gives_back_the_callers_signal_handlers(tmp_path):
    """apps/ancf_fit.main installs the clean-stop handlers (solving/interrupt.py) and, like
    ancf-solve's, restores the caller's on return: it left its own SIGINT handler behind, under
    which a later Ctrl-C in the same session only recorded the signal."""
    import signal

    from apps.ancf_fit import main
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    assert main([str(tmp_path / "missing.yaml")]) == 2
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before


def test_a_solve_leaves_the_sessions_sigpipe_handler(tmp_path):
    """The API's first ``solve`` initialises PETSc, whose SIGPIPE handler replaced Python's: a
    script that solved, then printed into a closed pipe (``python script.py | head -1``) ended in
    a PETSc error dump and MPI_ABORT (exit 59) instead of Python's BrokenPipeError."""
    import subprocess
    import sys
    script = (
        "import sys, ancf_petsc as ap\n"
        f"spec = ap.load_config('{CONFIGS}/uniaxial_neohookean.yaml')\n"
        f"spec.output.dir, spec.steps = '{tmp_path / 'o'}', [1.0]\n"
        "ap.solve(spec, log=lambda line: None)\n"
        "try:\n"
        "    for i in range(10 ** 6):\n"
        "        print(i, flush=True)\n"
        "except BrokenPipeError:\n"
        "    sys.stderr.write('BrokenPipeError\\n')\n"
        "    sys.stdout = None\n")
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    proc.stdout.readline()
    proc.stdout.close()
    err = proc.stderr.read()
    assert (proc.wait(timeout=120), err.strip().splitlines()[-1:]) == (0, ["BrokenPipeError"]), err


def test_solve_takes_an_mpi4py_communicator_and_refuses_a_dict(tmp_path):
    """``solve(spec, comm=MPI.COMM_WORLD)`` ended in an AttributeError mid-setup ('Intracomm'
    object has no attribute 'tompi4py'), a raw config dict in one ('dict' has no 'beams')."""
    from mpi4py import MPI
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "o")
    spec.steps = [1.0]
    assert ap.solve(spec, comm=MPI.COMM_WORLD, log=lambda *_: None).status == "completed"
    with pytest.raises(TypeError, match="solve: expected a ModelSpec .*; got dict"):
        ap.solve(spec.raw)


def test_the_stored_config_says_the_edited_material(tmp_path):
    """uniaxial_neohookean with mu edited to 2 MPa on the parsed spec: results.h5's config_yaml
    ('the config the levels were solved with') said mu 1.0e6 beside the 2 MPa bar's answer (tip
    u_x 11.18 mm; 24.60 mm with 1 MPa); now it says the material solved, and that config parsed
    again gives the same tip."""
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "edited")
    spec.steps = [1.0]
    spec.beams[0].material["mu"] = 2.0e6
    assert ap.solve(spec, log=lambda *_: None).status == "completed"
    u_edit = ap.read_results(tmp_path / "edited").probe("tip")[-1]
    with h5py.File(tmp_path / "edited" / "results.h5") as h5:
        stored = yaml.safe_load(h5["model"].attrs["config_yaml"])["beams"][0]["material"]
    assert float(stored["mu"]) == 2.0e6
    u_parse = _parsed_tip(ap, "uniaxial_neohookean.yaml", {"material": stored}, tmp_path)
    assert u_edit[0] == pytest.approx(u_parse[0], rel=1e-12) and u_parse[0] < 0.02


def test_an_edited_fibre_angle_in_the_configs_key_is_solved(tmp_path):
    """A GOH bar's fibres['angle_deg'] (the config's key) set to 60 on the parsed spec was dropped
    for the parsed angles_deg [0]: the run solved 0 deg (tip u_x 18.24 mm against 60 deg's 101.3
    mm) with no word.  Now it is the angle solved and the one stored, as the config's would be."""
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "edited")
    spec.steps = [1.0]
    goh = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 5.0e7, "k1": 2.0e6, "k2": 5.0, "kappa": 0.1,
           "fibres": {"follow": "axis", "angle_deg": 0.0}}
    from ancf_petsc.config.beams import parse_material
    spec.beams[0].material = parse_material(goh, "beams[0].material")
    spec.beams[0].material["fibres"]["angle_deg"] = 60.0
    assert ap.solve(spec, log=lambda *_: None).status == "completed"
    assert spec.beams[0].material["fibres"]["angles_deg"] == [60.0]
    u_edit = ap.read_results(tmp_path / "edited").probe("tip")[-1]
    with h5py.File(tmp_path / "edited" / "results.h5") as h5:
        stored = yaml.safe_load(h5["model"].attrs["config_yaml"])["beams"][0]["material"]
    assert stored["fibres"]["angle_deg"] == [60.0]
    u_parse = _parsed_tip(ap, "uniaxial_neohookean.yaml",
                          {"material": dict(goh, fibres={"follow": "axis", "angle_deg": 60.0})}, tmp_path)
    assert u_edit[0] == pytest.approx(u_parse[0], rel=1e-12)


@pytest.mark.parametrize("petsc,message", [
    ({"snes_rtol": "abc"}, r"petsc\.snes_rtol: expected a number \(PETSc reads it with strtod\); got 'abc'"),
    ({"snes_rtol": None}, r"petsc\.snes_rtol: needs a value: a number"),   # ran: 30 Newton iterations
    ({"help": None}, r"petsc\.help: PETSc reads -help only while it starts"),
], ids=["not a number", "no value", "start-up option"])
def test_edited_petsc_options_are_checked_as_the_configs(tmp_path, petsc, message):
    """spec.petsc edited to {'snes_rtol': 'abc'} was refused by PETSc mid-setup in a line naming
    no key ('PETSc refused an option while setting up the solver ... Input string abc has no
    numeric value'); {'snes_rtol': None} ran.  Now the config's one-line errors, nothing written."""
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "o")
    spec.petsc = petsc
    with pytest.raises(ap.ConfigError, match=message):
        ap.solve(spec, log=lambda *_: None)
    assert not (tmp_path / "o" / "summary.json").exists()


def test_the_stored_config_says_the_edited_petsc_options(tmp_path):
    """spec.petsc edited to a backtracking line search: 54 Newton iterations against 31, and
    results.h5's config said no petsc: at all."""
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "o")
    spec.steps, spec.petsc = [1.0], {"snes_linesearch_type": "bt", "snes_converged_reason": None, "snes_max_it": 30}
    assert ap.solve(spec, log=lambda *_: None).status == "completed"
    with h5py.File(tmp_path / "o" / "results.h5") as h5:
        stored = yaml.safe_load(h5["model"].attrs["config_yaml"])["petsc"]
    assert stored == {"snes_linesearch_type": "bt", "snes_converged_reason": None, "snes_max_it": "30"}


def test_an_edited_material_takes_the_solver_defaults_of_its_law(tmp_path):
    """bending_neohookean edited to GOH through the API kept the neo-Hookean default, the secant
    predictor, where the GOH config parsed takes the tangent (config.parse.default_predictor):
    37 Newton iterations against 26 (the elastica: 412 against 288), the same tip.  Now the edited spec takes the GOH law's
    defaults and the parsed config's path; a predictor set on the spec is kept."""
    from ancf_petsc.config.beams import parse_material
    from ancf_petsc.config.parse import parse_config
    goh = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 5.0e7, "k1": 2.0e6, "k2": 5.0, "kappa": 0.1,
           "fibres": {"follow": "axis", "angle_deg": 30.0}}
    ap, spec = _spec("bending_neohookean.yaml", tmp_path / "edited")
    spec.beams[0].material = parse_material(goh, "beams[0].material")
    edited = ap.solve(spec, log=lambda *_: None)
    raw = yaml.safe_load(open(f"{CONFIGS}/bending_neohookean.yaml"))
    raw["beams"][0]["material"] = goh
    parsed = parse_config(raw, base_dir=CONFIGS)
    parsed.output.dir = str(tmp_path / "parsed")
    alone = ap.solve(parsed, log=lambda *_: None)
    assert (spec.solver.predictor, spec.solver.section_update) == ("tangent", "rotation")
    assert edited.summary["newton_iterations"] == alone.summary["newton_iterations"]     # 37 against 26
    assert (ap.read_results(tmp_path / "edited").probe("tip")[-1]
            == ap.read_results(tmp_path / "parsed").probe("tip")[-1]).all()
    ap, spec = _spec("bending_neohookean.yaml", tmp_path / "kept")
    spec.beams[0].material, spec.solver.predictor = parse_material(goh, "beams[0].material"), "none"
    from ancf_petsc.api import check_edited
    check_edited(spec)
    assert spec.solver.predictor == "none"


def test_an_edited_element_type_is_checked_against_the_contacts_pressure_space(tmp_path):
    """The paper's sliding tendon with projection.curve: 2 (3 pressure functions across, allowed
    on 3363's quadratic sections) edited to 3333 (linear across: at most 2, which its config
    refuses) ran: 2 elements, the soleus 2.796 mm at 200 N against 2.903 mm with the default
    space (3.7 % stiffer).  Now the config's refusal, before anything is written."""
    from ancf_petsc.config.parse import parse_config
    raw = yaml.safe_load(open(f"{CONFIGS}/achilles_type3_psi45.yaml"))
    raw["contact"]["projection"] = {"curve": 2}
    ap, _ = _spec("uniaxial_neohookean.yaml", tmp_path / "o")
    spec = parse_config(raw, base_dir=CONFIGS)
    spec.output.dir = str(tmp_path / "o")
    for beam in spec.beams:
        beam.element = "3333"
    with pytest.raises(ap.ConfigError, match=r"contact\.projection\.curve: under the sliding law .* at most 2 "
                                             r"pressure functions across"):
        ap.solve(spec, log=lambda *_: None)
    assert not (tmp_path / "o").exists()



@pytest.mark.parametrize("obj,key,value,message", [
    ("solver", "allow_unstable", "no", r"solver\.allow_unstable: expected true or false; got 'no'"),   # ran as true
    ("solver", "options_prefix", "-left_", r"solver\.options_prefix: a PETSc options prefix is"),   # PETSc error dump
    ("solver", "max_increment", 1e-9, r"solver\.max_increment: 1e-09 would take 1e\+09 increments"),  # ran until killed
    ("solver", "predictor", "bogus", r"solver\.predictor: must be one of none, secant, tangent; got 'bogus'"),
    ("spec", "partition", "bogus", r"partition\.method: must be one of blocks, metis, beams; got 'bogus'"),
    ("output", "vtk_samples", 0, r"output\.vtk_samples: must be >= 1; got 0"),   # failed at its first write
], ids=["allow_unstable", "options_prefix", "max_increment", "predictor", "partition", "vtk_samples"])
def test_edited_solver_and_output_keys_are_checked_as_the_configs(tmp_path, obj, key, value, message):
    """solver, partition and output keys set on a parsed spec were taken unchecked: allow_unstable
    'no' accepted unstable levels, options_prefix '-left_' stopped in PETSc's error dump ('Options
    prefix should not begin with a hyphen'), max_increment 1e-9 ran until killed, predictor and
    partition 'bogus' ran as others, vtk_samples 0 ended 'failed' at its first write."""
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "o")
    setattr(spec if obj == "spec" else getattr(spec, obj), key, value)
    with pytest.raises(ap.ConfigError, match=message):
        ap.solve(spec, log=lambda *_: None)
    assert not (tmp_path / "o").exists()


def test_an_edit_the_accuracy_ladder_would_not_see_is_refused(tmp_path):
    """With accuracy: the rungs are the config parsed again: bending_neohookean with its load
    halved on the spec solved the config's load, tip u_z 40.29 mm against the halved load's 23.07
    mm, and 'completed'; so were an edited length and solver.predictor.  Now refused naming the
    change, nothing written; an edit the stored config says (a material; since the stored config
    says the geometry solved, the length too: its rungs are the edited bar's) still runs."""
    from ancf_petsc.api import check_edited
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.workflows.accuracy import check_rungs_carry
    raw = yaml.safe_load(open(f"{CONFIGS}/bending_neohookean.yaml"))
    raw["accuracy"] = {"probe": "tip", "component": "z", "rtol": 1e-2, "start": 2}
    ap, _ = _spec("uniaxial_neohookean.yaml", tmp_path / "o")
    for edit, key in [(lambda s: setattr(s.loads[0], "force", tuple(0.5 * f for f in s.loads[0].force)),
                       r"spec\.loads\[0\]\.force\[2\]"),
                      (lambda s: setattr(s.solver, "predictor", "none"), r"spec\.solver\.predictor")]:
        spec = parse_config(raw, base_dir=CONFIGS)
        spec.output.dir = str(tmp_path / "o")
        edit(spec)
        with pytest.raises(ap.ConfigError, match=r"accuracy: the ladder's rungs are made from the config, and "
                                                 + key + " was changed after parsing"):
            ap.solve(spec, log=lambda *_: None)
        assert not (tmp_path / "o").exists()
    for edit in (lambda s: s.beams[0].material.update(mu=2.0 * s.beams[0].material["mu"]),
                 lambda s: setattr(s, "length", 2 * s.length)):
        spec = parse_config(raw, base_dir=CONFIGS)
        edit(spec)
        check_edited(spec)
        check_rungs_carry(spec)


@pytest.mark.parametrize("key,value,message", [
    ("length", -0.1, r"geometry\.length: must be > 0 \(metres\); got -0\.1"),          # ValueError in the build
    ("twist_deg", float("nan"), r"geometry\.twist_deg: must be a finite number"),       # LinAlgError
    ("twist_deg", 5000.0, r"geometry\.twist_deg: must be <= 3600; got 5000"),           # ran
    ("twist_axis", "bogus", r"geometry\.twist_axis: expected a list of 2 numbers"),     # ValueError
], ids=["length", "twist_nan", "twist_5000", "axis"])
def test_edited_geometry_is_checked_as_the_configs(tmp_path, key, value, message):
    ap, spec = _spec("pretwisted_bar.yaml", tmp_path / "g")
    setattr(spec, key, value)
    with pytest.raises(ap.ConfigError, match=message):
        ap.solve(spec, log=lambda *_: None)
    assert not (tmp_path / "g").exists()


@pytest.mark.parametrize("axis", [None, [0.001, 0.0]], ids=["given point", "point over the centroid rule"])
def test_the_stored_config_says_the_edited_twist_and_axis(tmp_path, axis):
    """pretwisted_bar with twist_deg edited to 90 and twist_axis to [1 mm, 0]: results.h5's
    config_yaml said 60 deg and [0, 0] beside the 90 deg answer, and an axis point set where the
    config gave the centroid rule was ignored (the centroid's answer).  Now the stored config is
    what was solved, and parsed again gives the same tip."""
    from ancf_petsc.config.parse import parse_config
    ap, spec = _spec("pretwisted_bar.yaml", tmp_path / "edited")
    if axis is not None:                         # the config's rule, then a point set on the spec
        spec = parse_config(dict(spec.raw, geometry={"length": 0.1, "twist_deg": 60.0}), base_dir=CONFIGS)
        spec.output.dir = str(tmp_path / "edited")
        spec.twist_axis = axis
    spec.steps, spec.twist_deg = [1.0], 90.0
    assert ap.solve(spec, log=lambda *_: None).status == "completed"
    u_edit = ap.read_results(tmp_path / "edited").probe("tip")[-1]
    with h5py.File(tmp_path / "edited" / "results.h5") as h5:
        stored = yaml.safe_load(h5["model"].attrs["config_yaml"])
    assert stored["geometry"]["twist_deg"] == 90.0
    assert stored["geometry"]["twist_axis"] == (axis or [0.0, 0.0])
    parsed = parse_config(dict(stored, output={"dir": str(tmp_path / "parsed")}), base_dir=CONFIGS)
    ap.solve(parsed, log=lambda *_: None)
    assert ap.read_results(tmp_path / "parsed").probe("tip")[-1] == pytest.approx(u_edit, rel=1e-12, abs=1e-15)


def test_an_edited_section_is_checked_and_stored_as_solved(tmp_path):
    """uniaxial_neohookean with semi_axes edited to [12, 4] mm: solved (u_x 11.09 mm, twice the
    area) while results.h5's config_yaml said [6, 4] mm; cubature_degree 1 ran to 'unstable' (the
    config refuses it).  Now the stored config parsed again gives the same tip; degree 1 refused."""
    from ancf_petsc.config.parse import parse_config
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "edited")
    spec.steps = [1.0]
    spec.beams[0].section.semi_axes = (0.012, 0.004)
    assert ap.solve(spec, log=lambda *_: None).status == "completed"
    u_edit = ap.read_results(tmp_path / "edited").probe("tip")[-1]
    with h5py.File(tmp_path / "edited" / "results.h5") as h5:
        stored = yaml.safe_load(h5["model"].attrs["config_yaml"])
    assert stored["beams"][0]["section"]["semi_axes"] == [0.012, 0.004]
    ap.solve(parse_config(dict(stored, output={"dir": str(tmp_path / "parsed")}), base_dir=CONFIGS),
             log=lambda *_: None)
    assert ap.read_results(tmp_path / "parsed").probe("tip")[-1] == pytest.approx(u_edit, rel=1e-12, abs=1e-15)
    assert u_edit[0] == pytest.approx(0.011092, rel=1e-4)
    ap, spec = _spec("uniaxial_neohookean.yaml", tmp_path / "degree")
    spec.beams[0].section.cubature_degree = 1
    with pytest.raises(ap.ConfigError, match=r"^beams\[0\]\.section\.cubature_degree: must be >= 2; got 1"):
        ap.solve(spec, log=lambda *_: None)
