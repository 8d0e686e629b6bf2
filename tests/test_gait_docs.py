"""docs/gait.md: its envelope tables are the committed CSVs' (docs/gait_envelope_*.csv, written by
scripts/bench_envelope.py --csv), rendered by workflows.envelope.render_docs."""
import os

import pytest

from ancf_petsc.workflows.envelope import render_docs

DOCS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "docs")


def test_envelope_tables_match_their_csvs():
    text = open(os.path.join(DOCS, "gait.md")).read()
    assert text.count("<!-- envelope:") >= 2
    assert render_docs(text, DOCS) == text


def test_a_block_filter_picks_its_rows(tmp_path):
    """Friction cells share twist and bias with the frictionless ones: ``:friction=0.3`` picks."""
    import csv
    head = ["base", "law", "friction", "twist", "bias", "elements", "stride", "status", "last_level",
            "iterations", "iterations_to_1200", "cutbacks", "cutbacks_to_1200", "levels",
            "median_iterations", "cutback_levels", "solve_time", "wall_time", "message", "solver"]
    rows = [dict(zip(head, ["a.yaml", "sliding", mu, 90.0, "uniform", 4, False, "completed", 3000,
                            its, its, 0, 0, 12, 3, 0, 1.0, 1.0, "", "after"])) for mu, its in ((0.0, 41), (0.3, 57))]
    with open(tmp_path / "gait_envelope_friction.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=head)
        w.writeheader()
        w.writerows(rows)
    text = "<!-- envelope:friction:sliding:friction=0.3 -->\n<!-- /envelope -->"
    out = render_docs(text, str(tmp_path))
    assert "| 90 | 57 |" in out and "41" not in out
    out = render_docs("<!-- envelope:friction:sliding:friction=0 -->\n<!-- /envelope -->", str(tmp_path))
    assert "| 90 | 41 |" in out and "57" not in out


def test_a_cell_that_switched_to_pointwise_fade_forces_says_where():
    """``contact.fade_forces: auto`` (solving/fade_switch.py): a row with
    ``fade_forces_pointwise_from`` ends its table cell with where the run switched; the
    ``CellResult`` row carries it from summary.json."""
    from ancf_petsc.workflows.envelope import CellResult, EnvelopeCell, markdown_table
    base = {"base": "a.yaml", "law": "unilateral", "friction": "0.0", "bias": "soleus", "elements": "8",
            "status": "completed", "last_level": "3000", "iterations": "420", "iterations_to_1200": "109",
            "cutbacks": "19", "cutbacks_to_1200": "0", "cutback_levels": "2", "median_iterations": "15.5"}
    rows = [dict(base, twist="135", stride="False", fade_forces_pointwise_from=""),
            dict(base, twist="150", stride="False", fade_forces_pointwise_from="2468.75")]
    text = markdown_table(rows, law="unilateral")
    assert "| 150 | 109, pointwise from 2469 N |" in text and "| 135 | 109 |" in text
    strides = [dict(base, twist="120", stride="True", fade_forces_pointwise_from="35.7169")]
    assert "pointwise from frame 35.72" in markdown_table(strides, law="unilateral", key="median_iterations")
    cell = EnvelopeCell("a.yaml", 150.0, "soleus", "unilateral", elements=8)
    assert CellResult(cell, "completed", pointwise_from=2468.75).row()["fade_forces_pointwise_from"] == 2468.75
    assert CellResult(cell, "completed").row()["fade_forces_pointwise_from"] == ""


def test_a_cell_that_snapped_past_a_critical_point_says_where(tmp_path):
    """A run that snapped (solving/critical_point.py) ends its table cell with the critical
    states' load levels; the ``CellResult`` row carries them from summary.json's branch switches
    (a bifurcation's switch has no ``critical_load_factor`` and is not listed)."""
    import json
    from ancf_petsc.workflows.envelope import NEO, CellResult, EnvelopeCell, markdown_table, run_cell
    base = {"base": "a.yaml", "law": "own", "friction": "0.0", "bias": "soleus", "elements": "4",
            "status": "completed", "last_level": "3000", "iterations": "1500", "iterations_to_1200": "1400",
            "cutbacks": "20", "cutbacks_to_1200": "20", "cutback_levels": "1", "median_iterations": "3",
            "fade_forces_pointwise_from": ""}
    rows = [dict(base, twist="120", stride="False", snaps="7.27152"), dict(base, twist="105", stride="False")]
    text = markdown_table(rows)
    assert "| 120 | 1400 (20 cut-backs), snap at 7.272 N |" in text and "| 105 | 1400 (20 cut-backs) |" in text
    strides = [dict(base, twist="150", stride="True", snaps="41.5;60.25")]
    assert "snap at frame 41.5, snap at frame 60.25" in markdown_table(strides, key="median_iterations")
    cell = EnvelopeCell(NEO, 120.0, "soleus", "unilateral")
    assert CellResult(cell, "completed", snaps=(7.27152,)).row()["snaps"] == "7.27152"
    assert CellResult(cell, "completed").row()["snaps"] == ""
    # from summary.json: a fake ancf-solve that writes one
    summary = {"status": "completed", "newton_iterations": 9, "steps": [
        {"load_factor": 30.0, "iterations": 9, "cutbacks": 0, "branch_switches": [
            {"kind": "bifurcation", "load_factor": 12.0},
            {"kind": "limit point", "load_factor": 20.02, "critical_load_factor": 20.0}]}]}
    fake = tmp_path / "fake-solve"
    fake.write_text("#!/bin/sh\nmkdir -p \"$3\"\ncat > \"$3/summary.json\" <<'END'\n" + json.dumps(summary)
                    + "\nEND\n")
    fake.chmod(0o755)
    res = run_cell(cell, [str(fake)], str(tmp_path / "work"))
    assert res.status == "completed" and res.snaps == (20.0,) and res.row()["snaps"] == "20"


def test_a_cell_whose_search_windows_widened_says_from_where(tmp_path):
    """A run whose contact search windows became the whole partner beam (solving/window_widening.py)
    says from which load in its table cell; the row carries summary.json's
    ``search_window_whole_from`` (empty without a widening, and in the CSVs written before it)."""
    import json
    from ancf_petsc.workflows.envelope import NEO, CellResult, EnvelopeCell, markdown_table, run_cell
    base = {"base": "a.yaml", "law": "own", "friction": "0.0", "bias": "soleus", "elements": "4",
            "status": "completed", "last_level": "3000", "iterations": "1500", "iterations_to_1200": "1400",
            "cutbacks": "20", "cutbacks_to_1200": "20", "cutback_levels": "1", "median_iterations": "3",
            "fade_forces_pointwise_from": "", "snaps": "4.6705", "stride": "False"}
    text = markdown_table([dict(base, twist="150", search_window_whole_from="4.6705"), dict(base, twist="135")])
    assert "| 150 | 1400 (20 cut-backs), whole windows from 4.67 N, snap at 4.67 N |" in text
    assert "| 135 | 1400 (20 cut-backs), snap at 4.67 N |" in text
    cell = EnvelopeCell(NEO, 150.0, "soleus", "unilateral")
    assert CellResult(cell, "completed").row()["search_window_whole_from"] == ""
    summary = {"status": "completed", "newton_iterations": 9, "search_window_whole_from": 4.6705,
               "steps": [{"load_factor": 30.0, "iterations": 9, "cutbacks": 0}]}
    fake = tmp_path / "fake-solve"
    fake.write_text("#!/bin/sh\nmkdir -p \"$3\"\ncat > \"$3/summary.json\" <<'END'\n" + json.dumps(summary)
                    + "\nEND\n")
    fake.chmod(0o755)
    res = run_cell(cell, [str(fake)], str(tmp_path / "work"))
    assert res.windows_from == 4.6705 and res.row()["search_window_whole_from"] == 4.6705


def test_a_stride_cell_states_its_cut_backs_and_total_newton_iterations():
    """A stride's median per frame hides a frame that cut back many times: the cell also says
    how many cut-backs in how many frames and the stride's Newton iterations in all (the 120 deg
    uniform unilateral stride: median 4, but 19 cut-backs in one frame and 1546 iterations)."""
    from ancf_petsc.workflows.envelope import markdown_table
    base = {"base": "a.yaml", "law": "unilateral", "friction": "0.0", "bias": "uniform", "elements": "4",
            "stride": "True", "status": "completed", "last_level": "100", "median_iterations": "4.0",
            "iterations_to_1200": "1546", "cutbacks_to_1200": "19", "fade_forces_pointwise_from": ""}
    rows = [dict(base, twist="120", iterations="1546", cutbacks="19", cutback_levels="1"),
            dict(base, twist="150", iterations="858", cutbacks="6", cutback_levels="3"),
            dict(base, twist="90", iterations="260", cutbacks="0", cutback_levels="0")]
    text = markdown_table(rows, law="unilateral", key="median_iterations")
    assert "| 120 | 4 (19 cut-backs in 1 frame; 1546 in all) |" in text
    assert "| 150 | 4 (6 cut-backs in 3 frames; 858 in all) |" in text
    assert "| 90 | 4 |" in text


def test_fibre_strides_grid_runs_the_walking_stride_on_every_goh_config_with_its_own_law():
    """The ``fibre_strides`` grid (docs/gait.md, "Fibre-reinforced (GOH) strides"): every shipped
    GOH config × twist × bias, each cell the walking stride of its bias with the config's own
    contact law and material."""
    import yaml
    from ancf_petsc.workflows.envelope import GOH, cell_config, grid
    cells = grid("fibre_strides", [0.0, 90.0], ["uniform", "soleus"])
    assert len(cells) == 2 * 2 * len(GOH) and all(c.stride and c.law is None for c in cells)
    assert sorted({c.base for c in cells}) == sorted(GOH)
    alex = next(c for c in cells if c.base.endswith("_alex.yaml") and c.twist == 90.0 and c.bias == "soleus")
    raw = cell_config(alex)
    with open(alex.base) as fh:
        own = yaml.safe_load(fh)
    assert raw["history"]["file"].endswith("stride_walking_soleus.csv") and "steps" not in raw
    assert raw["contact"]["mode"] == own["contact"]["mode"]
    assert [b["material"] for b in raw["beams"]] == [b["material"] for b in own["beams"]]
    assert raw["geometry"]["twist_deg"] == 90.0


def test_subject2_strides_grid_runs_the_walking_stride_on_the_traced_outlines():
    """The ``subject2_strides`` grid (docs/gait.md, "A second subject's strides"): the traced
    subject's walking stride sliding, unilateral and with Coulomb μ = 0.3, every twist and bias."""
    from ancf_petsc.workflows.envelope import SUBJECT2, cell_config, grid
    cells = grid("subject2_strides", [0.0, 90.0], ["uniform", "soleus"])
    assert len(cells) == 3 * 2 * 2 and all(c.stride and c.base == SUBJECT2 for c in cells)
    assert sorted({(c.law, c.friction) for c in cells}) == [("sliding", 0.0), ("sliding", 0.3),
                                                           ("unilateral", 0.0)]
    raw = cell_config(next(c for c in cells if c.friction and c.twist == 90.0 and c.bias == "soleus"))
    assert raw["history"]["file"].endswith("stride_walking_soleus.csv") and "steps" not in raw
    assert raw["contact"]["tangential"] == {"law": "coulomb", "friction": 0.3}
    assert raw["geometry"]["twist_deg"] == 90.0


def test_friction_strides_grid_and_the_augmentation_of_its_cells():
    """The ``friction_strides`` grid (the μ = 0.3 strides alone, "Friction's augmentation: G/E")
    and ``--augmentation``: set on friction cells (their name says it), ignored elsewhere."""
    from ancf_petsc.workflows.envelope import cell_config, grid
    cells = grid("friction_strides", [0.0, 90.0], ["uniform"], augmentation=1.0)
    assert len(cells) == 2 and all(c.stride and c.friction == 0.3 and c.law == "sliding" for c in cells)
    raw = cell_config(cells[0])
    assert raw["contact"]["tangential"] == {"law": "coulomb", "friction": 0.3, "augmentation": 1.0}
    assert cells[0].name.endswith("_c1") and raw["name"] == cells[0].name
    plain = grid("friction_strides", [0.0], ["uniform"])[0]
    assert "augmentation" not in cell_config(plain)["contact"]["tangential"] and not plain.name.endswith("_c1")
    core = grid("core", [0.0], ["uniform"], augmentation=1.0)[0]
    assert "tangential" not in cell_config(core)["contact"] and "_c1" not in core.name


#: the proportional grids with contact run with the secant and the tangent load predictor (CSV
#: names after gait_envelope_): the tangent is the default with contact (GRID.csv; frictionless
#: since 2026-12-02, with a tangential law since 2026-12-03), the secant's runs are GRID_secant.csv
PREDICTOR_GRIDS = {"core": ("core_secant", "core_predicted"), "core8": ("core8_secant", "core8"),
                   "subject2": ("subject2_secant", "subject2_as_traced"),
                   "friction": ("friction_secant", "friction")}
#: the grids measured with ``solver.tangent: mixed`` (docs/gait_envelope_GRID_mixed.csv) against
#: the committed default ones on the load predictor the mixed runs had, the secant's where the
#: default changed since (``PREDICTOR_GRIDS``)
MIXED_GRIDS = ("core", "core8", "subject2", "friction", "fibres", "strides")


def _rows(path):
    import csv
    with open(path) as fh:
        return {(r["base"], r["law"], float(r["friction"]), float(r["twist"]), r["bias"], r["stride"]): r
                for r in csv.DictReader(fh)}


def _grid_counts(rows):
    """Cells not completed, columns at ψ ≤ 90° over 60 Newton iterations or cut back to 1.2 kN
    (strides: frames cut back), and the Newton iterations of every cell."""
    bad = sum(r["status"] != "completed" for r in rows)
    over = sum(int(r["cutback_levels"] or 0) if r["stride"] == "True" else float(r["twist"]) <= 90
               and (int(r["iterations_to_1200"] or 0) > 60 or int(r["cutbacks_to_1200"] or 0) > 0) for r in rows)
    return f"{bad} / {over} / {_spaced(sum(int(r['iterations']) for r in rows))}"


def _spaced(n: int) -> str:
    """``n`` with its thousands spaced, as the docs write it (1647 → "1 647")."""
    return f"{n:,}".replace(",", " ")


def _same_predictor(name: str) -> str:
    """The default grid the mixed runs of ``name`` compare with (``MIXED_GRIDS``): the secant's;
    the fibres' the thirty-fourth session's (turned Newton steps, linear predictions)."""
    if name == "fibres":
        return os.path.join(DOCS, "gait_envelope_fibres_rotation.csv")
    # the secant's where the predictor's default changed since, else every increment predicted
    before = PREDICTOR_GRIDS.get(name, SETTLED_GRIDS.get(name, (name,)))[0]
    return os.path.join(DOCS, f"gait_envelope_{before}.csv")


def _ratios(before, after, keys, key="iterations_to_1200"):
    """after ÷ before of ``key`` per column at ψ ≤ 90° that both complete."""
    return [int(after[k][key]) / int(before[k][key]) for k in keys
            if k[3] <= 90 and before[k]["status"] == after[k]["status"] == "completed" and int(before[k][key])]


def _comparison_row(name: str, before: dict, after: dict, key: str = "iterations_to_1200") -> str:
    """One grid's row of a before/after table: counts of each side, ratio at ψ ≤ 90°."""
    import numpy as np
    keys = sorted(set(before) & set(after))
    ratios = _ratios(before, after, keys, key)
    return (f"| {name} ({len(keys)}) | {_grid_counts([before[k] for k in keys])} | "
            f"{_grid_counts([after[k] for k in keys])} | {np.median(ratios):.2f} "
            f"({min(ratios):.2f}–{max(ratios):.2f}) |")


def _block(marker: str) -> str:
    """The text between ``<!-- marker -->`` and ``<!-- /marker -->`` in docs/gait.md."""
    text = open(os.path.join(DOCS, "gait.md")).read()
    start, end = f"<!-- {marker} -->\n", f"\n<!-- /{marker} -->"
    assert start in text and end in text
    return text.split(start, 1)[1].split(end, 1)[0]


def predictor_table() -> str:
    """The docs/gait.md table of the tangent load predictor against the secant, from the CSVs."""
    lines = ["| grid (cells) | secant: not completed / over the target / Newton iterations | tangent "
             "| tangent ÷ secant at ψ ≤ 90°, median (range) |", "|---|---|---|---|"]
    for name, files in PREDICTOR_GRIDS.items():
        sec, tan = (_rows(os.path.join(DOCS, f"gait_envelope_{f}.csv")) for f in files)
        assert set(sec) == set(tan), name
        lines.append(_comparison_row(name, sec, tan))
    return "\n".join(lines)


def test_the_predictor_table_is_its_csvs():
    assert _block("predictor-grids") == predictor_table()


def mixed_tangent_table() -> str:
    """The docs/gait.md table of ``solver.tangent: mixed`` against the default, from the CSVs."""
    lines = ["| grid (cells) | `standard`: not completed / over the target / Newton iterations | `mixed` "
             "| `mixed` ÷ `standard` at ψ ≤ 90°, median (range) |", "|---|---|---|---|"]
    for name in MIXED_GRIDS:
        mixed_path = os.path.join(DOCS, f"gait_envelope_{name}_mixed.csv")
        if not os.path.exists(mixed_path):
            continue
        lines.append(_comparison_row(name, _rows(_same_predictor(name)), _rows(mixed_path),
                                     "iterations" if name == "strides" else "iterations_to_1200"))
    return "\n".join(lines)


def test_the_mixed_tangent_table_is_its_csvs():
    assert _block("mixed-tangent-grids") == mixed_tangent_table()


#: the grids whose unilateral rows were re-run with settled active sets solved before they are
#: predicted (2026-12-05): the committed rows before (GRID_predicted.csv: every increment
#: predicted, the tables' comparisons above were made on them) and now (GRID.csv)
SETTLED_GRIDS = {"core": ("core_predicted", "core"), "strides": ("strides_predicted", "strides"),
                 "subject2_strides": ("subject2_strides_predicted", "subject2_strides_as_traced")}


def settled_table() -> str:
    """The docs/gait.md table of settled active sets against every increment predicted: the
    unilateral cells of each grid, from the CSVs."""
    lines = ["| grid (unilateral cells) | every increment predicted: not completed / over the target or "
             "frames cut back / Newton iterations | settled sets solved first | settled ÷ predicted at "
             "ψ ≤ 90°, median (range) |", "|---|---|---|---|"]
    for name, files in SETTLED_GRIDS.items():
        before, after = ({k: r for k, r in _rows(os.path.join(DOCS, f"gait_envelope_{f}.csv")).items()
                          if r["law"] == "unilateral"} for f in files)
        assert set(before) == set(after), name
        lines.append(_comparison_row(name, before, after, "iterations" if "strides" in name else "iterations_to_1200"))
    return "\n".join(lines)


def test_the_settled_table_is_its_csvs():
    assert _block("settled-grids") == settled_table()


#: the fibre grids of 2026-12-04: on one host the complementarity predictor's step not held to
#: the fibres' exponent growth (GRID_unheld.csv), held with the linear section update
#: (GRID_linear.csv) and held with turned Newton steps (GRID_rotation.csv); on another the turned
#: Newton steps with the predictions not turned (GRID_plain_predictions.csv) and turned, the
#: default with fibres (GRID.csv)
FIBRE_GRIDS = ("fibres", "fibre_strides")


def _fibre_table(head: str, before: str, after: str) -> str:
    lines = [head, "|---|---|---|---|"]
    for name in FIBRE_GRIDS:
        b, a = (_rows(os.path.join(DOCS, f"gait_envelope_{name}{s}.csv")) for s in (before, after))
        assert set(b) == set(a), name
        lines.append(_comparison_row(name, b, a, "iterations" if name == "fibre_strides" else "iterations_to_1200"))
    return "\n".join(lines)


def exponent_hold_table() -> str:
    """The docs/gait.md table of the predictor's exponent hold against its absence, from the CSVs."""
    return _fibre_table("| grid (cells) | step not held: not completed / over the target or frames cut back / "
                        "Newton iterations | held | held ÷ not held at ψ ≤ 90°, median (range) |",
                        "_unheld", "_linear")


def section_turn_table() -> str:
    """The docs/gait.md table of turned sections (the default with fibres) against the linear update."""
    return _fibre_table("| grid (cells) | `linear`: not completed / over the target or frames cut back / "
                        "Newton iterations | `rotation` | `rotation` ÷ `linear` at ψ ≤ 90°, median (range) |",
                        "_linear", "_rotation")


def prediction_turn_table() -> str:
    """The docs/gait.md table of turned load predictions (fibre models' default) against plain ones."""
    return _fibre_table("| grid (cells) | predictions not turned: not completed / over the target or frames cut "
                        "back / Newton iterations | turned | turned ÷ not turned at ψ ≤ 90°, median (range) |",
                        "_plain_predictions", "")


def test_the_exponent_hold_table_is_its_csvs():
    assert _block("exponent-hold-grids") == exponent_hold_table()


def test_the_section_turn_table_is_its_csvs():
    assert _block("section-turn-grids") == section_turn_table()


def test_the_prediction_turn_table_is_its_csvs():
    assert _block("prediction-turn-grids") == prediction_turn_table()


def _total(rows: dict, key: str) -> str:
    """The sum of ``key`` over the rows, written as the docs write it (``_spaced``)."""
    return _spaced(sum(int(r[key]) for r in rows.values()))


def test_the_eight_element_friction_sample_is_its_csvs():
    """The bullet "Friction: the tangent too": the 8-element Coulomb sample's totals (all levels,
    and to 1.2 kN) and its cells over the target, secant → tangent, are what the two CSVs say."""
    sec, tan = (_rows(os.path.join(DOCS, f"gait_envelope_friction8{s}.csv")) for s in ("_secant", ""))
    assert sec.keys() == tan.keys() and len(tan) == 27
    assert all(r["status"] == "completed" for r in list(sec.values()) + list(tan.values()))
    over = [_grid_counts(list(rows.values())).split(" / ")[1] for rows in (sec, tan)]
    text = " ".join(open(os.path.join(DOCS, "gait.md")).read().split())
    assert f"{_total(sec, 'iterations')} → {_total(tan, 'iterations')} Newton iterations" in text
    assert f"to 1.2 kN {_total(sec, 'iterations_to_1200')} → {_total(tan, 'iterations_to_1200')}" in text
    assert f"over the target {over[0]} → {over[1]}" in text


def test_a_cell_with_a_level_past_a_gap_says_where(tmp_path):
    """A run that reported a level past a gap of the load path (solving/step_over.py) ends its
    table cell with the level and where it was reported; the ``CellResult`` row carries them from
    summary.json's ``steps[].passed_over``."""
    from ancf_petsc.workflows.envelope import CellResult, EnvelopeCell, markdown_table
    base = {"base": "a.yaml", "law": "sliding", "friction": "0.0", "bias": "soleus", "elements": "4",
            "status": "completed", "last_level": "3000", "iterations": "602", "iterations_to_1200": "48",
            "cutbacks": "28", "cutbacks_to_1200": "0", "cutback_levels": "1", "median_iterations": "4",
            "stride": "False"}
    rows = [dict(base, twist="30", passed_over="2500@2500.5"), dict(base, twist="45", passed_over="")]
    text = markdown_table(rows, law="sliding")
    assert "| 30 | 48, 2500 N past a gap at 2500.5 N |" in text and "| 45 | 48 |" in text
    cell = EnvelopeCell("a.yaml", 30.0, "soleus", "sliding")
    row = CellResult(cell, "completed", passed_over=((2500.0, 2500.5), (1600.0, 1640.0))).row()
    assert row["passed_over"] == "2500@2500.5;1600@1640"
    assert CellResult(cell, "completed").row()["passed_over"] == ""
    # from summary.json: a fake ancf-solve that writes one
    import json
    from ancf_petsc.workflows.envelope import NEO, run_cell
    summary = {"status": "completed", "newton_iterations": 9, "steps": [
        {"load_factor": 2000.0, "iterations": 4, "cutbacks": 0},
        {"load_factor": 2500.5, "iterations": 5, "cutbacks": 28, "passed_over":
            {"level": 2500.0, "last_converged": 2496.09, "reported_at": 2500.5}}]}
    fake = tmp_path / "fake-solve"
    fake.write_text("#!/bin/sh\nmkdir -p \"$3\"\ncat > \"$3/summary.json\" <<'END'\n" + json.dumps(summary)
                    + "\nEND\n")
    fake.chmod(0o755)
    res = run_cell(EnvelopeCell(NEO, 30.0, "soleus", "sliding"), [str(fake)], str(tmp_path / "work"))
    assert res.status == "completed" and res.passed_over == ((2500.0, 2500.5),)


@pytest.mark.slow
def test_iterations_to_1200_count_a_1200_level_reported_past_a_gap(tmp_path):
    """The 8-element unilateral soleus-biased 135° column reports 1200 N at 1200.2 N (a gap of the
    load path), a level of 330 Newton iterations and 8 cut-backs; the cell counted 'to 1.2 kN' the
    steps at load factors up to 1200 N and gave 70 iterations and 0 cut-backs
    (docs/gait_envelope_core8.csv).  Now the steps of the levels asked up to 1.2 kN: 400 and 8."""
    import shutil
    from ancf_petsc.workflows.envelope import NEO, EnvelopeCell, run_cell
    res = run_cell(EnvelopeCell(NEO, 135.0, "soleus", "unilateral", elements=8),
                   [os.path.join(os.path.dirname(DOCS), ".venv", "bin", "ancf-solve")], str(tmp_path))
    assert res.status == "completed" and res.passed_over == ((1200.0, 1200.2),), res.message
    early = res.per_level[:8]
    assert early[-1][0] == 1200.2 and early[-1][2] == 8
    assert res.iterations_to_1200 == sum(its for _, its, _ in early) and res.cutbacks_to_1200 == 8
