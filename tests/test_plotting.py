"""Figures from a real run: 3D surface renders, load-elongation and convergence plots."""
import os

import numpy as np
import pytest

from helpers import CONFIGS, solve_cli

matplotlib = pytest.importorskip("matplotlib")
from matplotlib import image as mpimg  # noqa: E402

from ancf_petsc import plotting  # noqa: E402

PAPER_CSV = os.path.join(CONFIGS, "data", "paper_table1_elongation.csv")


@pytest.fixture(scope="module")
def bar_run(tmp_path_factory):
    """configs/pretwisted_bar.yaml solved by ancf-solve (4 load levels, ~1 s)."""
    out = tmp_path_factory.mktemp("bar")
    proc = solve_cli(os.path.join(CONFIGS, "pretwisted_bar.yaml"),
                     extra=["--output-dir", str(out), "--quiet"], timeout=120)
    assert proc.returncode == 0, proc.stderr
    return out


def assert_picture(path, min_ink=0.05):
    """A PNG that is not blank: varied pixels and a few % of them not white."""
    assert os.path.isfile(path)
    with open(path, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
    img = mpimg.imread(path)[..., :3]
    assert img.shape[0] > 100 and img.shape[1] > 100
    assert img.std() > 0.05
    ink = np.mean(np.any(img < 0.9, axis=-1))
    assert ink > min_ink, f"{path}: only {ink:.1%} non-white pixels"
    # something coloured (the colour map), not only grey axes and text
    chroma = img.max(axis=-1) - img.min(axis=-1)
    assert np.mean(chroma > 0.2) > 0.01
    return img


def test_render_surfaces(bar_run, tmp_path):
    vtu = str(bar_run / "surface_0004.vtu")
    out = plotting.render_surfaces(vtu, str(tmp_path / "bar.png"), title="pretwisted bar",
                                   reference_vtu=str(bar_run / "surface_0000.vtu"))
    assert out == str(tmp_path / "bar.png")
    img = assert_picture(out)
    assert img.shape[1] > img.shape[0]  # long body: a wide picture
    assert_picture(plotting.render_surfaces(vtu, str(tmp_path / "u.png"), color_by="displacement",
                                            view=(10.0, 70.0), clim=(0.0, 5.0)))


def test_render_surfaces_unknown_field(bar_run, tmp_path):
    with pytest.raises(ValueError, match="color_by='stress'.*available: E_xx, J, beam"):
        plotting.render_surfaces(str(bar_run / "surface_0004.vtu"), str(tmp_path / "x.png"),
                                 color_by="stress")
    assert not (tmp_path / "x.png").exists()


def test_field_values(bar_run):
    mesh = plotting.read_surface(str(bar_run / "surface_0004.vtu"))
    e, label = plotting.field_values(mesh, "E_xx")
    assert "[%]" in label and np.allclose(e, 100 * mesh.point_data["E_xx"])
    ux, _ = plotting.field_values(mesh, "displacement_x")
    assert np.allclose(ux, 1e3 * mesh.point_data["displacement"][:, 0])
    grids = mesh.grids()
    assert grids is not None and len(grids) == 1 and grids[0].size == len(mesh.points)


def test_render_pair(bar_run, tmp_path):
    out = plotting.render_pair(str(bar_run / "surface_0002.vtu"), str(bar_run / "surface_0004.vtu"),
                               str(tmp_path / "pair.png"), titles=("half load", "full load"))
    img = assert_picture(out)
    assert img.shape[1] > 2 * img.shape[0]


def test_plot_load_elongation(bar_run, tmp_path):
    table = plotting.read_csv_table(PAPER_CSV)
    loads = table["load_N"]
    curves = {"psi = 0": (list(loads), list(table["psi0_mm"] * 1.01)),
              "psi = 45": (list(loads[::2]), list(table["psi45_mm"][::2] * 0.98))}
    out = plotting.plot_load_elongation(curves, PAPER_CSV, str(tmp_path / "le.png"),
                                        columns={"psi = 0": "psi0_mm", "psi = 45": "psi45_mm"})
    assert_picture(out, min_ink=0.02)
    with pytest.raises(ValueError, match="psi90_mm"):
        plotting.plot_load_elongation(curves, PAPER_CSV, str(tmp_path / "bad.png"),
                                      columns={"psi = 0": "psi90_mm"})
    # a real run's probe as a curve
    lam, ux = plotting.curve_from_summary(str(bar_run / "summary.json"), "tip")
    assert lam == [0.25, 0.5, 0.75, 1.0] and 0 < ux[0] < ux[-1]


def test_plot_convergence(tmp_path):
    ours = {"psi = 0": [(1, 6.0), (2, 6.1), (4, 6.15)], "psi = 45": [(1, 6.1), (2, 6.12), (4, 6.2)]}
    paper = {"psi = 0": [(1, 6.051), (2, 6.089), (4, 6.151)]}
    assert_picture(plotting.plot_convergence(ours, paper, str(tmp_path / "conv.png")),
                   min_ink=0.02)
