"""The documentation: a short README that reaches every page, links that resolve, and the
config reference in step with the code's defaults (issue 14)."""
import os
import re

import pytest

from helpers import ROOT

README = os.path.join(ROOT, "README.md")
DOCS = os.path.join(ROOT, "docs")
LINK = re.compile(r"\]\(([^)#\s]+)(#[^)\s]*)?\)")


def _pages():
    return sorted(os.path.join(DOCS, f) for f in os.listdir(DOCS) if f.endswith(".md"))


def _links(path):
    with open(path, encoding="utf-8") as fh:
        text = fh.read()
    base = os.path.dirname(path)
    out = []
    for target, _ in LINK.findall(text):
        if re.match(r"[a-z]+://", target):
            continue
        out.append(os.path.relpath(os.path.normpath(os.path.join(base, target)), ROOT))
    return out


def test_readme_is_short():
    with open(README, encoding="utf-8") as fh:
        assert len(fh.readlines()) < 400


def test_every_docs_page_is_linked_from_the_readme():
    linked = set(_links(README))
    for page in _pages():
        assert os.path.relpath(page, ROOT) in linked, f"{page} is not reachable from README.md"


@pytest.mark.parametrize("path", [README] + _pages(), ids=lambda p: os.path.relpath(p, ROOT))
def test_relative_links_resolve(path):
    missing = [t for t in _links(path) if not os.path.exists(os.path.join(ROOT, t))]
    assert not missing, f"{os.path.relpath(path, ROOT)}: broken links {missing}"


def test_config_reference_shows_the_default_axial_rule():
    from ancf_petsc.config.specs import BeamSpec, DEFAULT_AXIAL_POINTS
    with open(README, encoding="utf-8") as fh:
        text = fh.read()
    assert re.search(rf"^\s+axial_points: {DEFAULT_AXIAL_POINTS}\s+# Gauss points along xi", text, re.M)
    assert BeamSpec.__dataclass_fields__["axial_points"].default == DEFAULT_AXIAL_POINTS


def test_readme_python_api_example_runs(tmp_path):
    """The README's Python example, run as written (from a copy of the repository's configs, in
    a fresh process: ``import ancf_petsc`` initialises nothing until ``solve``)."""
    import shutil
    import subprocess
    import sys

    from helpers import MPI_ENV
    with open(README, encoding="utf-8") as fh:
        text = fh.read()
    code = re.search(r"\*\*Python API\.\*\*.*?```python\n(.*?)```", text, re.S).group(1)
    shutil.copytree(os.path.join(ROOT, "configs"), tmp_path / "configs")
    p = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                       timeout=300, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode == 0, p.stdout + p.stderr
    first, second = p.stdout.splitlines()
    assert first == "completed 0"
    level, disp = second.split(" ", 1)
    assert float(level) == 1.0 and disp.startswith("[") and float(disp.strip("[]").split()[0]) > 0.0


def _table_rows(path: str, heading: str) -> list[list[str]]:
    """The cells of the first table after ``heading`` in a docs page."""
    with open(path, encoding="utf-8") as fh:
        text = fh.read()
    part = text[text.index(heading):]
    rows = re.findall(r"^\|(.+)\|\s*$", part[:part.index("\n\n", part.index("|"))], re.M)
    return [[c.strip() for c in re.split(r"(?<!\\)\|", r)] for r in rows[2:]]


def test_surface_field_table_is_the_registry():
    """docs/running.md lists exactly the registry's fields, in order, with their chart unit and
    where they apply; the README's outputs table names every one."""
    from ancf_petsc.io.surface_fields import SURFACE_FIELDS
    rows = _table_rows(os.path.join(DOCS, "running.md"), "### Surface point fields")
    assert [r[0].strip("`") for r in rows] == list(SURFACE_FIELDS)
    for r in rows:
        f = SURFACE_FIELDS[r[0].strip("`")]
        assert r[2].endswith(f"[{f.unit}]") and r[3] == f.where, r
    with open(README, encoding="utf-8") as fh:
        outputs = [ln for ln in fh if ln.startswith("| `surface_NNNN.vtu`")][0]
    assert all(f"`{name}`" in outputs for name in SURFACE_FIELDS), outputs


def test_geometry_guide_names_every_outline_format():
    """docs/geometry.md's table of sources names every extension of every outline format
    (outline_formats.FORMATS) and the per-outline keys each reads."""
    from ancf_petsc.outline_formats import FORMATS
    rows = _table_rows(os.path.join(DOCS, "geometry.md"), "### Sources of an outline")
    text = "\n".join(" | ".join(r) for r in rows)
    for f in FORMATS.values():
        for e in f.extensions:
            assert e in text, f"docs/geometry.md: no source row names {e} ({f.title})"
        for k in f.keys:
            assert f"{k.name}:" in text, f"docs/geometry.md: no source row shows {k.name}: ({f.title})"


def _config_reference() -> dict:
    """The README's config reference, read as YAML."""
    from ancf_petsc import yamlio
    with open(README, encoding="utf-8") as fh:
        text = fh.read()
    return yamlio.load(re.search(r"## Config reference.*?```yaml\n(.*?)```", text, re.S).group(1))


#: values the reference shows as examples, not as the defaults (its comments say so)
REFERENCE_EXAMPLES = {("solver", "initial_increment"), ("solver", "max_increment"),
                      ("solver", "max_newton_iterations"), ("solver", "options_prefix"),
                      ("contact", "interfaces"), ("contact", "tangential"), ("output", "dir"),
                      ("accuracy", "level"), ("accuracy", "probe")}


def test_config_reference_is_a_config_the_code_accepts():
    """Every key the README's config reference shows is accepted where it stands, and reaches
    the spec (the reference's two beam names made real; steps instead of history and bundle)."""
    import copy
    from ancf_petsc.config.parse import parse_config
    raw = _config_reference()
    for key in ("bundle", "history"):
        raw.pop(key)
    raw["geometry"].pop("sections")
    section = raw["beams"][0]["section"]
    section.pop("compress"), section.pop("spline_degree")     # outline only
    section["semi_axes"] = [0.003, 0.002]
    other = copy.deepcopy(raw["beams"][0])
    other["name"], other["section"]["center"] = "other", [0.0, 0.006]
    raw["beams"].append(other)
    spec = parse_config(raw, base_dir=os.path.join(ROOT, "configs"))
    assert (spec.solver.options_prefix, spec.solver.max_newton_iterations, spec.partition) == ("left_", 2000, "blocks")
    assert spec.contact.tangential.law == "elastic" and spec.contact.tangential.stiffness == 1e10
    assert [b.dofs for b in spec.boundary_conditions][2] == [(0, 1), (0, 2), (1, 0)]
    assert spec.boundary_conditions[3].displacement == [(0, 0, 6e-3)] and spec.boundary_conditions[3].name == "grip"


def test_config_reference_shows_the_defaults():
    """A value the reference shows is the code's default (of a model with contact, whose
    predictor is tangent), unless it is one of the examples its comments name as such."""
    from ancf_petsc.config.parse import parse_config
    ref = _config_reference()
    beam = {"name": "a", "section": {"shape": "circle", "radius": 0.002}, "elements": 2,
            "material": {"model": "neo-hookean", "mu": 1e6, "bulk_modulus": 5e7}}
    raw = {"name": "m", "geometry": {"length": 0.07}, "beams": [beam], "steps": [1.0],
           "boundary_conditions": [{"beam": "a", "node": "first", "fix": "clamped"}],
           "probes": [{"name": "tip", "beam": "a", "node": "last"}], "contact": {},
           "accuracy": {"probe": "tip"}}
    spec = parse_config(raw)
    parts = {"solver": spec.solver, "contact": spec.contact, "output": spec.output,
             "accuracy": spec.accuracy}
    for part, obj in parts.items():
        for key, shown in ref[part].items():
            if (part, key) in REFERENCE_EXAMPLES:
                continue
            default = getattr(obj, key)
            if part == "contact" and key == "projection":
                shown = (shown["axial"], shown["curve"])
            if part == "output" and key == "vtk_compress":
                shown = None if shown == "auto" else shown
            assert default == shown, f"README config reference: {part}.{key}: {shown!r}, the code's default {default!r}"
    b, shown = spec.beams[0], ref["beams"][0]
    for key in ("axial_points", "element", "locking"):
        assert getattr(b, key) == shown[key], key
    for key in ("cubature_degree", "spline_degree", "compress"):
        assert getattr(b.section, key) == shown["section"][key], key


@pytest.mark.slow
def test_globalisation_table_is_what_the_pretwisted_bar_gives():
    """docs/model.md, "Which Newton globalisation?": the pretwisted bar's row is what
    ``ancf-solve configs/pretwisted_bar.yaml -snes_linesearch_type TYPE`` gives (1 rank)."""
    import json
    import tempfile

    from helpers import solve_cli
    rows = _table_rows(os.path.join(DOCS, "model.md"), "**Which Newton globalisation?**")
    row = [r for r in rows if "configs/pretwisted_bar.yaml" in r[0]][0]
    stated = [int(c.strip("*")) for c in row[1:]]
    kinds = [["-snes_linesearch_type", t] for t in ("basic", "bt", "cp", "l2")] + [["-snes_type", "newtontr"]]
    got = []
    with tempfile.TemporaryDirectory() as out:
        for extra in kinds:
            p = solve_cli(os.path.join(ROOT, "configs", "pretwisted_bar.yaml"), timeout=120,
                          extra=["--output-dir", out, "--quiet"] + extra)
            assert p.returncode == 0, p.stderr
            with open(os.path.join(out, "summary.json"), encoding="utf-8") as fh:
                got.append(json.load(fh)["newton_iterations"])
    assert got == stated, f"docs/model.md says {stated}, ancf-solve gives {got}"


def test_readme_sweep_example_names_its_runs(tmp_path):
    """The README's sweep file, beside a copy of configs/: ``ancf-sweep sweep.yaml --dry-run``
    lists the run id the README gives as an example, and writes nothing."""
    import contextlib
    import io

    from apps.ancf_sweep import main
    with open(README, encoding="utf-8") as fh:
        text = fh.read()
    (tmp_path / "sweep.yaml").write_text(re.search(r"```yaml\n(# sweep\.yaml.*?)```", text, re.S).group(1))
    os.symlink(os.path.join(ROOT, "configs"), tmp_path / "configs")
    example = re.search(r"stable id such as\s+`(run_\d+__[^`]+)`", text).group(1)
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        assert main([str(tmp_path / "sweep.yaml"), "--dry-run"]) == 0
    assert re.search(rf"^\s+{re.escape(example)}\s+todo", out.getvalue(), re.M), out.getvalue()
    assert not (tmp_path / "sweeps").exists()


CODE_PATH = re.compile(r"(?<![\w/.])((?:scripts|ancf_petsc|ancf_verify|apps|tests)/[\w/]+\.(?:pyx|py|sh))\b")


@pytest.mark.parametrize("path", [README] + _pages(), ids=lambda p: os.path.relpath(p, ROOT))
def test_named_code_files_exist(path):
    """Every script, module or test a page names by its path exists (a script moved into a
    package leaves no `scripts/...py` for a reader to run)."""
    with open(path, encoding="utf-8") as fh:
        named = set(CODE_PATH.findall(fh.read()))
    missing = sorted(p for p in named if not os.path.exists(os.path.join(ROOT, p)))
    assert not missing, f"{os.path.relpath(path, ROOT)} names files that do not exist: {missing}"


def test_step_table_names_every_group_a_level_writes(tmp_path):
    """docs/running.md, "What each level writes": every dataset and group of a level of a
    run without contact (the uniaxial bar, one level) has its row."""
    import h5py

    from helpers import load_raw, run_inline
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.1]
    run_inline(raw, tmp_path / "out")
    rows = _table_rows(os.path.join(DOCS, "running.md"), "### What each level writes")
    documented = {m for r in rows for m in re.findall(r"`([a-z_]+)[/`]", r[0])}
    with h5py.File(tmp_path / "out" / "results.h5", "r") as f:
        written = set(f["steps/step_0001"])
    assert written <= documented, f"docs/running.md has no row for {sorted(written - documented)}"


def _anchors(path: str) -> set[str]:
    """The heading anchors of a page as GitHub makes them (lower case, punctuation dropped,
    blanks to '-', repeats numbered), outside code blocks."""
    out, seen, code = set(), {}, False
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            if line.startswith("```"):
                code = not code
            m = None if code else re.match(r"^#+\s+(.*?)\s*#*\s*$", line)
            if m:
                s = re.sub(r"[^\w\- ]", "", m.group(1).strip().lower()).replace(" ", "-")
                n = seen.get(s, 0)
                seen[s] = n + 1
                out.add(s if n == 0 else f"{s}-{n}")
    return out


@pytest.mark.parametrize("path", [README] + _pages(), ids=lambda p: os.path.relpath(p, ROOT))
def test_link_anchors_resolve(path):
    """A link to a section (page.md#anchor, or #anchor on the page) names a heading there."""
    with open(path, encoding="utf-8") as fh:
        text = fh.read()
    broken = []
    for target, frag in re.findall(r"\]\(([^)#\s]*)(#[^)\s]*)\)", text):
        if re.match(r"[a-z]+://", target):
            continue
        dest = os.path.normpath(os.path.join(os.path.dirname(path), target)) if target else path
        if dest.endswith(".md") and os.path.exists(dest) and frag[1:] not in _anchors(dest):
            broken.append(target + frag)
    assert not broken, f"{os.path.relpath(path, ROOT)}: links to no heading: {broken}"


def test_paper_refinement_numbers_are_what_the_psi45_column_gives(tmp_path):
    """docs/paper.md, Table 2's refinement notes: the soleus at 400 N with 2 axial points and with
    an end traction (4/8/16 elements) is what configs/achilles_type3_psi45.yaml gives (they said
    6.379/6.370/6.381 and 6.110/6.158/6.178 mm after the runs gave 6.383/6.364/6.367 and
    6.131/6.162/6.191)."""
    import copy

    from helpers import load_raw, probe, run_inline
    with open(os.path.join(DOCS, "paper.md"), encoding="utf-8") as fh:
        text = " ".join(fh.read().split())
    two = re.search(r"With 2 axial points, 4/8/16 elements give ([\d.]+)/([\d.]+)/([\d.]+) mm", text)
    trac = re.search(r"uniform traction weakens the effect \(4/8/16 elements, 3 points: ([\d.]+), "
                     r"([\d.]+), ([\d.]+) mm\)", text)
    base = load_raw("achilles_type3_psi45.yaml")
    for stated, change in ((two, {"axial_points": 2}), (trac, None)):
        got = []
        for n in (4, 8, 16):
            raw = copy.deepcopy(base)
            raw["steps"] = [200.0, 400.0]             # the 400 N state does not depend on the path
            for b in raw["beams"]:
                b["elements"] = n
                b.update(change or {})
            if change is None:
                raw["loads"] = [{"beam": "soleus", "node": "last", "traction_force": [1.0, 0.0, 0.0]}]
            got.append(f"{probe(run_inline(raw, tmp_path / f'{n}_{change}'), 'soleus')[0] * 1e3:.3f}")
        assert list(stated.groups()) == got, f"docs/paper.md says {stated.groups()}, the runs give {got}"


def test_geometry_guide_merge_warnings_are_what_the_mask_example_gives(tmp_path):
    """docs/geometry.md: the mask example at ``merge_tolerance: 2.0e-5`` prints exactly the
    warnings the page shows (``ancf-solve --check``, no solve)."""
    from helpers import solve_cli
    with open(os.path.join(DOCS, "geometry.md"), encoding="utf-8") as fh:
        text = fh.read()
    block = re.search(r"The\s+header says so, with the fix.*?```\n(.*?)```", text, re.S).group(1)
    stated = [ln.strip() for ln in block.splitlines() if ln.strip()]
    with open(os.path.join(ROOT, "configs", "geometry_mask_demo.yaml"), encoding="utf-8") as fh:
        cfg = fh.read()
    geo = os.path.join(ROOT, "configs", "data", "demo_tendon_geometry.yaml")
    cfg = cfg.replace("file: data/demo_tendon_geometry.yaml", f"file: {geo}\n    merge_tolerance: 2.0e-5")
    (tmp_path / "mask.yaml").write_text(cfg)
    p = solve_cli(str(tmp_path / "mask.yaml"), timeout=120,
                  extra=["--check", "--output", str(tmp_path / "g.png")])
    assert p.returncode == 0, p.stderr
    got = [ln.split("]", 1)[1].strip() for ln in p.stdout.splitlines() if "warning:" in ln]
    assert got == stated, f"docs/geometry.md shows {stated}, --check prints {got}"
