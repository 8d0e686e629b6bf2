"""Bad input: one line naming the key path and the fix, exit code 2, no traceback."""
import copy

import pytest

from ancf_petsc.config.values import ConfigError
from ancf_petsc.config.parse import parse_config
from helpers import CONFIGS, load_raw, solve_cli, write_config

BASE = load_raw("uniaxial_neohookean.yaml")


def mutate(fn):
    raw = copy.deepcopy(BASE)
    fn(raw)
    return raw


def _set(path, value):
    def fn(raw):
        node = raw
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value
    return fn


def _del(path):
    def fn(raw):
        node = raw
        for k in path[:-1]:
            node = node[k]
        del node[path[-1]]
    return fn


BOWTIE = {"shape": "outline", "spline_degree": 1,
          "curves": [{"points": [[0, 0], [0.01, 0.01], [0.01, 0], [0, 0.01], [0, 0]]}]}

CASES = [
    ("unknown key", _set(["beams", 0, "material", "mue"], 1.0), "beams[0].material.mue", "unknown key"),
    ("unknown top key", _set(["geometri"], {}), "geometri", "unknown key"),
    ("wrong type", _set(["beams", 0, "elements"], "four"), "beams[0].elements", "expected an integer"),
    ("wrong type list", _set(["geometry", "twist_axis"], 3), "geometry.twist_axis", "list of 2"),
    ("missing value", _del(["beams", 0, "material", "bulk_modulus"]), "beams[0].material", "bulk_modulus"),
    ("missing top", _del(["steps"]), "steps", "missing"),
    ("mu <= 0", _set(["beams", 0, "material", "mu"], -1.0e6), "beams[0].material.mu", "must be > 0"),
    ("L <= 0", _set(["geometry", "length"], 0.0), "geometry.length", "must be > 0"),
    ("nu >= 0.5", _set(["beams", 0, "material"], {"model": "svk", "E": 1e6, "nu": 0.5}),
     "beams[0].material.nu", "< 0.5"),
    ("bad model", _set(["beams", 0, "material", "model"], "mooney"), "beams[0].material.model", "one of"),
    ("node missing", _set(["boundary_conditions", 0, "node"], 7), "boundary_conditions[0].node",
     "does not exist"),
    ("unknown beam", _set(["loads", 0, "beam"], "rod"), "loads[0].beam", "unknown beam"),
    ("bad element", _set(["beams", 0, "element"], 3344), "beams[0].element", "one of 3363, 33103, 33153, 3333"),
    ("bad locking", _set(["beams", 0, "locking"], "sri"), "beams[0].locking", "one of none, ecm"),
    ("mixed on 3333", lambda raw: raw["beams"][0].update(element="3333", locking="mixed"), "beams[0].locking",
     "'mixed' is not a remedy of element 3333 (mixed projects J onto 1, y, z, where 3333's J already lies"),
    ("ecm on 33153", lambda raw: raw["beams"][0].update(element="33153", locking="ecm"), "beams[0].locking",
     "section's cubic and quartic modes"),
    ("bad fix", _set(["boundary_conditions", 0, "fix"], {"r": "xw"}), "boundary_conditions[0].fix.r",
     "components"),
    ("bad preset", _set(["boundary_conditions", 0, "fix"], "pinned"), "boundary_conditions[0].fix",
     "unknown preset"),
    ("bad vtk_compress", _set(["output", "vtk_compress"], "yes"), "output.vtk_compress",
     "expected true, false or auto"),
    ("steps order", _set(["steps"], [0.5, 0.2]), "steps", "increase"),
    ("negative step", _set(["steps"], [-0.5]), "steps[0]", "> 0"),
    ("both loads", _set(["loads", 0, "force"], [1, 0, 0]), "loads[0]", "exactly one"),
    ("traction mid", _set(["loads", 0], {"beam": "bar", "node": 1, "traction_force": [1, 0, 0]}),
     "loads[0].node", "end section"),
    ("units", _set(["units"], "mm"), "units", "SI"),
    ("petsc nested", _set(["petsc"], {"snes": {"rtol": 1}}), "petsc.snes", "scalars"),
    # it said only 'loads[0]: the load pushes on a fixed component of r at this node'
    ("load on fixed", _set(["boundary_conditions", 0, "node"], "last"), "loads[0].traction_force",
     "bar node last: r.x is held by boundary_conditions[0] ('bar.2'), whose reaction would take this load; "
     "load another node or free that component; got [45.0, 0.0, 0.0]"),
    ("point force on a roller",
     lambda raw: (raw["boundary_conditions"].append({"beam": "bar", "node": -1, "name": "roller", "fix": {"r": "z"}}),
                  raw["loads"].__setitem__(0, {"beam": "bar", "node": "last", "force": [45.0, 0.0, 1.0]})),
     "loads[0].force", "bar node last: r.z is held by boundary_conditions[1] ('roller')"),
    ("self-intersecting outline", _set(["beams", 0, "section"], BOWTIE), "beams[0].section", "intersect"),
    ("even spline degree", _set(["beams", 0, "section"], dict(BOWTIE, spline_degree=6)),     # was a traceback
     "beams[0].section.spline_degree", "must be one of 1, 2, 3, 5, 7: interpolating splines of even degree"),
    ("semi axes", _set(["beams", 0, "section", "semi_axes"], [0.01, -0.002]),
     "beams[0].section.semi_axes[1]", "> 0"),
    ("missing file", _set(["beams", 0, "section"], {"shape": "outline", "file": "nope.yaml", "loop": "x"}),
     "beams[0].section.file", "not found"),
    ("bad loop", _set(["beams", 0, "section"], {"shape": "outline", "file": "data/achilles_type3_sections.yaml",
                                                 "loop": "plantaris"}), "beams[0].section.loop", "soleus"),
    ("partition method", _set(["partition"], {"method": "scotch"}), "partition.method", "metis"),
    ("second support",
     lambda raw: raw["boundary_conditions"].append({"beam": "bar", "node": "first", "fix": "clamped"}),
     "boundary_conditions[1]", "bar node first already has a support (boundary_conditions[0]): merge"),
    ("support names",
     lambda raw: raw["boundary_conditions"].append({"beam": "bar", "node": "last", "fix": {"r": "y"}, "name": "bar.0"}),
     "boundary_conditions[1].name", "duplicate support name 'bar.0' (also boundary_conditions[0])"),
    # 3333 holds r_yy at 0 outside its interpolation: moving it changed nothing (completed)
    ("displacement of a vector 3333 holds",
     lambda raw: (raw["beams"][0].update(element="3333"), raw["boundary_conditions"].append(
         {"beam": "bar", "node": "last", "displacement": {"r_yy": {"x": 0.1}}})),
     "boundary_conditions[1].displacement.r_yy.x", "element 3333 of beam bar does not interpolate r_yy"),
    # a support named like another's default: it said "bar node last already has a support"
    ("a default name taken",
     lambda raw: (raw.update(loads=[]), raw["boundary_conditions"][0].update(name="bar.2"), raw["boundary_conditions"].append(
         {"beam": "bar", "node": "last", "displacement": {"r": {"x": 0.01}}})),
     "boundary_conditions[1]", "this support's default name 'bar.2' is the name of boundary_conditions[0] (on another node)"),
    # two named supports on one node that both held r_x: the later one's value (or the sum of
    # two curves' moves: 0.02 + 0.01) was applied and each reported the whole reaction
    ("one component, two supports",
     lambda raw: raw["boundary_conditions"].append({"beam": "bar", "node": 0, "name": "grip",
                                                    "displacement": {"r": {"x": 0.01}}}),
     "boundary_conditions[1].displacement.r.x", "bar node 0: r.x is also held by boundary_conditions[0] ('bar.0')"),
    ("two displacements of one component",
     lambda raw: (raw.update(loads=[]), raw["boundary_conditions"].extend([
         {"beam": "bar", "node": "last", "name": "a", "displacement": {"r": {"x": 0.02}}},
         {"beam": "bar", "node": -1, "name": "b", "displacement": {"r": {"x": 0.01}}, "curve": [[0, 0], [1, 1]]}])),
     "boundary_conditions[2].displacement.r.x", "r.x is also held by boundary_conditions[1] ('a')"),
    # a curve not at 0 at load factor 0: its load was never solved for (0 Newton iterations, the
    # bar reported unloaded; a displacement's reactions 129 and 898 N, out of equilibrium)
    ("load curve from a load", _set(["loads", 0, "curve"], [[0.5, 1.0], [1.0, 1.0]]),
     "loads[0].curve[0][1]", "must be 0: a run starts at rest"),
    ("displacement curve from a displacement",
     lambda raw: (raw.update(loads=[]), raw["boundary_conditions"].append(
         {"beam": "bar", "node": "last", "displacement": {"r": {"x": 0.01}}, "curve": [[0, 1], [1, 1]]})),
     "boundary_conditions[1].curve[0][1]", "start the curve at [0, 0]; got 1"),
]

BUNDLE = {"count": 7, "fascicle_section": "hexagon", "radius": 0.5e-3, "elements": 2, "force": [1, 0, 0],
          "material": {"model": "neo-hookean", "mu": 1e8, "bulk_modulus": 1e9}}


def _bundle(**change):
    def fn(raw):
        for k in ("beams", "boundary_conditions", "loads", "probes"):
            raw.pop(k, None)
        raw["bundle"] = {**copy.deepcopy(BUNDLE), **change}
        raw["bundle"] = {k: v for k, v in raw["bundle"].items() if v is not None}
    return fn


CASES += [
    ("bundle count", _bundle(count=8), "bundle.count", "7"),
    ("bundle section", _bundle(fascicle_section="square"), "bundle.fascicle_section", "hexagon"),
    ("bundle radius", _bundle(radius=-1.0), "bundle.radius", "> 0"),
    ("bundle missing", _bundle(force=None), "bundle", "force"),
    ("bundle gap of hexagons", _bundle(fascicle_section="hexagon", gap=2e-4), "bundle.gap", "circle fascicles only"),
    ("bundle arc of hexagons", _bundle(fascicle_section="hexagon", arc_deg=40), "bundle.arc_deg", "remove it"),
    ("matrix format", _set(["solver"], {"matrix": "dense"}), "solver.matrix", "one of"),
    ("linear solver", _set(["solver"], {"linear": "gmres"}), "solver.linear", "fieldsplit"),
    ("section update", _set(["solver"], {"section_update": "twist"}), "solver.section_update", "rotation"),
    ("tangent", _set(["solver"], {"tangent": "mip"}), "solver.tangent", "mixed"),
    # values that ran until killed or crawled (2026-12-06): 4e14 increments, steps held to 1e-9
    # band widths
    ("max increment too small", _set(["solver"], {"max_increment": 1e-12}), "solver.max_increment",
     "increments to load factor 1; give at least 1e-05"),
    ("band step too small", _set(["solver"], {"band_step": 1e-9}), "solver.band_step", "give 0 (off) or at least 0.1"),
    ("bundle with beams", lambda raw: (raw.__setitem__("bundle", copy.deepcopy(BUNDLE))), "beams", "bundle"),
    # a degree-1 section rule (one point on a rectangle, two angles on the z axis of an ellipse):
    # the 8-element elastica failed after 165 Newton iterations, or ended unstable at a third of its deflection
    ("cubature degree one", _set(["beams", 0, "section", "cubature_degree"], 1),
     "beams[0].section.cubature_degree", "must be >= 2; got 1: a rule of degree 1 does not integrate y^2, z^2"),
    ("bundle cubature degree one", _bundle(cubature_degree=1), "bundle.cubature_degree", "must be >= 2; got 1"),
    # ecm's nu = 0 part loads 3363's quadratic modes with another axial stress than a GOH law's: one
    # element in uniaxial tension (kappa 0.2 along x) completed 0.92 % long, r_yy.x -13.6 /m, r_y.y != r_z.z
    ("ecm on 3363 with GOH",
     lambda raw: raw["beams"][0].update(locking="ecm", material={
         "model": "goh", "mu": 1e6, "bulk_modulus": 50e6, "k1": 2e6, "k2": 5.0, "kappa": 0.2}),
     "beams[0].locking", "'ecm' on element 3363 with a fibre law loads the quadratic modes"),
    # element: null read "got 'None'", a list "got '[3363]'" (the value turned into a string)
    ("element null", _set(["beams", 0, "element"], None), "beams[0].element",
     "expected one of 3363, 33103, 33153, 3333; got null"),
    ("element list", _set(["beams", 0, "element"], [3363]), "beams[0].element", "; got [3363]"),
    # one material for all beams at the top level: was 'unknown key; allowed here: ...', no place or fix
    ("top-level material", _set(["material"], dict(BASE["beams"][0]["material"])), "material",
     "is given per beam, as beams[i].material (one for several beams: material: &m {...} on the first, "
     "material: *m on the others; a bundle: bundle.material); got material: at the top level"),
    # read by nothing without the ParaView files: accepted, and ignored, before
    ("vtk_samples, vtk off", lambda raw: raw["output"].update(vtk=False, vtk_samples=8), "output.vtk_samples",
     "applies to the ParaView files, which output.vtk: false turns off; remove it or set output.vtk: true; got 8"),
    ("vtk_compress, vtk off", lambda raw: raw["output"].update(vtk=False, vtk_compress=True), "output.vtk_compress",
     "which output.vtk: false turns off"),
]


@pytest.mark.parametrize("name,fn,path,text", CASES, ids=[c[0] for c in CASES])
def test_error_names_key_path(name, fn, path, text):
    from ancf_petsc.model.build import build_model
    raw = mutate(fn)
    with pytest.raises(ConfigError) as err:
        build_model(parse_config(raw, base_dir=CONFIGS))   # sections are checked at build
    msg = str(err.value)
    assert msg.startswith(path + ":") or msg.startswith(path + "."), msg
    assert text in msg, msg
    assert "\n" not in msg


@pytest.mark.parametrize("name,fn,path,text", [CASES[0], CASES[6], CASES[10], CASES[21]],
                         ids=["unknown-key", "mu", "node", "outline"])
def test_cli_reports_one_line_and_exit_code_2(tmp_path, name, fn, path, text):
    raw = mutate(fn)
    raw["output"]["dir"] = str(tmp_path / "out")
    cfg = write_config(raw, tmp_path / "bad.yaml")
    p = solve_cli(cfg)
    assert p.returncode == 2, p.stderr
    assert "Traceback" not in p.stderr
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and path in lines[0] and text in lines[0], p.stderr


def test_cli_yaml_syntax_and_missing_file(tmp_path):
    bad = tmp_path / "broken.yaml"
    bad.write_text("name: x\ngeometry: {length: 0.1\nbeams: []\n")
    p = solve_cli(str(bad))
    assert p.returncode == 2 and "YAML syntax error at line" in p.stderr and "Traceback" not in p.stderr
    p = solve_cli(str(tmp_path / "missing.yaml"))
    assert p.returncode == 2 and "no such config file" in p.stderr


@pytest.mark.mpi
def test_cli_config_error_under_mpi_is_one_line(tmp_path):
    raw = mutate(CASES[6][1])
    cfg = write_config(raw, tmp_path / "bad.yaml")
    p = solve_cli(cfg, ranks=2)
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert sum("config error" in ln for ln in p.stderr.splitlines()) == 1, p.stderr


@pytest.mark.mpi
@pytest.mark.parametrize("arg", [["-snes_max_it", "abc"], ["-pc_type", "nosuch"], ["--outputdir", "x"]])
def test_command_line_errors_under_mpi_are_one_line(tmp_path, arg):
    """Found before MPI starts, printed by the launcher's rank 0 only (it was once per rank)."""
    cfg = write_config(copy.deepcopy(BASE), tmp_path / "ok.yaml")
    p = solve_cli(cfg, ranks=2, extra=arg)
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert sum(ln.startswith("ancf-solve: ") for ln in p.stderr.splitlines()) == 1, p.stderr


def test_repeated_keys_are_an_error_naming_both_lines(tmp_path):
    """Appending ``steps: [1.0]`` and ``loads: []`` gave a zero-load run reported completed
    (PyYAML keeps the last value): now one line naming the key and both lines, exit 2."""
    with open(f"{CONFIGS}/uniaxial_neohookean.yaml") as fh:
        text = fh.read()
    first = 1 + next(i for i, ln in enumerate(text.splitlines()) if ln.startswith("steps:"))
    cfg = tmp_path / "twice.yaml"
    cfg.write_text(text + "\nsteps: [1.0]\nloads: []\n")
    p = solve_cli(str(cfg))
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode == 2 and len(lines) == 1, p.stderr
    assert "duplicate key 'steps'" in lines[0] and f"first at line {first}" in lines[0]


def test_a_key_repeated_on_one_line_is_an_error_too():
    """``{..., column: sol, column: gm}`` loaded the second value silently (the duplicate test
    compared lines only): a load history then took another muscle's column."""
    from ancf_petsc import yamlio
    with pytest.raises(yamlio.ConstructorError,
                       match=r"duplicate key 'column' \(first at line 2, column 32\)"):
        yamlio.load("loads:\n  - {beam: soleus, node: last, column: sol, column: gm}\n")
    with pytest.raises(yamlio.ConstructorError, match=r"duplicate key 'name' \(first at line 1\)"):
        yamlio.load("name: x\nname: y\n")
    anchors = "a: &d {k: 1}\nb: *d\nc: {<<: *d, k: 2}\n"      # aliases and merges are no repeats
    assert yamlio.load(anchors) == {"a": {"k": 1}, "b": {"k": 1}, "c": {"k": 2}}


def test_an_alias_bomb_is_shown_by_its_first_elements():
    """A 400-byte YAML document whose aliases expand to 9^10 values under ``name``: the error
    message shows a few elements (building the whole value took ~1 GB)."""
    items = ["&a [x,x,x,x,x,x,x,x,x]"] + [f"&{n} [" + ",".join([f"*{p}"] * 9) + "]"
                                           for p, n in zip("abcdefghij", "bcdefghijk")]
    from ancf_petsc import yamlio
    raw = yamlio.load("name: [" + ", ".join(items) + "]\ngeometry: {length: 1}\nbeams: []\nsteps: [1]\n")
    with pytest.raises(ConfigError) as err:
        parse_config(raw)
    assert len(str(err.value)) < 200 and "name" in str(err.value)


@pytest.mark.parametrize("program", ["ancf-study", "ancf-sweep"])
def test_study_and_sweep_files_that_are_not_yaml_text(tmp_path, program):
    """A binary file or a directory given as a study/sweep file: one line, exit 2 (a
    UnicodeDecodeError traceback before)."""
    import os
    import subprocess
    from helpers import MPI_ENV, ROOT, VENV_BIN
    for arg, words in (("/bin/ls", "not a text (UTF-8) YAML file"), (str(tmp_path), "is a directory")):
        p = subprocess.run([os.path.join(VENV_BIN, program), arg], capture_output=True, text=True,
                           cwd=ROOT, env=dict(os.environ, **MPI_ENV), timeout=120)
        lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
        assert p.returncode == 2 and len(lines) == 1 and words in lines[0], p.stderr
        assert lines[0].count(arg) == 1
