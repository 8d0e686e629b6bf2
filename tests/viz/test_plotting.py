"""Figures from a real run: 3D surface renders, load-elongation and convergence plots."""
import os

import numpy as np
import pytest

from helpers import CONFIGS, ROOT, solved_config, solved_run

matplotlib = pytest.importorskip("matplotlib")
from matplotlib import image as mpimg  # noqa: E402

from ancf_petsc import viz

PAPER_CSV = os.path.join(CONFIGS, "data", "paper_table1_elongation.csv")


@pytest.fixture(scope="module")
def bar_run(tmp_path_factory):
    """configs/pretwisted_bar.yaml solved by ancf-solve (4 load levels, ~1 s)."""
    return solved_config(tmp_path_factory, "pretwisted_bar.yaml", timeout=120)


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
    out = viz.render_surfaces(vtu, str(tmp_path / "bar.png"), title="pretwisted bar",
                                   reference_vtu=str(bar_run / "surface_0000.vtu"))
    assert out == str(tmp_path / "bar.png")
    img = assert_picture(out)
    assert img.shape[1] > img.shape[0]  # long body: a wide picture
    assert_picture(viz.render_surfaces(vtu, str(tmp_path / "u.png"), color_by="displacement",
                                            view=(10.0, 70.0), clim=(0.0, 5.0)))


def test_render_surfaces_unknown_field(bar_run, tmp_path):
    with pytest.raises(ValueError, match="color_by='stress'.*available: E_xx, J, beam"):
        viz.render_surfaces(str(bar_run / "surface_0004.vtu"), str(tmp_path / "x.png"),
                                 color_by="stress")
    assert not (tmp_path / "x.png").exists()


def test_field_values(bar_run):
    mesh = viz.read_surface(str(bar_run / "surface_0004.vtu"))
    e, label = viz.field_values(mesh, "E_xx")
    assert "[%]" in label and np.allclose(e, 100 * mesh.point_data["E_xx"])
    ux, _ = viz.field_values(mesh, "displacement_x")
    assert np.allclose(ux, 1e3 * mesh.point_data["displacement"][:, 0])
    grids = mesh.grids()
    assert grids is not None and len(grids) == 1 and grids[0].size == len(mesh.points)


def test_render_pair(bar_run, tmp_path):
    out = viz.render_pair(str(bar_run / "surface_0002.vtu"), str(bar_run / "surface_0004.vtu"),
                               str(tmp_path / "pair.png"), titles=("half load", "full load"))
    img = assert_picture(out)
    assert img.shape[1] > 2 * img.shape[0]


def test_plot_load_elongation(bar_run, tmp_path):
    table = viz.read_csv_table(PAPER_CSV)
    loads = table["load_N"]
    curves = {"psi = 0": (list(loads), list(table["psi0_mm"] * 1.01)),
              "psi = 45": (list(loads[::2]), list(table["psi45_mm"][::2] * 0.98))}
    out = viz.plot_load_elongation(curves, PAPER_CSV, str(tmp_path / "le.png"),
                                        columns={"psi = 0": "psi0_mm", "psi = 45": "psi45_mm"})
    assert_picture(out, min_ink=0.02)
    with pytest.raises(ValueError, match="psi90_mm"):
        viz.plot_load_elongation(curves, PAPER_CSV, str(tmp_path / "bad.png"),
                                      columns={"psi = 0": "psi90_mm"})
    # a real run's probe as a curve
    lam, ux = viz.curve_from_summary(str(bar_run / "summary.json"), "tip")
    assert lam == [0.25, 0.5, 0.75, 1.0] and 0 < ux[0] < ux[-1]


def test_plot_convergence(tmp_path):
    ours = {"psi = 0": [(1, 6.0), (2, 6.1), (4, 6.15)], "psi = 45": [(1, 6.1), (2, 6.12), (4, 6.2)]}
    paper = {"psi = 0": [(1, 6.051), (2, 6.089), (4, 6.151)]}
    assert_picture(viz.plot_convergence(ours, paper, str(tmp_path / "conv.png")),
                   min_ink=0.02)


# ---------------------------------------------------------------- charts people read (issue 14)
def _rows(spec):
    """Study rows (element, axial points, degree, elements, wall time, error, pareto)."""
    from ancf_petsc.workflows.study import Row
    return [Row(label="", element=e, elements=n, axial_points=a, cubature_degree=d, dofs=18 * (2 * n + 1),
                gauss_points=0, status="completed", value=1.0, wall_time=t, newton_iterations=10,
                rel_error=err, pareto=p) for e, a, d, n, t, err, p in spec]


def _labelled_ticks(axis):
    lo, hi = sorted(axis.get_view_interval())
    return [t.get_text() for t, v in zip(axis.get_majorticklabels(), axis.get_majorticklocs())
            if lo <= v <= hi and t.get_text()]


@pytest.mark.parametrize("lo,hi", [(4.5, 60.0), (1.3e-3, 3.1e-2), (0.05, 0.09), (1e-16, 2.0), (7.0, 9.0)])
def test_log_ticks_give_at_least_two_labels(lo, hi):
    from ancf_petsc.viz.charts import log_ticks, tick_label
    ticks = log_ticks(lo, hi)
    assert len(ticks) >= 2 or hi / lo < 1.5
    assert all(lo <= t <= hi for t in ticks)
    labels = [tick_label(t) for t in ticks]
    assert len(set(labels)) == len(labels) and all(labels)
    assert tick_label(2e-4) == "2×10⁻⁴" and tick_label(1e-5) == "10⁻⁵" and tick_label(0.05) == "0.05"


def test_pareto_chart_axes_labels_and_legend_are_readable(tmp_path):
    """A narrow study (the Achilles one spans one decade in time and error) still gets two or
    more labelled ticks per axis; a cluster of runs gets labels that do not overlap; the legend
    is in words."""
    from ancf_petsc.viz.charts import pareto_figure, text_overlaps
    spec = [("3363", 2, 4, 4, 6.7, 1.6e-3, True), ("3363", 2, 4, 8, 32.0, 3.0e-3, False),
            ("3363", 2, 4, 16, 53.0, 1.3e-3, True), ("3363", 3, 4, 4, 5.7, 2.6e-2, True),
            ("3363", 3, 4, 8, 13.0, 1.4e-2, False), ("3363", 3, 4, 16, 36.0, 7.2e-3, False),
            ("3333", 2, 4, 4, 5.5, 2.7e-2, True), ("3333", 2, 4, 8, 4.8, 2.7e-2, True),
            ("3333", 2, 4, 16, 16.0, 2.7e-2, False)]
    # a tight cluster: eight runs within a few per cent of each other in time and error
    spec += [("3333", 3, 4, n, 10.0 * (1 + 0.02 * k), 2.0e-2 * (1 + 0.03 * k), False)
             for k, n in enumerate((1, 2, 4, 8, 16, 32, 64, 128))]
    fig, ax, labels = pareto_figure(_rows(spec), "achilles psi45: x-displacement of probe 'soleus'")
    fig.canvas.draw()
    assert len(_labelled_ticks(ax.xaxis)) >= 2 and len(_labelled_ticks(ax.yaxis)) >= 2
    assert labels and not text_overlaps(fig, labels)
    box = ax.bbox.extents
    renderer = fig.canvas.get_renderer()
    from matplotlib.text import Text
    for t in labels:
        x0, y0, x1, y1 = Text.get_window_extent(t, renderer).extents
        assert box[0] - 0.5 <= x0 and x1 <= box[2] + 0.5 and box[1] - 0.5 <= y0 and y1 <= box[3] + 0.5
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "3363, 2 axial Gauss points" in legend and not any("_" in t for t in legend)
    # the front's labels are placed first, so all four Pareto runs are labelled
    assert sum(t.get_text() in ("4", "8") for t in labels) >= 4


def test_stability_chart_speaks_words(tmp_path):
    from ancf_petsc.viz.charts import axis_words, stability_chart
    assert axis_words("bulk_ratio", 100) == "K/μ = 100"
    assert axis_words("element", "3333-none") == "element 3333 without ecm"
    assert axis_words("contact", "unilateral") == "unilateral contact"
    cells = [{"increment": inc, "linesearch": ls, "bulk_ratio": k, "status": st, "iterations": 12,
              "short": "max it", "rel_error": 0.02}
             for inc in ("adaptive", 0.5) for ls in ("basic", "bt") for k in (10, 1000)
             for st in (("completed",) if inc == "adaptive" else ("failed",))]
    assert_picture(stability_chart(cells, str(tmp_path / "s.png"), "bulk_ratio", "", "increment",
                                   "linesearch"), min_ink=0.05)


def test_figure5_view_runs_x_from_0_to_L_left_to_right():
    """Figure 5's camera (report.FIGURE5_VIEW) puts x = 0 left of x = L on the screen, by
    matplotlib's own 3D projection; the old view (8, 70) ran it right to left."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d import proj3d
    from ancf_petsc.paper import FIGURE5_VIEW

    def screen_x(view):
        fig = Figure()
        FigureCanvasAgg(fig)
        ax = fig.add_subplot(projection="3d")
        ax.set_xlim(0, 70)
        ax.set_ylim(0, 10)
        ax.set_zlim(-8, 0)
        ax.view_init(*view)
        fig.canvas.draw()
        xs, _, _ = proj3d.proj_transform(np.array([0.0, 70.0]), np.array([5.0, 5.0]),
                                         np.array([-4.0, -4.0]), ax.get_proj())
        return xs

    xs = screen_x(FIGURE5_VIEW)
    assert xs[1] > xs[0]
    old = screen_x((8.0, 70.0))
    assert old[1] < old[0]


def test_load_elongation_legend_has_no_csv_column_names(tmp_path, monkeypatch):
    from ancf_petsc.viz import figures
    table = viz.read_csv_table(PAPER_CSV)
    curves = {"ψ = 0°": (list(table["load_N"]), list(table["psi0_mm"]))}
    captured = {}
    real_save = figures.save_figure

    def grab(fig, out_png):
        captured["fig"] = fig
        return real_save(fig, out_png)
    monkeypatch.setattr(figures, "save_figure", grab)
    viz.plot_load_elongation(curves, PAPER_CSV, str(tmp_path / "le.png"), {"ψ = 0°": "psi0_mm"})
    legend = [t.get_text() for ax in captured["fig"].axes if ax.get_legend()
              for t in ax.get_legend().get_texts()]
    assert legend == ["ψ = 0° (this code)", "ψ = 0° (paper)"]


def test_the_interface_study_chart_gives_every_law_its_own_style(tmp_path):
    """Issue 39: the non-uniformity figure reused three colours among its 15 laws."""
    from ancf_petsc.viz import plot_law_differences
    from ancf_petsc.viz.law_charts import law_style
    from ancf_verify.studies import interface_study as study
    labels = [law[0] for law in study.LAWS]
    styles = {str(law_style(label, labels)) for label in labels}
    assert len(labels) == 15 and len(styles) == 15
    steps = [{"load_factor": f, "displacement_differences": {"a|b": {"end": 1e-5 * f}}} for f in (10.0, 20.0)]
    runs = [{"loading": "soleus", "law": label, "elements": 4, "status": "completed", "steps": steps} for label in labels]
    out = plot_law_differences(runs, labels, ["soleus"], "a|b", 4, str(tmp_path / "laws.png"))
    assert os.path.getsize(out) > 10_000


def test_a_history_without_neighbours_draws_no_empty_difference_panel(tmp_path):
    """A load history of one beam (no contact, no displacement_differences) drew a third panel,
    'end displacement difference [mm]', with nothing in it; it now has the force and strain
    panels alone, and a run with a pair keeps all three."""
    from ancf_petsc.viz.history import plot_history

    def summary(diff):
        steps = [{"load_factor": k, "frame": k, "time": 0.1 * k,
                  "subtendons": {"bar": {"end_force": [10.0 * k, 0, 0], "strain": 0.01 * k}},
                  **({"displacement_differences": {"bar_other": {"end": 1e-4 * k}}} if diff else {})}
                 for k in (1, 2, 3)]
        return {"steps": steps}
    heights = [mpimg.imread(plot_history(summary(diff), str(tmp_path / f"h{diff}.png"))).shape[0]
               for diff in (False, True)]
    assert heights[0] < 0.75 * heights[1]


def _fibre_and_plain_beams() -> dict:
    """Two 40 mm bars side by side (no contact), pulled at their tips: the first fibre-reinforced
    (GOH, fibres along x), the second neo-Hookean, so the VTU's fibre fields are NaN on it."""
    def beam(name, y0, material):
        return {"name": name, "elements": 1, "material": material,
                "section": {"shape": "ellipse", "semi_axes": [0.003, 0.002], "center": [y0, 0.0]}}
    goh = {"model": "goh", "mu": 1e6, "bulk_modulus": 50e6, "k1": 2e6, "k2": 5.0, "kappa": 0.0}
    neo = {"model": "neo-hookean", "mu": 1e6, "bulk_modulus": 50e6}
    return {"name": "fibre_and_plain", "units": "SI", "geometry": {"length": 0.04, "twist_axis": "origin"},
            "beams": [beam("fibres", -0.004, goh), beam("plain", 0.004, neo)],
            "boundary_conditions": [{"beam": b, "node": "first", "fix": "reduced"} for b in ("fibres", "plain")],
            "loads": [{"beam": b, "node": "last", "traction_force": [2.0, 0.0, 0.0]} for b in ("fibres", "plain")],
            "steps": [1.0]}


def test_a_field_of_one_beam_colours_it_and_greys_the_others(tmp_path):
    """fibre_stress is NaN on a beam without fibres: the render drew no face at all (the colour
    scale's limits were NaN; its bar read -0.1..0.1 MPa); now the fibre beam is coloured over the
    range of its values and the other beam is light grey."""
    run = solved_run(_fibre_and_plain_beams(), tmp_path)
    vtu = os.path.join(run, "surface_0001.vtu")
    stress = viz.read_surface(vtu).point_data["fibre_stress"]
    assert np.isnan(stress).any() and np.isfinite(stress).any()
    img = mpimg.imread(viz.render_surfaces(vtu, str(tmp_path / "f.png"), color_by="fibre_stress",
                                           view=(30.0, -90.0)))[..., :3]
    axes = img[:, : img.shape[1] - 220]                  # the 3D axes, left of the colour bar
    chroma = axes.max(axis=-1) - axes.min(axis=-1)
    grey = (chroma < 0.03) & (axes.mean(axis=-1) > 0.4) & (axes.mean(axis=-1) < 0.85)
    assert np.mean(chroma > 0.2) > 0.03, "the fibre beam is not coloured"
    assert np.mean(grey) > 0.03, "the beam without fibres is not drawn"
