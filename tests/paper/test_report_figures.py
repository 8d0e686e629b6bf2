"""The figures in an ``ancf-report --out`` directory are the report's own: an earlier report's
figures there, of other runs, read as this one's (``make demo`` says 'plots: report/*.png')."""
import os

from helpers import load_raw, paper_column, report_existing, solved_run


def test_a_report_leaves_no_figure_of_an_earlier_report_in_its_directory(tmp_path):
    """The tendon on 2 elements (its force and slip figures), then the one-element bar (no
    figure) reported into the same --out: the tendon's two figures stayed beside the bar's
    report.md, which names no figure; they are removed now, and a third report of the tendon
    draws them again."""
    tendon = paper_column()
    for b in tendon["beams"]:
        b["elements"] = 2
    tendon["steps"], tendon["output"] = [10.0, 20.0], {"vtk": False}
    bar = load_raw("uniaxial_neohookean.yaml")
    bar["steps"] = [0.5, 1.0]
    runs = [solved_run(tendon, tmp_path, "tendon"), solved_run(bar, tmp_path, "bar")]
    out = tmp_path / "rep"
    figures = {"achilles_type3_psi45_force.png", "achilles_type3_psi45_slip.png"}
    report_existing([runs[0]], out)
    assert figures <= set(os.listdir(out))
    report_existing([runs[1]], out)
    assert not [f for f in os.listdir(out) if f.endswith(".png")] and "png" not in open(out / "report.md").read()
    report_existing([runs[0]], out)
    assert figures <= set(os.listdir(out))


def test_a_report_of_the_papers_sweeps_keeps_the_figures_of_the_one_before(tmp_path):
    """ancf-report --contact after ancf-report (one --out, the same reused runs): the first one's
    figures stay and are listed, so that a later --existing report removes them."""
    from ancf_petsc.paper.figures import FIGURE_LIST, keep_only
    for name in ("load_elongation.png", "figure5.png", "mine.png"):
        (tmp_path / name).write_text("png")
    keep_only(str(tmp_path), [str(tmp_path / "load_elongation.png"), str(tmp_path / "figure5.png")])
    keep_only(str(tmp_path), [], others=True)
    assert (tmp_path / FIGURE_LIST).read_text().split() == ["figure5.png", "load_elongation.png"]
    keep_only(str(tmp_path), [str(tmp_path / "figure5.png")])
    assert sorted(os.listdir(tmp_path)) == sorted([FIGURE_LIST, "figure5.png", "mine.png"])


def test_a_moved_paper_run_draws_its_own_figures(tmp_path):
    """The paper's column solved into A and moved to B (copied from a cluster, or kept aside
    before A was solved again): the figures read results.h5 and the VTUs from A, where
    summary.json says it ran; with A gone figure5_psi45.png and slip_psi45.png were left out with
    no word, with another run in A they drew that run (a 50 MPa soleus: 20 % strain where B's
    Table 1 says 9 %).  Likewise a sweep moved after its runs (paper/runs.summary_of)."""
    import shutil
    from types import SimpleNamespace
    from ancf_petsc.paper.runs import summary_of
    raw = paper_column()
    raw["steps"] = [10.0, 400.0]
    ran = solved_run(raw, tmp_path, "A")
    shutil.move(ran, tmp_path / "B")
    report_existing([str(tmp_path / "B")], tmp_path / "rep")
    assert {"figure5_psi45.png", "slip_psi45.png", "load_elongation.png"} <= set(os.listdir(tmp_path / "rep"))
    moved = summary_of(SimpleNamespace(run=SimpleNamespace(dir=str(tmp_path / "B"))))
    assert moved["output_dir"] == str(tmp_path / "B") and len(moved["steps"]) == 2
