"""ancf-solve --check: the model built and drawn without solving (issue 25, docs/geometry.md)."""
import os
import re

import pytest

from helpers import CONFIGS, solve_cli

pytest.importorskip("matplotlib")
from matplotlib import image as mpimg  # noqa: E402

from ancf_petsc.config.parse import load_config  # noqa: E402
from ancf_petsc.model.build import build_model  # noqa: E402

AREA = re.compile(r"beam (\S+): area (\S+) m\^2 \((\S+) mm\^2\), centroid \((\S+), (\S+)\) m")
BORDER = re.compile(r"border (\S+) \((\S+)\): length (\S+) m .*, (contact interface|not in contact)")


def _picture(path):
    """A PNG that is not blank: coloured sections, several % of the pixels inked."""
    assert os.path.getsize(path) > 20_000
    img = mpimg.imread(path)[..., :3]
    assert img.shape[0] > 300 and img.shape[1] > 300
    chroma = img.max(axis=-1) - img.min(axis=-1)
    assert (img < 0.9).any(axis=-1).mean() > 0.05 and (chroma > 0.1).mean() > 0.02


@pytest.mark.parametrize("name, borders, contact", [
    ("achilles_type3_psi45.yaml", 3, True),        # the paper's outlines, pretwisted
    ("geometry_mask_demo.yaml", 3, True),          # an imported subject: geometry.sections, merged
    ("bundle_hex7.yaml", 12, True),                # a bundle
    ("geometry_stations_demo.yaml", 3, False),     # sections varying along x, no contact
])
def test_check_prints_the_model_and_draws_it(tmp_path, name, borders, contact):
    png = tmp_path / "geometry.png"
    p = solve_cli(os.path.join(CONFIGS, name), extra=["--check", "--output", str(png)],
                  cwd=str(tmp_path), timeout=300)
    assert p.returncode == 0, p.stderr
    assert p.stderr == "" and "not solved" in p.stdout and f"picture: {png}" in p.stdout
    assert not (tmp_path / "results").exists()                  # nothing solved, nothing written
    _picture(png)
    model = build_model(load_config(os.path.join(CONFIGS, name)))
    printed = {m[0]: m[1:] for m in AREA.findall(p.stdout)}
    assert list(printed) == [b.name for b in model.beams]
    for beam in model.beams:
        area, area_mm2, cy, cz = map(float, printed[beam.name])
        assert area == pytest.approx(beam.section.area, rel=1e-6)
        assert area_mm2 == pytest.approx(1e6 * beam.section.area, rel=1e-4)
        assert (cy, cz) == pytest.approx(tuple(beam.section.centroid), abs=1e-9)
    found = BORDER.findall(p.stdout)
    assert len(found) == borders
    assert all((kind == "contact interface") == contact for *_, kind in found)
    assert all(float(length) > 0 for _, _, length, _ in found)


def test_border_lengths_match_the_merge_report(tmp_path):
    """The imported subject: each merged border's length is the one the merge reports."""
    p = solve_cli(os.path.join(CONFIGS, "geometry_mask_demo.yaml"),
                  extra=["--check", "--output", str(tmp_path / "g.png")], timeout=300)
    merged = dict(re.findall(r"interface (\S+): ([\d.]+) mm long", p.stdout))
    drawn = {name: 1e3 * float(length) for name, _, length, _ in BORDER.findall(p.stdout)}
    assert merged.keys() == drawn.keys()
    assert all(abs(drawn[k] - float(v)) < 2e-3 for k, v in merged.items())


def test_check_default_picture_goes_to_the_output_dir(tmp_path):
    p = solve_cli(os.path.join(CONFIGS, "pretwisted_bar.yaml"),
                  extra=["--check", "--output-dir", str(tmp_path / "out")], timeout=300)
    assert p.returncode == 0, p.stderr
    _picture(tmp_path / "out" / "geometry.png")
    assert sorted(os.listdir(tmp_path / "out")) == ["geometry.png"]


@pytest.mark.parametrize("extra, message", [
    (["--output", "x.png"], "--output PNG names the picture of --check"),
    (["--check", "--output", "x.pdf"], "give a file name ending in .png"),
    (["--check", "--output", "/nonexistent/x.png"], "cannot write the picture"),
    (["--check", "--restart", "somewhere"], "leave out --restart"),
])
def test_check_input_errors_are_one_line(tmp_path, extra, message):
    p = solve_cli(os.path.join(CONFIGS, "pretwisted_bar.yaml"), extra=extra, cwd=str(tmp_path))
    assert p.returncode == 2 and message in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr


def test_check_config_error_is_one_line(tmp_path):
    raw = open(os.path.join(CONFIGS, "achilles_type3_psi0.yaml")).read()
    bad = tmp_path / "bad.yaml"
    bad.write_text(raw.replace("loop: soleus,", "loop: solues,").replace("data/", CONFIGS + "/data/"))
    p = solve_cli(str(bad), extra=["--check", "--output", str(tmp_path / "g.png")])
    assert p.returncode == 2 and "config error: beams[0].section" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and not (tmp_path / "g.png").exists()


@pytest.mark.mpi
def test_check_under_mpirun_speaks_once(tmp_path):
    png = tmp_path / "g.png"
    p = solve_cli(os.path.join(CONFIGS, "achilles_type3_psi0.yaml"),
                  extra=["--check", "--output", str(png)], ranks=2, timeout=300)
    assert p.returncode == 0, p.stderr
    assert p.stdout.count("[ancf] check ") == 1 and p.stdout.count("picture:") == 1
    _picture(png)
    bad = solve_cli(os.path.join(CONFIGS, "achilles_type3_psi0.yaml"),
                    extra=["--check", "--output", str(tmp_path / "no" / "g.png")], ranks=2, timeout=300)
    assert bad.returncode == 2 and bad.stderr.count("cannot write the picture") == 1
