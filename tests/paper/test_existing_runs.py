"""``ancf-report --existing`` on runs that are not the paper's model (issue 39): probes with their
own units (a direction vector's change is not a displacement in mm), a title that does not claim
the paper's reproduction, plain reasons, and for a contact run under displacement control the
reaction, the first − second differences, a force chart and slip and pressure along the tendon."""
import os
import subprocess

from helpers import MPI_ENV, ROOT, VENV_BIN, load_raw, report_existing, solve_cli, write_config


def test_existing_runs_of_other_models_say_what_they_hold(tmp_path):
    bar = load_raw("pretwisted_bar.yaml")
    strips = load_raw("friction_pressed_strips.yaml")
    strips["steps"] = [1.0, 1.5, 2.0, 2.1]
    runs = []
    for name, raw in (("bar", bar), ("strips", strips)):
        p = solve_cli(write_config(raw, tmp_path / f"{name}.yaml"), extra=["--output-dir", str(tmp_path / name), "--quiet"])
        assert p.returncode == 0, p.stderr
        runs.append(str(tmp_path / name))
    text = report_existing(runs, tmp_path / "rep")
    title = text.splitlines()[0]
    assert "reproduction" not in title and "pretwisted_bar" in title and "not the paper's model" in title
    # the r_y probe: its change (x, y, z), dimensionless; before: "tip_r_y u_x [mm]" 10.95
    assert "| tip_r_y Δr_y (x, y, z) [1] |" in text and "tip_r_y u_x" not in text
    assert "(0.01095, " in text and "10.95" not in text
    # plain reasons, no fingerprint keys
    assert "beams/" not in text and "beam base is not in the paper's model" in text
    # the strips: the grip's reaction (displacement control) and base − slider per level
    head = "| load factor | reaction of grip along x [N] | base − slider [mm] |"
    assert head in text
    row = next(line for line in text.split(head)[1].splitlines() if line.startswith("| 1.5 | ")).split("|")
    assert abs(float(row[2]) - 0.5 * 0.01) < 1e-3 * 0.005      # sliding: mu N
    assert float(row[3]) < 0                                    # the slider (second) ahead
    for png in ("friction_pressed_strips_force.png", "friction_pressed_strips_slip.png"):
        assert os.path.getsize(tmp_path / "rep" / png) > 10_000 and f"]({png})" in text


def test_a_history_run_reports_the_load_of_each_frame(tmp_path):
    """A load history (each muscle on its column, loading then unloading): the report's force is
    the frame's applied load (the columns' sum), not the frame number times the unit loads.  Its
    rows were labelled by load factor (1, 2, 3), not by frame and time [s]; and the figure of the
    muscle forces, strains and end differences over the frames that docs/gait.md shows
    (viz/history.py) was made by no command: ancf-report --existing now makes it."""
    from helpers import CONFIGS
    raw = load_raw("achilles_type3_psi45.yaml")
    names = [b["name"] for b in raw["beams"]]
    for b in raw["beams"]:
        b["elements"] = 2
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw.pop("steps")
    raw["history"] = {"table": {"time": [0.0, 0.1, 0.2], "s": [20.0, 60.0, 10.0], "m": [10.0, 30.0, 5.0],
                                "l": [10.0, 30.0, 5.0]}}
    raw["loads"] = [{"beam": n, "node": "last", "traction_force": [1.0, 0.0, 0.0], "column": c}
                    for n, c in zip(names, "sml")]
    raw["output"] = {"vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "h.yaml"), extra=["--output-dir", str(tmp_path / "h"), "--quiet"])
    assert p.returncode == 0, p.stderr
    text = report_existing([str(tmp_path / "h")], tmp_path / "rep")
    head = "| frame | time [s] | applied load along x [N] |"
    rows = [line.split("|") for line in text.split(head)[1].splitlines()[2:5]]
    assert [(int(r[1]), float(r[2]), float(r[3])) for r in rows] == [(1, 0.0, 40.0), (2, 0.1, 120.0), (3, 0.2, 20.0)]
    assert "| load factor |" not in text and "The supports at the last level (frame 3, t = 0.2 s)" in text
    png = "achilles_type3_psi45_history.png"
    assert os.path.getsize(tmp_path / "rep" / png) > 10_000 and f"]({png})" in text


def test_a_killed_run_is_reported_with_the_levels_results_h5_holds(tmp_path):
    """A run killed while summary.json lagged results.h5 (status still 'running', the last level
    only in results.h5): the report lists the levels read_results sees, and says the run has no
    final status, not 'running (: )'."""
    import json
    from ancf_petsc.io.reader import read_results
    raw = load_raw("pretwisted_bar.yaml")
    raw["steps"] = raw["steps"][:3]
    p = solve_cli(write_config(raw, tmp_path / "bar.yaml"),
                  extra=["--output-dir", str(tmp_path / "bar"), "--quiet"])
    assert p.returncode == 0, p.stderr
    path = tmp_path / "bar" / "summary.json"
    s = json.load(open(path))
    s["steps"] = s["steps"][:1]
    s["status"] = "running"
    for key in ("reason_code", "message"):
        s.pop(key, None)
    json.dump(s, open(path, "w"))
    assert len(read_results(str(tmp_path / "bar")).summary["steps"]) == 3
    text = report_existing([str(tmp_path / "bar")], tmp_path / "rep")
    assert "running (no final status: still running, or killed)" in text and "(: )" not in text
    row = next(line for line in text.splitlines() if line.startswith(f"| {tmp_path / 'bar'} |"))
    assert row.rstrip().endswith("| 3 |"), row


def test_odd_summaries_and_an_output_path_that_is_a_file_are_one_line_errors(tmp_path):
    """A summary.json that is JSON but no run's summary ([], or one without twist_deg) and an
    --out that is a file ended in tracebacks (AttributeError, TypeError, FileExistsError), in
    ancf-report and likewise in ancf-study and ancf-fit; then their fix named ancf-solve's
    output.dir / --output-dir (ancf-report's twice, with "(--out)" after it)."""
    from helpers import CONFIGS
    (tmp_path / "afile").write_text("")
    (tmp_path / "list").mkdir()
    (tmp_path / "list" / "summary.json").write_text("[]")
    (tmp_path / "bare").mkdir()
    (tmp_path / "bare" / "summary.json").write_text('{"status": "completed", "name": "x", "steps": []}')
    bin_ = lambda name: os.path.join(VENV_BIN, name)      # noqa: E731
    runs = [([bin_("ancf-report"), "--existing", str(tmp_path / "list"), "--out", str(tmp_path / "o1")],
             2, "not a run's summary (a JSON object with its status and steps); got list"),
            ([bin_("ancf-report"), "--existing", str(tmp_path / "bare"), "--out", str(tmp_path / "o2")], 0, ""),
            ([bin_("ancf-report"), "--existing", str(tmp_path / "bare"), "--out", str(tmp_path / "afile")],
             2, "afile: exists and is not a directory (choose another --out)\n"),
            ([bin_("ancf-study"), os.path.join(CONFIGS, "studies", "bending_pareto.yaml"), "--out",
              str(tmp_path / "afile")], 2, "afile: exists and is not a directory (choose another output / --out)"),
            ([bin_("ancf-fit"), os.path.join(CONFIGS, "fits", "bar_twin.yaml"), "--out", str(tmp_path / "afile")],
             2, "afile: exists and is not a directory (choose another output / --out)")]
    for cmd, code, words in runs:
        p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=dict(os.environ, **MPI_ENV),
                           timeout=300)
        assert p.returncode == code and "Traceback" not in p.stderr, (cmd, p.stderr)
        assert words in p.stderr and len(p.stderr.strip().splitlines()) <= 1, (cmd, p.stderr)
    text = open(tmp_path / "o2" / "report.md").read()
    assert "| ? | completed | 0 |" in text and "its summary gives no pretwist (twist_deg)" in text


def _solved_twice(raw: dict, tmp_path, stem: str) -> list[str]:
    """``raw`` solved into tmp_path/<stem>1 and <stem>2; the two output directories."""
    runs = []
    for k in (1, 2):
        p = solve_cli(write_config(raw, tmp_path / f"{stem}{k}.yaml"),
                      extra=["--output-dir", str(tmp_path / f"{stem}{k}"), "--quiet"])
        assert p.returncode == 0, p.stderr
        runs.append(str(tmp_path / f"{stem}{k}"))
    return runs


def test_two_runs_of_one_model_keep_their_own_figures(tmp_path):
    """Two runs of friction_pressed_strips: the second's figures overwrote the first's and the
    report linked one file twice; each run now has its own."""
    strips = load_raw("friction_pressed_strips.yaml")
    strips["steps"] = [1.0, 1.5, 2.0]
    text = report_existing(_solved_twice(strips, tmp_path, "s"), tmp_path / "rep")
    for k in (1, 2):
        png = f"friction_pressed_strips_{k}_force.png"
        assert os.path.getsize(tmp_path / "rep" / png) > 10_000 and f"]({png})" in text


def test_a_second_run_at_one_pretwist_is_named_not_dropped_silently(tmp_path):
    """Table 1 takes the last run given per pretwist; the earlier one was left out silently."""
    from helpers import CONFIGS
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    text = report_existing(_solved_twice(raw, tmp_path, "a"), tmp_path / "rep")
    assert f"{tmp_path / 'a1'} (ψ = 45°: {tmp_path / 'a2'} is the column)" in text, text[:3000]


def _force_column(text: str, head: str) -> dict[float, float]:
    """Load factor → the force column of the report's differences table under ``head``."""
    assert head in text, text[:3000]
    rows = []
    for line in text.split(head)[1].splitlines()[2:]:
        if not line.startswith("| "):            # the table ends (the supports' table may follow)
            break
        rows.append(line.split("|"))
    return {float(r[1]): float(r[2]) for r in rows}


def test_the_force_column_is_the_moved_supports_reaction_or_the_applied_load(tmp_path):
    """The pressed strips pulled by a grip without a name at the slider's first node: the force
    column said 'applied load along x' and showed the base's last support's reaction (-0.00023 N at
    load factor 1.5) instead of the grip's, 'slider.0', sliding at mu N = 0.005 N (the moved
    support was looked up as 'slider.first'). The same strips held at the slider's last node and
    pulled by a force of 0.004 N x (0..1 from load factor 1 to 2) at its middle node: 'applied
    load along x' was the end forces of the beams' last nodes (2.97e-05 / -7.8e-05 N: the
    reactions of the supports there), not the 0.002 / 0.004 N applied."""
    grip = load_raw("friction_pressed_strips.yaml")
    grip["steps"] = [1.0, 1.5]
    bcs = grip["boundary_conditions"]
    bcs[9] = {"beam": "slider", "node": "last", "fix": {"r": "y"}}
    bcs[10] = {k: v for k, v in bcs[10].items() if k != "name"} | {"node": "first"}
    grip["probes"][0]["node"] = "first"
    held = load_raw("friction_pressed_strips.yaml")
    held["steps"] = [1.0, 1.5, 2.0]
    held["boundary_conditions"][10] = {"beam": "slider", "node": "last", "fix": {"r": "xy"}}
    held["loads"].append({"beam": "slider", "node": 4, "force": [0.004, 0.0, 0.0],
                          "curve": [[0, 0], [1, 0], [2, 1], [4, 1]]})
    for name, raw in (("grip", grip), ("held", held)):
        raw["output"] = {"vtk": False}
        p = solve_cli(write_config(raw, tmp_path / f"{name}.yaml"),
                      extra=["--output-dir", str(tmp_path / name), "--quiet"])
        assert p.returncode == 0, p.stderr
    text = report_existing([str(tmp_path / "grip")], tmp_path / "rep1")
    force = _force_column(text, "| load factor | reaction of slider.0 along x [N] | base − slider [mm] |")
    assert abs(force[1.5] - 0.5 * 0.01) < 1e-3 * 0.005
    text = report_existing([str(tmp_path / "held")], tmp_path / "rep2")
    force = _force_column(text, "| load factor | applied load along x [N] | base − slider [mm] |")
    assert force == {1.0: 0.0, 1.5: 0.002, 2.0: 0.004}


def test_a_run_without_probes_has_no_probe_table(tmp_path):
    """The pressed strips without probes: the report had a probe table of a header without
    columns ('| load factor |  |' over '|---:|', the rows '| 1 |  |'); now none, and the
    differences table as before."""
    raw = load_raw("friction_pressed_strips.yaml")
    raw["steps"], raw["output"] = [1.0, 1.5], {"vtk": False}
    raw.pop("probes")
    p = solve_cli(write_config(raw, tmp_path / "s.yaml"), extra=["--output-dir", str(tmp_path / "s"), "--quiet"])
    assert p.returncode == 0, p.stderr
    text = report_existing([str(tmp_path / "s")], tmp_path / "rep")
    assert "| load factor |  |" not in text and "\n|---:|\n" not in text
    assert "| load factor | reaction of grip along x [N] | base − slider [mm] |" in text


def test_a_displacement_controlled_run_without_interfaces_has_a_whole_force_table(tmp_path):
    """uniaxial_neohookean pulled by an unnamed grip at its last node (no contact): the force table
    had a third, empty column in its header ('| load factor | ... [N] |  |' over '|---:|---:|') and
    rows ('| 0.5 | 20.1074 |  |'), under 'How far the subtendons moved against each other'."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["loads"], raw["steps"], raw["output"] = [], [0.5, 1.0], {"vtk": False}
    raw["boundary_conditions"].append({"beam": "bar", "node": "last", "displacement": {"r": {"x": 0.02}}})
    p = solve_cli(write_config(raw, tmp_path / "g.yaml"), extra=["--output-dir", str(tmp_path / "g"), "--quiet"])
    assert p.returncode == 0, p.stderr
    text = report_existing([str(tmp_path / "g")], tmp_path / "rep")
    assert "|  |" not in text and "moved against each other" not in text
    assert "| load factor | reaction of bar.2 along x [N] |\n|---:|---:|\n" in text
    force = _force_column(text, "| load factor | reaction of bar.2 along x [N] |")
    assert set(force) == {0.5, 1.0} and 15.0 < force[0.5] < force[1.0]


def test_the_supports_force_and_moment_at_the_last_level(tmp_path):
    """A clamped cantilever with an end force P along z (4 elements, small load): the report gave
    no reaction at all; now the support's force (−P along z) and moment (P L about y) at the
    last level."""
    raw = load_raw("bending_neohookean.yaml")
    raw["beams"][0]["elements"], raw["steps"], raw["output"] = 4, [1e-3], {"vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "b.yaml"), extra=["--output-dir", str(tmp_path / "b"), "--quiet"])
    assert p.returncode == 0, p.stderr
    text = report_existing([str(tmp_path / "b")], tmp_path / "rep")
    head = "| support | F_x | F_y | F_z | M_x | M_y | M_z |"
    assert "The supports at the last level (load factor 0.001)" in text and head in text
    row = text.split(head)[1].splitlines()[2].split("|")
    P = raw["loads"][0]["traction_force"][2] * 1e-3
    assert row[1].strip() == "beam.0" and abs(float(row[4]) + P) < 1e-5 * P
    assert abs(float(row[6]) - P * 0.1) < 1e-3 * P * 0.1


def test_a_run_whose_beams_have_other_element_counts_names_every_one(tmp_path):
    """The paper's tendon on 1 element per subtendon (the paper's 4): the report named one beam,
    'lateral_gastrocnemius has another number of elements (4 → 1)', as if the others were the
    paper's.  Now every beam whose count changed, in the paper's order; one alone as before."""
    from helpers import CONFIGS
    from ancf_petsc.paper import existing
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["elements"] = 1
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["steps"] = [10.0]
    raw["output"] = {"vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["--output-dir", str(tmp_path / "c"), "--quiet"])
    assert p.returncode == 0, p.stderr
    text = report_existing([str(tmp_path / "c")], tmp_path / "rep")
    assert ("its model is not the paper's: soleus (4 → 1), medial_gastrocnemius (4 → 1) and "
            "lateral_gastrocnemius (4 → 1) have other numbers of elements.") in text, text[:2000]
    paper = {"beams/soleus/elements": 4, "beams/medial_gastrocnemius/elements": 4}
    assert existing.element_counts(paper, dict(paper, **{"beams/soleus/elements": 2})) == \
        "soleus has another number of elements (4 → 2)"


def test_an_accepted_unstable_level_is_marked_in_the_tables(tmp_path):
    """The paper's tendon on 1 element per subtendon stepped straight to 50 N lands on a saddle
    (tests/solving/test_stability_check.py); with solver.allow_unstable the run ends 'completed',
    and the report's rows showed that level like any other.  Now its row says it is unstable."""
    from helpers import CONFIGS
    raw = load_raw("achilles_type3_psi0.yaml")
    for b in raw["beams"]:
        b["elements"] = 1
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["steps"] = [10.0, 50.0]
    raw["contact"]["projection"] = {"axial": 2, "curve": 0}
    raw["solver"] = {"stability_cutbacks": 0, "branch_switch": False, "allow_unstable": True}
    raw["output"] = {"vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["--output-dir", str(tmp_path / "c"), "--quiet"])
    assert p.returncode == 0, p.stderr
    text = report_existing([str(tmp_path / "c")], tmp_path / "rep")
    assert "| completed |" in text
    assert text.count("| 50 (unstable: 1 negative tangent eigenvalue(s)) | ") == 2, text[:3000]
    assert "| 10 | " in text


def test_a_damaged_or_foreign_results_h5_is_a_one_line_error(tmp_path):
    """A contact run whose results.h5 was truncated (a full disk, a copy cut short), emptied, is a
    folder, or is another run's with fewer levels: ancf-report --existing ended in an OSError or KeyError
    traceback (exit 1) from the slip figure's read_contact; now one line naming the file, exit 2,
    before anything is written."""
    import shutil
    import h5py
    from helpers import CONFIGS
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["elements"] = 2
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["steps"], raw["output"] = [10.0, 20.0], {"vtk": False}
    run = tmp_path / "run"
    p = solve_cli(write_config(raw, tmp_path / "t.yaml"), extra=["--output-dir", str(run), "--quiet"])
    assert p.returncode == 0, p.stderr
    for case in ("truncated", "empty", "foreign", "folder"):
        shutil.copytree(run, tmp_path / case)
        h5 = tmp_path / case / "results.h5"
        if case == "folder":                    # HDF5's message for it ran over two lines
            os.remove(h5)
            os.mkdir(h5)
        elif case == "foreign":
            with h5py.File(h5, "a") as f:
                del f["steps/step_0002"]
        else:
            os.truncate(h5, 2000 if case == "truncated" else 0)
        cmd = [os.path.join(VENV_BIN, "ancf-report"), "--existing", str(tmp_path / case), "--out", str(tmp_path / f"o_{case}")]
        p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=dict(os.environ, **MPI_ENV), timeout=300)
        assert p.returncode == 2 and "Traceback" not in p.stderr, (case, p.stderr)
        assert len(p.stderr.strip().splitlines()) == 1 and f"--existing: {h5}: " in p.stderr, (case, p.stderr)
        assert ("no level 2 (it holds 1)" if case == "foreign" else "cannot read") in p.stderr, p.stderr
        assert not os.path.exists(tmp_path / f"o_{case}")


def test_a_report_that_cannot_be_written_is_a_one_line_error(tmp_path):
    """--out holding a report.md that cannot be replaced (here a folder so named; another user's
    file, a full disk alike) ended ancf-report --existing in an IsADirectoryError /
    PermissionError traceback, exit 1; so did a figure's file.  Now one line naming it, exit 2."""
    raw = load_raw("pretwisted_bar.yaml")
    raw["steps"], raw["output"] = raw["steps"][:1], {"vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "bar.yaml"), extra=["--output-dir", str(tmp_path / "bar"), "--quiet"])
    assert p.returncode == 0, p.stderr
    (tmp_path / "rep" / "report.md").mkdir(parents=True)
    cmd = [os.path.join(VENV_BIN, "ancf-report"), "--existing", str(tmp_path / "bar"), "--out", str(tmp_path / "rep")]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=dict(os.environ, **MPI_ENV), timeout=300)
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert p.stderr.strip() == f"ancf-report: output error: {tmp_path / 'rep' / 'report.md'}: Is a directory", p.stderr


def test_a_probe_table_shows_the_components_a_run_moves(tmp_path):
    """The cantilever's tip moves 40 mm down (z) and 10 mm back (x): the report's table showed
    u_x alone.  Now x and every component that moves (here z; y stays at rounding) are shown."""
    raw = load_raw("bending_neohookean.yaml")
    p = solve_cli(write_config(raw, tmp_path / "bend.yaml"), extra=["--output-dir", str(tmp_path / "bend"), "--quiet"])
    assert p.returncode == 0, p.stderr
    text = report_existing([str(tmp_path / "bend")], tmp_path / "rep")
    head = "| load factor | tip u_x [mm] | tip u_z [mm] |"
    assert head in text and "tip u_y" not in text
    last = [line for line in text.split(head)[1].splitlines() if line.startswith("| 1 | ")][0].split("|")
    import json
    with open(tmp_path / "bend" / "summary.json") as fh:
        u = json.load(fh)["steps"][-1]["probes"]["tip"]["displacement"]
    assert abs(float(last[2]) - 1e3 * u[0]) < 1e-5 and abs(float(last[3]) - 1e3 * u[2]) < 1e-5
    assert float(last[3]) > 30.0
