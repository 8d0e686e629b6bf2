"""``accuracy: {probe, rtol}``: Richardson estimates and the automatic choice of the element count."""
import math
import os

import pytest

from ancf_petsc.config.values import ConfigError
from ancf_petsc.config.parse import parse_config
from ancf_petsc.workflows.refinement import Discretisation, apply, choose, quantity, richardson
from helpers import CONFIGS, load_raw, read_summary, run_inline, solve_cli, write_config


@pytest.mark.parametrize("p", [1.0, 2.0, 3.5])
def test_richardson_recovers_limit_and_order_of_a_power_law(p):
    q = [2.5 + 0.3 * h ** p for h in (0.4, 0.2, 0.1)]
    ex = richardson(*q)
    assert ex.reliable
    assert ex.order == pytest.approx(p, rel=1e-10)
    assert ex.limit == pytest.approx(2.5, rel=1e-12)


def test_richardson_flags_oscillating_and_constant_sequences():
    assert not richardson(1.0, 1.2, 1.1).reliable          # oscillates
    assert not richardson(1.0, 1.1, 1.3).reliable          # diverges
    same = richardson(4.0, 4.0, 4.0)
    assert same.reliable and same.limit == 4.0


def test_choose_accepts_a_converged_plateau_but_not_scatter():
    """Non-monotone rungs within rtol/2 of their mean have converged (e.g. reduced integration);
    the same pattern spread wider is no estimate at all."""
    idx, errs, ex = choose([6.10, 6.3794, 6.3703, 6.3812], 5e-3)
    assert ex.kind == "plateau" and idx == 1 and errs[1] <= 5e-3
    assert ex.limit == pytest.approx((6.3794 + 6.3703 + 6.3812) / 3)
    assert choose([6.3794, 6.30, 6.3812], 5e-3)[0] is None


def test_choose_picks_the_coarsest_rung_within_tolerance():
    values = [1.0 + 0.1 * 2.0 ** (-2 * k) for k in range(5)]    # error 0.1 · 4^-k
    idx, errs, ex = choose(values, 1e-2)
    assert ex.limit == pytest.approx(1.0, rel=1e-12)
    assert idx == 2 and errs[2] <= 1e-2 < errs[1]
    assert choose(values[:2], 1e-2)[0] is None                  # fewer than three rungs
    assert choose([1.0, math.nan, 1.1, 1.2], 1e-2)[0] is None   # no three consecutive finite rungs


def test_a_probe_component_held_at_zero_is_met_by_the_first_rungs():
    """Three rungs of exactly 0 (the y of a gripped bundle's tip) were 'constant, limit 0' with
    no error (relative to 0: nan), so no rung met rtol and the ladder ran on to max_elements."""
    idx, errs, ex = choose([0.0, 0.0, 0.0], 1e-3)
    assert ex.kind == "constant" and idx == 0 and errs == [0.0, 0.0, 0.0]
    assert choose([1e-3, 0.0, 0.0, 0.0], 1e-3)[0] == 1
    idx, errs, _ = choose([1.0 + 0.1 * 4.0 ** -k for k in range(3)], 1e-2)    # a limit not 0: as before
    assert idx == 2 and errs[2] == pytest.approx(0.1 / 16, rel=1e-9)


def test_apply_sets_every_beam_and_keeps_the_rest():
    raw = load_raw("achilles_type3_psi45.yaml")
    out = apply(raw, Discretisation(elements=2, axial_points=2, cubature_degree=4, element="3333"))
    for b in out["beams"]:
        assert (b["elements"], b["axial_points"], b["section"]["cubature_degree"], b["element"]) == \
            (2, 2, 4, "3333")
    assert raw["beams"][0]["elements"] == 4 and "element" not in raw["beams"][0]
    assert quantity({"steps": [{"load_factor": 1.0, "probes": {"p": {"displacement": [3.0, 4.0, 0.0]}}}]},
                    "p") == 5.0


@pytest.mark.parametrize("accuracy,path,words", [
    ({"probe": "nope"}, "accuracy.probe", "no probe 'nope'"),
    ({"probe": "tip", "rtol": 0.0}, "accuracy.rtol", "must be > 0"),
    ({"probe": "tip", "level": 0.33}, "accuracy.level", "must be one of the steps (0.25, 0.5, 0.75, 1); got 0.33"),
    ({"probe": "tip", "start": 4, "max_elements": 8}, "accuracy.max_elements", "(= 16); got 8"),
    ({"probe": "tip", "component": "w"}, "accuracy.component", "must be one of x, y, z, norm"),
    ({"probe": "tip", "section_order": "yes"}, "accuracy.section_order", "must be one of none, check"),
])
def test_accuracy_config_errors_name_the_key(accuracy, path, words):
    raw = load_raw("bending_neohookean.yaml")
    raw["accuracy"] = accuracy
    with pytest.raises(ConfigError) as exc:
        parse_config(raw, base_dir=CONFIGS)
    assert exc.value.path == path and words in str(exc.value)


def test_uniaxial_tension_needs_one_element(tmp_path):
    """The homogeneous solution is in the element's space: the ladder sees three equal rungs."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["elements"] = 4
    raw["accuracy"] = {"probe": "tip", "component": "x", "rtol": 1e-6}
    s = run_inline(raw, tmp_path)
    acc = s["accuracy"]
    assert acc["met"] and acc["chosen_elements"] == 1
    assert s["elements_per_beam"] == {"bar": 1}
    assert [r["elements"] for r in acc["ladder"]] == [1, 2, 4]
    values = [r["value"] for r in acc["ladder"]]
    assert max(values) - min(values) < 1e-12 * abs(values[0])


def test_a_load_historys_ladder_runs_its_frames(tmp_path):
    """``accuracy:`` with ``history:``: each rung runs the history's frames and the probe is read
    at the level asked for.  Before, every rung was given ``steps``, which a history refuses: a
    config error about a key the config did not have."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw.pop("steps")
    raw["history"] = {"table": {"time": [0.0, 1.0, 2.0], "f": [10.0, 30.0, 20.0]}}
    raw["loads"][0]["column"] = "f"
    raw["accuracy"] = {"probe": "tip", "component": "x", "rtol": 1e-6, "level": 2}
    s = run_inline(raw, tmp_path)
    acc = s["accuracy"]
    assert acc["met"] and acc["chosen_elements"] == 1 and len(s["steps"]) == 3
    assert acc["reused_rung"] is True            # the rung ran every frame: no second solve
    at_level = s["steps"][1]["probes"]["tip"]["displacement"][0]
    assert acc["ladder"][0]["value"] == pytest.approx(at_level, rel=1e-9)


def test_bending_choice_meets_tolerance_against_a_fine_reference(tmp_path):
    rtol = 2e-3
    raw = load_raw("bending_neohookean.yaml")
    raw["beams"][0]["axial_points"] = 2
    raw["accuracy"] = {"probe": "tip", "component": "z", "rtol": rtol, "start": 2}
    s = run_inline(raw, tmp_path / "auto")
    acc = s["accuracy"]
    assert acc["met"] and acc["estimated_error"] <= rtol
    fine = run_inline(apply(raw | {"accuracy": None}, Discretisation(elements=64)), tmp_path / "fine")
    z, z_fine = (st["steps"][-1]["probes"]["tip"]["displacement"][2] for st in (s, fine))
    assert abs(z - z_fine) <= rtol * abs(z_fine)
    assert s["elements_per_beam"]["beam"] == acc["chosen_elements"] < 64
    # the estimate is honest: the chosen model's true error is within a factor 3 of it
    assert abs(z - z_fine) / abs(z_fine) <= 3.0 * acc["estimated_error"]


def test_section_order_check_compares_the_start_rung_one_order_up(tmp_path):
    """``section_order: check`` solves the start rung again with the next element of the section
    ladder (``richer``: 3333 → 3363, its default locking) and reports the probe's change.  In
    uniaxial tension both section fields hold the exact uniform contraction: no change, the
    field suffices.  The bending scene on 3333 (ecm) moves by 2.3 % at 2 elements: the check
    says so, its richer value is a 3363 run of the same rung, and the run keeps 3333."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["element"] = "3333"
    raw["accuracy"] = {"probe": "tip", "component": "x", "rtol": 1e-6, "section_order": "check"}
    so = run_inline(raw, tmp_path / "bar")["accuracy"]["section_order"]
    assert so["element"] == ["3333"] and so["next"] == "3363" and so["needs_next"] is False
    assert so["change"] < 1e-10
    raw = load_raw("bending_neohookean.yaml")
    raw["beams"][0].update(axial_points=2, element="3333")
    raw["accuracy"] = {"probe": "tip", "component": "z", "rtol": 2e-3, "start": 2, "section_order": "check"}
    s = run_inline(raw, tmp_path / "bending")
    so = s["accuracy"]["section_order"]
    assert so["needs_next"] is True and so["change"] > 0.01
    assert s["elements_per_beam"] == {"beam": s["accuracy"]["chosen_elements"]}
    direct = run_inline(apply(raw | {"accuracy": None}, Discretisation(elements=2, element="3363")),
                        tmp_path / "direct")
    assert so["next_value"] == pytest.approx(direct["steps"][-1]["probes"]["tip"]["displacement"][2], rel=1e-12)
    assert so["value"] == s["accuracy"]["ladder"][0]["value"]


def test_the_top_of_the_section_ladder_has_no_next_rung():
    from ancf_petsc.physics.elements import ELEMENTS, richer
    top = max(ELEMENTS.values(), key=lambda e: e.order)
    assert richer([top.name]) is None
    assert all(richer([e.name]).order > e.order for e in ELEMENTS.values() if e.order < top.order)


@pytest.mark.mpi
def test_accuracy_run_is_the_same_on_two_ranks(tmp_path):
    raw = load_raw("bending_neohookean.yaml")
    raw["beams"][0].update(axial_points=2, element="3333")      # its next section order: 3363
    raw["accuracy"] = {"probe": "tip", "component": "z", "rtol": 2e-3, "start": 2, "section_order": "check"}
    serial = run_inline(raw, tmp_path / "serial")
    raw["output"] = {"dir": str(tmp_path / "mpi"), "vtk": False}
    cfg = write_config(raw, tmp_path / "acc.yaml")
    proc = solve_cli(cfg, ranks=2, extra=["--output-dir", str(tmp_path / "mpi")], cwd=CONFIGS)
    assert proc.returncode == 0, proc.stderr
    assert "[accuracy] chosen:" in proc.stdout
    par = read_summary(tmp_path / "mpi")
    assert par["accuracy"]["chosen_elements"] == serial["accuracy"]["chosen_elements"]
    a, b = (st["steps"][-1]["probes"]["tip"]["displacement"][2] for st in (serial, par))
    assert a == pytest.approx(b, rel=1e-9)
    assert "[accuracy] section order: 3333 -> 3363 on the start rung changes tip by" in proc.stdout
    a, b = (st["accuracy"]["section_order"]["next_value"] for st in (serial, par))
    assert a == pytest.approx(b, rel=1e-9)


def test_a_scene_the_ladder_cannot_build_is_refused_with_its_own_counts(tmp_path):
    """Beams of an interface with different element counts: the config error names the counts
    the config gives (4 and 2), before the ladder scales them (it named its first rung's, 2 and 1)."""
    from helpers import solve_cli, write_config
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["beams"][0]["elements"] = 2
    raw["accuracy"] = {"probe": raw["probes"][0]["name"], "component": "x", "rtol": 1e-2, "start": 1}
    p = solve_cli(write_config(raw, tmp_path / "a.yaml"), extra=["--output-dir", str(tmp_path / "o"), "--quiet"])
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert "4 element(s) against 2 of soleus" in p.stderr and "[accuracy]" not in p.stdout, p.stderr


def test_a_ladder_whose_every_rung_fails_solves_the_scene_as_written(tmp_path):
    """Every rung failing (a 2-iteration Newton budget, no cut-back) left no finite rung: the
    choice fell back to the config's 3 elements, which is no rung of 1, 2, 4, and the lookup of
    its rung raised StopIteration (a traceback, exit 1).  Now the scene is solved as written and
    its failure is the run's."""
    raw = load_raw("bending_neohookean.yaml")
    raw["beams"][0]["elements"] = 3
    raw["solver"] = {"max_cutbacks": 0}
    raw["accuracy"] = {"probe": "tip", "component": "z", "rtol": 1e-3, "start": 1, "max_elements": 4}
    s = run_inline(raw, tmp_path, petsc={"snes_max_it": 2})
    acc = s["accuracy"]
    assert [r["status"] for r in acc["ladder"]] == ["failed"] * 3
    assert acc["met"] is False and acc["chosen_elements"] == 3 and acc["reused_rung"] is False
    assert s["status"] == "failed" and s["elements_per_beam"] == {"beam": 3}


@pytest.mark.parametrize("twist, axial, ladder", [
    (180.0, 2, [4, 8, 16, 32, 64]),          # 1 and 2 elements: area 22 %, 1.9 % off
    (90.0, 3, [2, 4, 8, 16, 32, 64]),        # 1 element: 2.1 %
    (45.0, 3, [1, 2, 4, 8, 16, 32, 64]),     # 0.14 % at 1: every rung
])
def test_the_ladder_leaves_out_rungs_whose_pretwist_is_under_resolved(twist, axial, ladder):
    """The paper's tendon at 180 deg (2 axial points) with accuracy {probe: soleus, component: x,
    rtol: 2e-3}: the 1- and 2-element rungs (reference area 22 % and 1.9 % off) put the Richardson
    limit at 6.9030 mm, and 4 elements 'met' the tolerance with an estimated 5.4e-4 where they are
    3.3e-3 off (6.90669 mm against 6.88378 at 32).  Without them it chooses 16 (8.5e-5)."""
    from ancf_petsc.workflows.accuracy import element_counts
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["geometry"]["twist_deg"] = twist
    for b in raw["beams"]:
        b["axial_points"] = axial
    raw["accuracy"] = {"probe": "soleus", "component": "x", "rtol": 2e-3}
    assert element_counts(parse_config(raw, base_dir=CONFIGS)) == ladder


@pytest.mark.parametrize("level", [1.0, 0.5])       # the rung is the whole scene / a second solve
def test_a_ladder_that_meets_no_rtol_says_so(tmp_path, level):
    """No rung met rtol 1e-9 up to 4 elements: the run ended as a plain "completed" (and without a
    final line when the finest rung was the whole scene).  Now its reason code, message and
    summary say the accuracy was not met; every level converged, so the exit code stays 0."""
    raw = load_raw("bending_neohookean.yaml")
    raw["accuracy"] = {"probe": "tip", "component": "z", "rtol": 1e-9, "start": 1, "max_elements": 4,
                       "level": level}
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    proc = solve_cli(write_config(raw, tmp_path / "c.yaml"))
    assert proc.returncode == 0, proc.stderr
    s = read_summary(tmp_path / "out")
    assert s["status"] == "completed" and s["reason_code"] == "ACCURACY_NOT_MET"
    assert "accuracy not met: no rung met rtol 1e-09" in s["message"]
    assert s["accuracy"]["met"] is False and s["accuracy"]["chosen_elements"] == 4
    assert s["accuracy"]["reused_rung"] is (level == 1.0)
    lines = proc.stdout.strip().splitlines()
    assert lines[-1].startswith("[accuracy] accuracy not met") and lines[-2].startswith("[ancf] completed:")


def test_rungs_that_round_a_beams_count_are_left_out(tmp_path):
    """Beams of 4 and 6 elements from start 1: the second beam ran 2 (1.5 rounded), 3, 6, …, so it
    was not refined by 2 between the first rungs, as the Richardson estimate assumes.  Such rungs
    are now left out while three remain, and the run says why."""
    import copy
    from ancf_petsc.workflows.accuracy import element_counts
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["elements"] = 4
    other = copy.deepcopy(raw["beams"][0]) | {"name": "bar2", "elements": 6}
    other["section"] = dict(other["section"], center=[0.0, 0.02])
    raw["beams"].append(other)
    raw["boundary_conditions"].append({"beam": "bar2", "node": "first", "fix": "reduced"})
    raw["loads"].append({"beam": "bar2", "node": "last", "traction_force": [45.0, 0.0, 0.0]})
    raw["steps"] = [1.0]
    raw["accuracy"] = {"probe": "tip", "component": "x", "rtol": 1e-6, "start": 1, "max_elements": 16}
    assert element_counts(parse_config(raw, base_dir=CONFIGS)) == [2, 4, 8, 16]
    raw["accuracy"]["max_elements"] = 4           # 2 and 4 alone: too few to leave 1 out
    assert element_counts(parse_config(raw, base_dir=CONFIGS)) == [1, 2, 4]
    raw["accuracy"]["max_elements"] = 8
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    proc = solve_cli(write_config(raw, tmp_path / "c.yaml"))
    assert proc.returncode == 0, proc.stderr
    assert "ladder over elements per beam [2, 4, 8] (1 left out: some beam's element count would be rounded" \
        in proc.stdout
    s = read_summary(tmp_path / "out")
    assert s["accuracy"]["left_out"] == [1] and s["elements_per_beam"] == {"bar": 2, "bar2": 3}
