"""Load histories (config history:, issue 38): each load follows its own column of a table over
frames, frame k at load factor k.  The tables (CSV, OpenSim storage, inline) and their errors;
a frictionless non-proportional history with unloading ends where a proportional run to the same
loads does (no path dependence); with friction a history is the load-curve machinery (the same
answers as the curves) and carries its path; a history run killed mid-way restarts to the
uninterrupted answers; the per-frame outputs."""
import copy
import os

import numpy as np
import pytest

from ancf_petsc.config.parse import parse_config
from ancf_petsc.config.values import ConfigError
from helpers import CONFIGS, ONE_AND_TWO_RANKS, load_raw, read_summary, run_inline, solve_cli, \
    write_config

PLANE = {"r": "xyz", "r_y": "xz", "r_z": "x", "r_yy": "x", "r_zz": "x", "r_yz": "x"}


def tendon(table=None, elements=2, contact="sliding"):
    """The paper's three subtendons (ψ = 45°, 2 elements, plane roots) pulled by end tractions
    following the columns soleus, medial, lateral of an inline history table."""
    raw = load_raw("achilles_type3_psi45.yaml")
    names = [b["name"] for b in raw["beams"]]
    for b in raw["beams"]:
        b["elements"], b["axial_points"] = elements, 2
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["boundary_conditions"] = [{"beam": n, "node": "first", "fix": dict(PLANE)} for n in names]
    raw["loads"] = [{"beam": n, "node": "last", "traction_force": [1.0, 0.0, 0.0], "column": c}
                    for n, c in zip(names, ("soleus", "medial", "lateral"))]
    raw["contact"] = {"mode": contact}
    raw.pop("steps")
    raw["history"] = {"table": table or {"time": [0.0, 0.1], "soleus": [10.0, 20.0],
                                         "medial": [0.0, 5.0], "lateral": [0.0, 5.0]}}
    raw["output"] = {"vtk": False}
    return raw


def test_tables_give_frames_and_curves(tmp_path):
    """A CSV (with an Excel byte-order mark and a comment), an OpenSim storage file and an inline
    table give the same frames; frame k is load factor k and every frame is a step."""
    rows = [(0.0, 10.0, 0.0, 1.0), (0.01, 20.0, 4.0, 2.0), (0.02, 15.0, 8.0, 3.0)]
    csv = tmp_path / "stride.csv"
    csv.write_text("\ufeff# forces [N]\ntime,soleus,medial,lateral\n"
                   + "".join(",".join(f"{v:g}" for v in r) + "\n" for r in rows), encoding="utf-8")
    sto = tmp_path / "stride.sto"
    sto.write_text("forces\nversion=1\nnRows=3\nnColumns=4\ninDegrees=no\nendheader\n"
                   "time\tsoleus\tmedial\tlateral\n" + "".join("\t".join(f"{v:g}" for v in r) + "\n" for r in rows))
    inline = {"time": [r[0] for r in rows], "soleus": [r[1] for r in rows],
              "medial": [r[2] for r in rows], "lateral": [r[3] for r in rows]}
    specs = []
    for hist in ({"file": str(csv)}, {"file": str(sto)}, {"table": inline}):
        raw = tendon()
        raw["history"] = hist
        specs.append(parse_config(raw, base_dir=CONFIGS))
    for s in specs:
        assert s.steps == [1.0, 2.0, 3.0]
        assert s.loads[1].curve == ((0.0, 0.0), (1.0, 0.0), (2.0, 4.0), (3.0, 8.0))
        assert s.history.time_of(2.0) == pytest.approx(0.01)
        assert s.solver.predictor == "tangent"
    raw = tendon()
    raw["history"]["scale"] = 1000.0
    assert parse_config(raw, base_dir=CONFIGS).loads[0].curve[-1] == (2.0, 20000.0)


def test_history_scale_multiplies_the_loads_columns_not_a_displacements():
    """history.scale is the loads' unit (1000 for kN): a grip's displacement column in metres
    was multiplied too (2 mm in the table moved the grip by 2 m)."""
    raw = tendon()
    raw["history"]["scale"] = 1000.0
    raw["history"]["table"]["grip"] = [1.0e-3, 2.0e-3]
    raw["loads"] = raw["loads"][1:]
    raw["boundary_conditions"].append({"beam": "soleus", "node": "last", "name": "grip",
                                       "displacement": {"r": {"x": 1.0}}, "column": "grip"})
    spec = parse_config(raw, base_dir=CONFIGS)
    assert spec.boundary_conditions[-1].curve == ((0.0, 0.0), (1.0, 1.0e-3), (2.0, 2.0e-3))
    assert spec.loads[0].curve[-1] == (2.0, 5000.0)


@pytest.mark.parametrize("edit,match", [
    (lambda r, p: r["history"].update(file=str(p / "bad.csv"), table=None) or r["history"].pop("table"),
     r"history\.file: .*bad\.csv: data row 2 \(line 3\), column 'medial': 'nan' is not a finite number"),
    (lambda r, p: r["history"]["table"].update(time=[0.0, 0.0]),
     r"history\.time: the times of history\.table must increase"),
    (lambda r, p: r.__setitem__("steps", [1, 2]), r"^steps: with history every frame"),
    (lambda r, p: r["loads"][0].pop("column"), r"^loads\[0\]: with history every load follows a column"),
    (lambda r, p: r["loads"][0].update(column="gastrocnemius"),
     r"^loads\[0\]\.column: no column 'gastrocnemius' in history\.table \(columns: soleus, medial, lateral\)"),
    (lambda r, p: r["history"]["table"].update(medial=[1.0]), r"history\.table\.medial: has 1 values"),
    (lambda r, p: r.pop("history"), r"^loads\[0\]\.column: a column names a load table's column"),
    (lambda r, p: r["loads"][0].update(column="time"),
     r"^loads\[0\]\.column: 'time' is the history's clock \(history\.time, seconds\), not a load"),
    (lambda r, p: r["history"].update(file=str(p / "semi.csv"), table=None) or r["history"].pop("table"),
     r"semi\.csv: the header line is one column 'time;soleus;medial;lateral': its fields are separated "
     r"by semicolons; a CSV file here separates them by commas"),
    (lambda r, p: r["history"].update(file=str(p / "opensim.csv"), table=None) or r["history"].pop("table"),
     r"opensim\.csv: an OpenSim storage file \(it has an 'endheader' line\): give it the extension \.sto"),
    (lambda r, p: r["history"].update(file=str(p / "cut.sto"), table=None) or r["history"].pop("table"),
     r"cut\.sto: its header says nRows=10, the table has 2 data rows: a file cut short\?"),
    # a scale no load reads (a grip's column in mm with scale 0.001: moved the grip 1000 times too far)
    (lambda r, p: r["history"].update(scale=0.001) or r["loads"].clear() or r["boundary_conditions"].append(
        {"beam": "soleus", "node": "last", "displacement": {"r": {"x": 1.0}}, "column": "soleus"}),
     r"^history\.scale: multiplies the columns loads read, and no load reads one \(a prescribed displacement's "
     r"column is read as written, in metres; a curve as written\): remove it; got 0\.001"),
])
def test_history_errors_name_the_key_row_and_column(tmp_path, edit, match):
    (tmp_path / "bad.csv").write_text("time,soleus,medial,lateral\n0,1,2,3\n0.1,1,nan,3\n")
    (tmp_path / "semi.csv").write_text("time;soleus;medial;lateral\n0;1;2;3\n0.1;1;2;3\n")
    opensim = ("version=1\nnRows=10\nnColumns=4\nendheader\n"
               "time\tsoleus\tmedial\tlateral\n0\t1\t2\t3\n0.1\t1\t2\t3\n")
    (tmp_path / "opensim.csv").write_text(opensim)
    (tmp_path / "cut.sto").write_text(opensim)           # a truncated OpenSim file
    raw = tendon()
    edit(raw, tmp_path)
    if "steps" not in raw and "history" not in raw:
        raw["steps"] = [1.0]
    with pytest.raises(ConfigError, match=match):
        parse_config(raw, base_dir=CONFIGS)


def _ends(summary, frame=-1):
    return np.array([summary["steps"][frame]["probes"][n]["displacement"]
                     for n in ("soleus", "medial_gastrocnemius", "lateral_gastrocnemius")])


def _stopped(raw, full, frames: int, tmp_path) -> dict:
    """``raw`` run into tmp_path/run with the Newton budget of ``full``'s first ``frames`` frames:
    it stops with exit 3 (every converged frame on disk); its summary."""
    stopped = copy.deepcopy(raw)
    stopped["solver"] = {"max_newton_iterations": sum(s["iterations"] for s in full["steps"][:frames])}
    p = solve_cli(write_config(stopped, tmp_path / "stopped.yaml"),
                  extra=["--output-dir", str(tmp_path / "run"), "--quiet"])
    assert p.returncode == 3, p.stderr
    return read_summary(tmp_path / "run")


def _restarted(full, config: str, tmp_path, rtol: float, ranks: int = 1) -> dict:
    """tmp_path/run restarted with ``config`` (on ``ranks``): it completes every frame of ``full``
    with the three ends within ``rtol`` of them; its summary."""
    p = solve_cli(config, ranks=ranks, extra=["--restart", str(tmp_path / "run"), "--quiet"])
    assert p.returncode == 0, p.stderr
    done = read_summary(tmp_path / "run")
    assert len(done["steps"]) == len(full["steps"])
    for k in range(len(full["steps"])):
        a, b = _ends(full, k), _ends(done, k)
        assert np.abs(a - b).max() <= rtol * np.abs(a).max()
    return done


@pytest.mark.slow
def test_frictionless_history_with_unloading_ends_where_a_proportional_run_does(tmp_path):
    """Non-proportional frames that load the soleus, move the load to the gastrocnemii and unload
    the soleus end at the state a single proportional increase to the last frame's loads reaches
    (sliding contact is conservative: no path dependence), to 1e-7 of the displacements; the
    reported end forces are the frames' loads."""
    table = {"time": [0.0, 0.01, 0.02, 0.03, 0.04], "soleus": [60.0, 200.0, 120.0, 40.0, 80.0],
             "medial": [0.0, 40.0, 150.0, 220.0, 90.0], "lateral": [10.0, 30.0, 90.0, 160.0, 70.0]}
    hist = run_inline(tendon(table), tmp_path / "history")
    assert hist["status"] == "completed" and len(hist["steps"]) == 5
    last = {k: v[-1] for k, v in table.items() if k != "time"}
    direct = run_inline(tendon({"time": [0.0], **{k: [v] for k, v in last.items()}}), tmp_path / "direct")
    a, b = _ends(hist), _ends(direct)
    assert np.abs(a - b).max() <= 1e-7 * np.abs(b).max()
    st = hist["steps"][2]
    assert st["frame"] == 3 and st["time"] == pytest.approx(0.02)
    assert st["subtendons"]["medial_gastrocnemius"]["end_force"] == pytest.approx([150.0, 0.0, 0.0])
    assert st["subtendons"]["soleus"]["elongation"] == pytest.approx(st["probes"]["soleus"]["displacement"][0],
                                                                      rel=0.05)


@pytest.mark.slow
def test_a_friction_history_is_the_load_curves_and_carries_its_path(tmp_path):
    """configs/friction_pressed_strips.yaml (pressing ramp, then the grip displaced out, back past
    zero and out again, Coulomb μ = 0.5) written as a history table of its own frames gives the
    curves' answers at every frame (the same machinery, load factors relabelled); the grip's
    reaction at equal displacement differs between going out and coming back (the path kept)."""
    raw = load_raw("friction_pressed_strips.yaml")
    raw["output"] = {"vtk": False}
    base = run_inline(raw, tmp_path / "curves")
    from ancf_petsc.model.loading import LoadCurve
    steps = raw["steps"]
    press = LoadCurve(tuple(map(tuple, raw["loads"][0]["curve"])))
    grip = LoadCurve(tuple(map(tuple, raw["boundary_conditions"][-1]["curve"])))
    hist = copy.deepcopy(raw)
    hist.pop("steps")
    hist["history"] = {"table": {"time": [float(s) for s in steps], "press": [press(s) for s in steps],
                                 "grip": [grip(s) for s in steps]}}
    for ld in hist["loads"]:
        ld.pop("curve")
        ld["column"] = "press"
    hist["boundary_conditions"][-1].pop("curve")
    hist["boundary_conditions"][-1]["column"] = "grip"
    hs = run_inline(hist, tmp_path / "history")
    assert base["status"] == hs["status"] == "completed" and len(hs["steps"]) == len(steps)
    r_curves = np.array([s["reactions"]["grip"] for s in base["steps"]])
    r_hist = np.array([s["reactions"]["grip"] for s in hs["steps"]])
    assert np.abs(r_curves - r_hist).max() <= 1e-6 * np.abs(r_curves).max()
    i_out, i_back = steps.index(1.5), steps.index(2.5)      # grip at +0.5e-4 m going out, coming back
    assert abs(r_hist[i_out, 0] - r_hist[i_back, 0]) > 0.2 * abs(r_hist[i_out, 0])


@pytest.mark.slow
def test_a_history_run_stopped_midway_restarts_to_the_uninterrupted_answers(tmp_path):
    """A history run stopped by its Newton budget after a few frames (exit 3, every converged
    frame on disk) continues with --restart from its last frame to the answers of an
    uninterrupted run (1e-10)."""
    table = {"time": [0.01 * k for k in range(8)], "soleus": [20, 60, 120, 160, 120, 60, 30, 60],
             "medial": [5, 20, 60, 100, 140, 100, 40, 20], "lateral": [5, 20, 40, 80, 120, 80, 40, 20]}
    raw = tendon({k: [float(v) for v in vs] for k, vs in table.items()})
    raw["history"]["table"]["time"] = [0.01 * k for k in range(8)]
    full = run_inline(raw, tmp_path / "full")
    assert full["status"] == "completed"
    part = _stopped(raw, full, 4, tmp_path)
    assert 3 <= len(part["steps"]) < 8
    done = _restarted(full, write_config(raw, tmp_path / "again.yaml"), tmp_path, 1e-10)
    assert len(done["steps"]) == 8 and done["steps"][-1]["frame"] == 8


def test_a_restart_with_frames_appended_to_its_history_goes_on_to_the_longer_runs_answers(tmp_path):
    """A history run stopped after 3 of its 5 frames, restarted with the table grown to 8 frames
    (frames 4 and 5 changed too, after the restart point): the uninterrupted 8-frame run's
    answers (1e-10).  It was refused: 'its curve has 6 → 9 points'."""
    table = {"time": [0.01 * k for k in range(8)], "soleus": [20, 60, 120, 160, 120, 60, 30, 60],
             "medial": [5, 20, 60, 100, 140, 100, 40, 20], "lateral": [5, 20, 40, 80, 120, 80, 40, 20]}
    longer = tendon({k: [float(v) for v in vs] for k, vs in table.items()})
    full = run_inline(longer, tmp_path / "full")
    assert full["status"] == "completed"
    short = copy.deepcopy(longer)
    short["history"]["table"] = {k: v[:5] for k, v in table.items()}
    short["history"]["table"]["soleus"][3:5] = [150.0, 100.0]     # after the restart point
    assert len(_stopped(short, full, 3, tmp_path)["steps"]) == 3
    done = _restarted(full, write_config(longer, tmp_path / "longer.yaml"), tmp_path, 1e-10)
    assert len(done["steps"]) == 8


def test_a_restart_with_a_changed_table_names_the_load_and_the_frame(tmp_path):
    """A table changed between a run and its restart is refused naming the load, its column and
    the frame, not the fingerprint's 'load_curve_0 (largest change at entry 7: ...)'."""
    raw = tendon({"time": [0.0, 0.1, 0.2], "soleus": [10.0, 20.0, 30.0], "medial": [0.0, 5.0, 10.0],
                  "lateral": [0.0, 5.0, 10.0]})
    assert run_inline(raw, tmp_path / "run")["status"] == "completed"
    raw["history"]["table"]["soleus"][1] = 21.0
    p = solve_cli(write_config(raw, tmp_path / "again.yaml"), extra=["--restart", str(tmp_path / "run")])
    assert p.returncode == 2, p.stderr
    assert ("was written by another model: the load curve of loads[0] (column 'soleus'): its multiplier "
            "at load factor 2 (a history: frame 2) 20 → 21; restart with") in p.stderr, p.stderr
    table = raw["history"]["table"]
    raw["history"]["table"] = {k: v + [v[-1] + 0.1 if k == "time" else 0.0] for k, v in table.items()}
    p = solve_cli(write_config(raw, tmp_path / "longer.yaml"), extra=["--restart", str(tmp_path / "run")])
    assert p.returncode == 2, p.stderr     # a frame appended, and frame 2 changed: frame 2 named
    assert "its multiplier at load factor 2 (a history: frame 2) 20 → 21; restart with" in p.stderr, p.stderr
    raw["history"]["table"]["soleus"][1] = 20.0          # only appended: the run goes on to frame 4
    p = solve_cli(write_config(raw, tmp_path / "longer.yaml"), extra=["--restart", str(tmp_path / "run")])
    assert p.returncode == 0 and len(read_summary(tmp_path / "run")["steps"]) == 4, p.stderr


@pytest.mark.slow
@pytest.mark.parametrize("ranks", ONE_AND_TWO_RANKS)
def test_a_friction_history_restarts_with_its_load_predictor(tmp_path, ranks):
    """With friction the answer follows the Newton path, so a restart must start each frame where
    the uninterrupted run does: the tangent predictor needs the factor of the last converged state,
    which a restart factors again (predictor.TangentPredictor.prime).  Without it the first frame
    after a restart started unpredicted (|F| 69 against 27 N here; on a 13-frame μ = 0.3 stride a
    later frame then cut back where the uninterrupted one did not: the final probes up to 6 %
    apart).  On 1 rank and on 2 (the factor is collective)."""
    table = {"time": [0.01 * k for k in range(6)], "soleus": [20, 60, 120, 160, 80, 20],
             "medial": [5, 20, 60, 100, 140, 60], "lateral": [5, 20, 40, 80, 120, 60]}
    raw = tendon({k: [float(v) for v in vs] for k, vs in table.items()})
    raw["contact"]["tangential"] = {"law": "coulomb", "friction": 0.3}
    full = run_inline(raw, tmp_path / "full")
    assert full["status"] == "completed"
    kept = len(_stopped(raw, full, 3, tmp_path)["steps"])
    assert 2 <= kept < 6
    done = _restarted(full, write_config(raw, tmp_path / "again.yaml"), tmp_path, 1e-9, ranks)
    first = done["steps"][kept]["newton_history"][0][0]          # |F| where the frame's solve starts
    assert first == pytest.approx(full["steps"][kept]["newton_history"][0][0], rel=1e-3)
    assert len(done["steps"]) == 6


def test_shipped_stride_files_agree():
    """The uniform stride as CSV and as OpenSim storage: the same frames and forces; every
    bias peaks at 2.63 kN in all (workflows/stride.py)."""
    from ancf_petsc.config.load_tables import read_load_table
    data = os.path.join(CONFIGS, "data")
    a = read_load_table(os.path.join(data, "stride_walking_uniform.csv"), "x")
    b = read_load_table(os.path.join(data, "stride_walking_uniform.sto"), "x")
    assert list(a.columns) == list(b.columns) == ["time", "soleus_r", "gasmed_r", "gaslat_r"]
    for k in a.columns:
        assert np.allclose(a.columns[k], b.columns[k])
    for bias in ("gastrocnemius", "uniform", "soleus"):
        t = read_load_table(os.path.join(data, f"stride_walking_{bias}.csv"), "x")
        total = t.columns["soleus_r"] + t.columns["gasmed_r"] + t.columns["gaslat_r"]
        assert t.n_rows == 100 and total.max() == pytest.approx(2630.0, abs=0.01)
        ratio = t.columns["soleus_r"] / t.columns["gasmed_r"]
        assert ratio.max() > 2.0 * ratio.min()          # not proportional


def test_a_unilateral_history_at_large_twist_restarts(tmp_path):
    """With the fade weights differentiated (contact.fade: newton) a frame converges with the
    force -p g grad(w) of its pressed points in a fade band; the restart check evaluates that
    residual (it used the kept weights' and refused every unilateral run at twist >= 90 deg with
    'not an equilibrium', |F| 6e-3 on the walking stride): a run stopped midway continues, and a
    finished one is accepted as it is."""
    table = {"time": [0.01 * k for k in range(6)], "soleus": [40, 150, 300, 450, 300, 150],
             "medial": [20, 60, 120, 200, 260, 200], "lateral": [20, 60, 120, 200, 260, 200]}
    raw = tendon({k: [float(v) for v in vs] for k, vs in table.items()}, elements=4, contact="unilateral")
    raw["geometry"]["twist_deg"] = 90.0
    full = run_inline(raw, tmp_path / "full")
    assert full["status"] == "completed"
    cfg = write_config(raw, tmp_path / "again.yaml")
    p = solve_cli(cfg, extra=["--restart", str(tmp_path / "full"), "--quiet"])
    assert p.returncode == 0, p.stderr
    _stopped(raw, full, 3, tmp_path)
    done = _restarted(full, cfg, tmp_path, 1e-8)
    assert len(done["steps"]) == 6


@pytest.mark.parametrize("contact", ["sliding", pytest.param("unilateral", marks=pytest.mark.mpi), "coulomb"])
def test_a_frame_that_repeats_its_loads_takes_no_newton_iteration(tmp_path, contact):
    """A frame whose forces are the frame before's (a stride's swing) starts at that converged
    state, which already holds them: no load predictor and, with unilateral contact, no
    complementarity prediction (it counted as one Newton iteration per swing frame: the
    walking stride's unilateral run 256 -> 215), only the check; the state stays the same.
    With friction too (μ = 0.3: the stick state holds its history); unilateral also on 2 ranks,
    the same answers as on one."""
    table = {"time": [0.01 * k for k in range(5)], "soleus": [40.0, 150.0, 150.0, 150.0, 80.0],
             "medial": [20.0, 60.0, 60.0, 60.0, 30.0], "lateral": [20.0, 60.0, 60.0, 60.0, 30.0]}
    raw = tendon(table, contact="sliding" if contact == "coulomb" else contact)
    if contact == "coulomb":
        raw["contact"]["tangential"] = {"law": "coulomb", "friction": 0.3}
    s = run_inline(raw, tmp_path / contact)
    assert s["status"] == "completed"
    its = [st["iterations"] for st in s["steps"]]
    assert its[2] == its[3] == 0 and min(its[1], its[4]) > 0, its
    for k in (2, 3):
        assert np.abs(_ends(s, k) - _ends(s, 1)).max() <= 1e-12 * np.abs(_ends(s, 1)).max()
    if contact == "unilateral":
        p = solve_cli(write_config(raw, tmp_path / "two.yaml"), ranks=2,
                      extra=["--output-dir", str(tmp_path / "two"), "--quiet"])
        assert p.returncode == 0, p.stderr
        two = read_summary(tmp_path / "two")
        # frame 1 from rest takes its own path on 2 ranks (MUMPS's distributed factor rounds
        # otherwise: 67 Newton iterations in 2 sub-steps against 35 in one on one rank), and
        # with it frame 2's start: after a first increment that reached frame 1 whole and formed
        # the contact state there is no load prediction (stepper.py ``_contact_formed``), so
        # frame 2 takes one iteration more on one rank (6 against 5); the repeated frames none
        its2 = [st["iterations"] for st in two["steps"]]
        assert its2[2] == its2[3] == 0 and its2[4] == its[4] and abs(its2[1] - its[1]) <= 1, (its, its2)
        # the same answers to the Newton tolerance along those paths (1.5e-9 measured at frame 1)
        for k in range(5):
            assert np.abs(_ends(two, k) - _ends(s, k)).max() <= 1e-8 * np.abs(_ends(s, k)).max()



def test_a_frame_reloading_from_zero_loads_is_a_first_increment_from_rest(tmp_path):
    """Without friction a frame of zero loads is the reference state: a table starting with a
    frame of zeros, or unloading to 0 N, and then loading to 150 / 50 / 50 N took that frame with
    the tangent load predictor and differentiated contact weights, 30 Newton iterations and a
    cut-back (DIVERGED_MAX_IT) against 10 in one increment from rest.  Now the frame is the
    first increment from rest: the iterations and the answer of a run whose only frame it is."""
    frames = {"soleus": 150.0, "medial": 50.0, "lateral": 50.0}
    alone = run_inline(tendon({"time": [0.0], **{k: [v] for k, v in frames.items()}}), tmp_path / "alone")
    for before in ([0.0], [100.0, 0.0]):
        table = {k: [v * (b > 0.0) for b in before] + [v] for k, v in frames.items()}
        table["time"] = [0.1 * k for k in range(len(before) + 1)]
        s = run_inline(tendon(table), tmp_path / f"after_{len(before)}")
        last = s["steps"][-1]
        assert (last["cutbacks"], last["iterations"]) == (0, alone["steps"][0]["iterations"]), before
        assert np.abs(_ends(s) - _ends(alone)).max() <= 1e-10 * np.abs(_ends(alone)).max()



@pytest.mark.parametrize("steps", [[3.0, 1.0], [2.5, 6.0], [7.0], [2.0, 3.0]])
def test_steps_edited_on_a_history_spec_must_be_its_first_frames(tmp_path, steps):
    """Through the Python API a history spec's steps were solved as edited: [3, 1] stopped with
    an UnboundLocalError, 2.5 was reported as frame 2 (time 0.15 s), 7 of a 6-frame table as
    frame 7 (time 0.5 s, the loads held at frame 6's), all 'completed'.  Now they must be the
    first frames, 1, 2, …; those run as a shorter table does."""
    from ancf_petsc.api import solve
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.pop("steps")
    raw["loads"][0].update(traction_force=[1.0, 0.0, 0.0], column="f")
    raw["history"] = {"table": {"time": [0.1 * k for k in range(6)], "f": [10.0, 45.0, 0.0, 0.0, 20.0, 45.0]}}
    raw["output"] = {"dir": str(tmp_path / "run"), "vtk": False}
    spec = parse_config(raw, base_dir=CONFIGS)
    spec.steps = steps
    with pytest.raises(ConfigError, match=r"^steps: with history every frame of history\.table is a reported "
                                          r"step \(load factor k = frame k\): give 1, 2, … up to at most 6"):
        solve(spec, log=lambda s: None)
    spec.steps = [1, 2, 3]
    done = solve(spec, log=lambda s: None).summary
    assert [(s["frame"], s["time"]) for s in done["steps"]] == [(1, 0.0), (2, 0.1), (3, 0.2)]



def test_a_restart_with_another_clock_is_refused(tmp_path):
    """A history restarted with its time column changed (ms for s) went on, and its outputs
    mixed the two: frames 0.04, 0.14 s then 240, 340 s.  Now the restart names the frame and
    both times; the same clock (frames appended) goes on."""
    from ancf_petsc.api import solve
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.pop("steps")
    raw["loads"][0].update(traction_force=[1.0, 0.0, 0.0], column="f")
    raw["history"] = {"table": {"time": [0.04, 0.14], "f": [10.0, 20.0]}}
    run_inline(raw, tmp_path / "run")
    longer = copy.deepcopy(raw)
    longer["history"]["table"] = {"time": [40.0, 140.0, 240.0], "f": [10.0, 20.0, 30.0]}
    longer["output"] = {"dir": str(tmp_path / "run"), "vtk": False}
    with pytest.raises(ConfigError, match=r"^--restart: .* was written with another clock: frame 1 was at "
                                          r"0\.04 s, the column 'time' of history\.table gives 40 s; restart"):
        solve(parse_config(longer, base_dir=CONFIGS), log=lambda s: None, restart=str(tmp_path / "run"))
    longer["history"]["table"]["time"] = [0.04, 0.14, 0.24]
    done = solve(parse_config(longer, base_dir=CONFIGS), log=lambda s: None, restart=str(tmp_path / "run")).summary
    assert [s["time"] for s in done["steps"]] == [0.04, 0.14, 0.24]



@pytest.mark.parametrize("edit", ["scale", "column", "grip", "removed"])
def test_a_history_edited_after_parsing_is_refused_not_ignored(tmp_path, edit):
    """Through the Python API spec.history.scale = 1000 (a table in kN) was ignored: the loads'
    curves were made at parsing, and the bar was pulled by 0.01 and 0.045 N, 'completed'; so
    was a column's value changed in place, for a load or a grip's displacement, and a history
    removed (spec.history = None: the walking stride's first 2 frames at 1 element solved again
    frame for frame, soleus u_x 0.13661 mm both).  Now refused."""
    from ancf_petsc.api import solve
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.pop("steps")
    raw["loads"][0].update(traction_force=[1.0, 0.0, 0.0], column="f")
    raw["boundary_conditions"].append({"beam": "bar", "node": "last", "name": "grip",
                                       "displacement": {"r": {"y": 1.0}}, "column": "d"})
    raw["history"] = {"table": {"time": [0.0, 0.1], "f": [0.01, 0.045], "d": [0.0, 1e-4]}}
    raw["output"] = {"dir": str(tmp_path / "run"), "vtk": False}
    spec = parse_config(raw, base_dir=CONFIGS)
    if edit == "scale":
        spec.history.scale = 1000.0
    elif edit == "removed":
        spec.history = None
        with pytest.raises(ConfigError, match=r"^history: removed after parsing, but the curve of loads\[0\] "
                                              r"was made from its column 'f' and would still be followed"):
            solve(spec, log=lambda s: None)
        return
    else:
        spec.history.columns["f" if edit == "column" else "d"][1] *= 2.0
    path = r"loads\[0\]" if edit != "grip" else r"boundary_conditions\[1\]"
    with pytest.raises(ConfigError, match=r"^history: edited after parsing .* the curve of " + path +
                                          r" \(column '[fd]'\) was made from the table as parsed"):
        solve(spec, log=lambda s: None)


def test_a_restart_goes_on_where_loads_that_shared_a_curve_part_after_it(tmp_path):
    """Two loads on the bar whose columns are equal in the 2 frames solved share one load curve;
    a third frame that parts them (30 and 25 N) was refused as 'the load curve of loads[0]
    (column 'a'): its loads or prescribed displacements at multiplier 1 differ', though nothing
    at or before the restart's frame changed.  Now it goes on to the 3-frame run's answers; a
    change of one of them at frame 2 is still refused."""
    from ancf_petsc.api import solve
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.pop("steps")
    raw["loads"] = [{"beam": "bar", "node": "last", "traction_force": [1.0, 0.0, 0.0], "column": "a"},
                    {"beam": "bar", "node": "last", "traction_force": [0.0, 0.1, 0.0], "column": "b"}]
    raw["history"] = {"table": {"time": [0.0, 0.1], "a": [10.0, 20.0], "b": [10.0, 20.0]}}
    longer = copy.deepcopy(raw)
    longer["history"]["table"] = {"time": [0.0, 0.1, 0.2], "a": [10.0, 20.0, 30.0], "b": [10.0, 20.0, 25.0]}
    full = run_inline(longer, tmp_path / "full")
    changed = copy.deepcopy(longer)
    changed["history"]["table"]["b"][1] = 21.0
    for out in ("run", "changed"):
        run_inline(raw, tmp_path / out)
    done = solve(parse_config(dict(longer, output={"dir": str(tmp_path / "run"), "vtk": False}), base_dir=CONFIGS),
                 log=lambda s: None, restart=str(tmp_path / "run")).summary
    assert done["status"] == "completed" and len(done["steps"]) == 3
    tip = [np.array(s["steps"][-1]["probes"]["tip"]["displacement"]) for s in (full, done)]
    assert np.abs(tip[0] - tip[1]).max() <= 1e-10 * np.abs(tip[0]).max()
    with pytest.raises(ConfigError, match="written by another model"):
        solve(parse_config(dict(changed, output={"dir": str(tmp_path / "changed"), "vtk": False}),
                           base_dir=CONFIGS), log=lambda s: None, restart=str(tmp_path / "changed"))


def _pvd_times(path) -> list[tuple[float, str]]:
    import re
    return [(float(t), f) for t, f in re.findall(r'timestep="([^"]+)" part="0" file="([^"]+)"', path.read_text())]


def test_a_history_s_paraview_series_runs_on_its_clock(tmp_path):
    """surface.pvd of a history gave each frame its frame number as time (1, 2, 3 for frames at
    0, 0.25, 0.5 s), and the rest state time 0, which frame 1 has here.  Now each frame is at its
    time [s] (the clock column) and the rest state, not a frame, is written (surface_0000.vtu) but
    not listed; a restart with a frame appended lists them the same way."""
    import meshio
    from ancf_petsc.api import solve
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.pop("steps")
    raw["loads"][0].update(traction_force=[1.0, 0.0, 0.0], column="f")
    raw["history"] = {"table": {"time": [0.0, 0.25, 0.5], "f": [10.0, 20.0, 30.0]}}
    run_inline(raw, tmp_path / "run")
    assert _pvd_times(tmp_path / "run" / "surface.pvd") == [
        (0.0, "surface_0001.vtu"), (0.25, "surface_0002.vtu"), (0.5, "surface_0003.vtu")]
    assert (tmp_path / "run" / "surface_0000.vtu").exists()
    assert meshio.read(tmp_path / "run" / "surface_0002.vtu").field_data["load_factor"].tolist() == [2.0]
    raw["history"]["table"] = {"time": [0.0, 0.25, 0.5, 0.75], "f": [10.0, 20.0, 30.0, 20.0]}
    res = solve(parse_config(dict(raw, output={"dir": str(tmp_path / "run")}), base_dir=CONFIGS),
                log=lambda s: None, restart=str(tmp_path / "run"))
    assert res.status == "completed" and len(res.summary["steps"]) == 4
    assert [t for t, _ in _pvd_times(tmp_path / "run" / "surface.pvd")] == [0.0, 0.25, 0.5, 0.75]


def test_a_friction_history_restarted_at_a_repeated_frame_goes_on_as_the_uninterrupted_run(tmp_path):
    """A frame that repeats the loads of the one before takes no Newton iteration and factors
    no tangent, so the predictor of the next frame uses the factor of the last frame that did.
    A restart at the repeated frame primed it with the history of the level before the restart
    instead (the repeated frame's, not the loaded one's): with μ = 0.3 the next frame started at
    |F| 1467 against the uninterrupted run's 153.6 N, and the unloading frame after it ended
    8.4 µm off the uninterrupted state, with 0.52 N support reactions under zero loads; the
    reloaded frame's probes 6e-4 apart.  Now the frames agree to 1e-9 of the largest end move."""
    table = {"time": [0.1 * k for k in range(5)], "soleus": [100.0, 300.0, 300.0, 0.0, 300.0],
             "medial": [20.0, 60.0, 60.0, 0.0, 60.0], "lateral": [20.0, 60.0, 60.0, 0.0, 60.0]}
    raw = tendon(table)
    raw["contact"]["tangential"] = {"law": "coulomb", "friction": 0.3}
    full = run_inline(raw, tmp_path / "full")
    assert full["status"] == "completed" and full["steps"][2]["iterations"] == 0
    assert len(_stopped(raw, full, 3, tmp_path)["steps"]) == 3
    p = solve_cli(write_config(raw, tmp_path / "again.yaml"), extra=["--restart", str(tmp_path / "run"), "--quiet"])
    assert p.returncode == 0, p.stderr
    done = read_summary(tmp_path / "run")
    scale = max(np.abs(_ends(full, k)).max() for k in range(5))
    for k in range(5):
        assert np.abs(_ends(done, k) - _ends(full, k)).max() <= 1e-9 * scale, k
        reactions = [np.array(list(s["steps"][k]["reactions"].values())) for s in (full, done)]
        assert np.abs(reactions[0] - reactions[1]).max() <= 1e-6, k


def test_a_friction_history_restarted_before_any_load_goes_on_as_the_uninterrupted_run(tmp_path):
    """Frames of zero loads first take no Newton iteration, but the first one's stability count
    factors the tangent at rest, which the uninterrupted run's predictor then uses: a restart
    after them must prime that factor too (not priming it, frame 3 started unpredicted: 19 Newton
    iterations against 16).  Stopped after frame 2 (a table of 2 frames), restarted with all 4."""
    table = {"time": [0.0, 0.1, 0.2, 0.3], "soleus": [0.0, 0.0, 100.0, 300.0],
             "medial": [0.0, 0.0, 20.0, 60.0], "lateral": [0.0, 0.0, 20.0, 60.0]}
    raw = tendon(table)
    raw["contact"]["tangential"] = {"law": "coulomb", "friction": 0.3}
    full = run_inline(raw, tmp_path / "full")
    assert full["status"] == "completed" and full["steps"][1]["iterations"] == 0
    run_inline(tendon({k: v[:2] for k, v in table.items()}) | {"contact": raw["contact"]}, tmp_path / "run")
    done = _restarted(full, write_config(raw, tmp_path / "again.yaml"), tmp_path, 1e-10)
    assert [s["iterations"] for s in done["steps"]] == [s["iterations"] for s in full["steps"]]


def test_a_unilateral_history_restarted_at_an_unloaded_frame_reloads_as_the_uninterrupted_run(tmp_path):
    """The active set's settled streak (solving/newton.py: increments whose predictions changed
    no status) decides whether an increment is first solved with its status kept; a restart
    started it again at 0.  Reloading from a frame of zero loads (40/80/0/80 N on the soleus,
    10/20/0/20 on each gastrocnemius, unilateral, 2 elements), the restarted run then predicted
    from rest, lost its way and took 122 Newton iterations against the uninterrupted run's 16.
    The streak is now kept in results.h5 (restart/settled_increments): the same iterations and
    answers."""
    table = {"time": [0.0, 0.1, 0.2, 0.3], "soleus": [40.0, 80.0, 0.0, 80.0],
             "medial": [10.0, 20.0, 0.0, 20.0], "lateral": [10.0, 20.0, 0.0, 20.0]}
    raw = tendon(table, contact="unilateral")
    full = run_inline(raw, tmp_path / "full")
    assert full["status"] == "completed"
    assert len(_stopped(raw, full, 3, tmp_path)["steps"]) == 3
    done = _restarted(full, write_config(raw, tmp_path / "again.yaml"), tmp_path, 1e-10)
    assert [s["iterations"] for s in done["steps"]] == [s["iterations"] for s in full["steps"]]


def _loop(frames: int) -> dict:
    """A closed loop in load space, ``frames`` frames a leg: the soleus to 300 N, the gastrocnemii
    to 200 N each, the soleus back to 0, the gastrocnemii back to 0."""
    corners = np.array([[0, 0, 0], [300, 0, 0], [300, 200, 200], [0, 200, 200], [0, 0, 0]], float)
    rows = np.array([a + t * (b - a) for a, b in zip(corners[:-1], corners[1:])
                     for t in np.linspace(0.0, 1.0, frames + 1)[1:]])
    return {"time": [0.01 * k for k in range(len(rows))], "soleus": rows[:, 0].tolist(),
            "medial": rows[:, 1].tolist(), "lateral": rows[:, 2].tolist()}


def _loads_work(summary, frames: int) -> tuple[float, float]:
    """The work of the end loads over the loop and over its loading half [J]: each subtendon's
    end force times its elongation (the section-mean u_x, conjugate to a traction_force),
    trapezoid over the frames from rest."""
    names = ("soleus", "medial_gastrocnemius", "lateral_gastrocnemius")
    F = np.array([[0.0] * 3] + [[s["subtendons"][n]["end_force"][0] for n in names] for s in summary["steps"]])
    E = np.array([[0.0] * 3] + [[s["subtendons"][n]["elongation"] for n in names] for s in summary["steps"]])
    w = 0.5 * (F[1:] + F[:-1]) * np.diff(E, axis=0)
    return float(w.sum()), float(w[:2 * frames].sum())


@pytest.mark.slow
def test_a_closed_load_loop_does_no_work_without_friction_and_dissipates_with_it(tmp_path):
    """Around a closed loop of end loads, sliding contact is conservative: the loads' work is the
    trapezoid rule's error, 4e-4 → 1.4e-4 of the loading work at 6 → 12 frames a leg (measured);
    Coulomb friction (μ = 0.3) dissipates 5 % of it.  As μ → 0 the friction answer tends to the
    frictionless one with the same pressure space (friction's default is linear along the beam:
    config/contact.default_axial), O(μ): 3e-4 of the displacements at μ = 1e-4 (the quadratic
    default differs by 2 %, a discretisation, not friction)."""
    runs = {}
    for name, frames, mu in (("s6", 6, None), ("s12", 12, None), ("c6", 6, 0.3)):
        raw = tendon(_loop(frames))
        if mu:
            raw["contact"]["tangential"] = {"law": "coulomb", "friction": mu}
        runs[name] = run_inline(raw, tmp_path / name)
        assert runs[name]["status"] == "completed", name
    (w6, load6), (w12, load12), (wc, loadc) = (_loads_work(runs[k], f) for k, f in
                                                (("s6", 6), ("s12", 12), ("c6", 6)))
    assert abs(w12) < 5e-4 * load12 and abs(w12) < 0.5 * abs(w6), (w6, w12, load12)
    assert wc > 0.02 * loadc and wc > 20 * abs(w6), (wc, loadc, w6)
    limit = {}
    for mu in (None, 1e-4):
        raw = tendon(_loop(6))
        raw["contact"]["projection"] = {"axial": 1}
        if mu:
            raw["contact"]["tangential"] = {"law": "coulomb", "friction": mu}
        s = run_inline(raw, tmp_path / f"limit_{mu}")
        assert s["status"] == "completed"
        limit[mu] = np.array([_ends(s, k) for k in range(len(s["steps"]))])
    assert np.abs(limit[1e-4] - limit[None]).max() <= 1e-3 * np.abs(limit[None]).max()
