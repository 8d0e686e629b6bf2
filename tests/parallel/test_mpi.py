"""-n 1, -n 2 and -n 3 --oversubscribe give the serial answer on every probe of every step."""
import os

import pytest

from ancf_petsc.workflows.envelope import NEO, EnvelopeCell, cell_config

from helpers import (CONFIGS, assert_same_as_serial, load_raw, probes_table, read_summary, run_on_ranks,
                     subject2_stride_frames, two_beam_twisted, unilateral_stride_frames, write_config)


def _cases():
    uni = load_raw("uniaxial_neohookean.yaml")
    elastica = load_raw("elastica_svk.yaml")
    elastica["beams"][0]["elements"] = 12
    twisted = load_raw("pretwisted_bar.yaml")
    two = two_beam_twisted()
    two["probes"].append({"name": "second_tip", "beam": "second", "node": "last"})
    two["loads"].append({"beam": "second", "node": "last", "force": [0.0, 0.05, 0.02]})
    mixed = two_beam_twisted()                  # element 3333 (ecm) beside 3363
    mixed["beams"][1].update({"element": 3333, "section": dict(mixed["beams"][1]["section"], cubature_degree=3)})
    mixed["probes"] = two["probes"]
    mixed["loads"] = two["loads"]
    # the three subtendons with clamped roots: the roots' pressure functions folded into their
    # neighbours (contact/multipliers.py), multipliers shared by elements on two ranks
    tendon = load_raw("achilles_type3_psi45.yaml")
    for b in tendon["beams"]:
        b["elements"] = 4
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    for bc in tendon["boundary_conditions"]:
        bc["fix"] = "clamped"
    tendon["steps"] = [10.0, 100.0]
    # unilateral at 90 deg: S far from semidefinite at 600 N, predicted with the active set held
    held = cell_config(EnvelopeCell(NEO, 90, "gastrocnemius", "unilateral", levels=(30.0, 100.0, 200.0, 400.0, 600.0)))
    # loading frames of the unilateral walking stride: settled active sets solved before they are
    # predicted, checks read from the converged evaluation (solving/newton.py)
    stride = unilateral_stride_frames(4, 16)
    # Coulomb friction (AIJ, LU): the l2 line search with the whole step first decides on global
    # norms only (linalg/full_step_first.py)
    coulomb = load_raw("achilles_type3_psi45.yaml")
    for b in coulomb["beams"]:
        b["elements"] = 4
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    coulomb["steps"] = [1.0, 2.5, 5.0, 10.0]
    coulomb["contact"] = {"mode": "sliding", "tangential": {"law": "coulomb", "friction": 0.3}}
    # the second subject's stride from rest at 90 deg: Newton steps held to the fade bands
    # (contact/band_step.py: each rank's points, one reduction, the scale on a grid): frames 1-13, to
    # frame 14, which has two equilibria (tests/contact/test_band_step.py)
    band = subject2_stride_frames(90.0, "uniform", 13)
    band["solver"] = {"band_step": 1.5}
    return {"uniaxial-1-element": uni, "elastica": elastica, "pretwisted": twisted, "two-beams": two,
            "two-beams-3363-3333": mixed, "tendon-clamped-roots": tendon, "tendon-unilateral-held": held,
            "tendon-unilateral-stride": stride,
            "tendon-coulomb": coulomb, "subject2-band-step": band}


CASES = _cases()


@pytest.mark.mpi
@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_ranks_agree_with_serial(tmp_path, name):
    runs = run_on_ranks(CASES[name], tmp_path)
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})


#: ancf-solve with a failure forced past a level (argv: config, level) by ``function`` of the
#: tests' module ``module``: the variational fade forces failing, contact points leaving their windows
FORCED = """import sys
sys.path[:0] = [{root!r}, {tests!r}]
from solving.{module} import {function}
{function}(float(sys.argv.pop()))
from apps.ancf_solve import cli
cli()
"""


def forced_on_ranks(tmp_path, module: str, function: str, key: str) -> None:
    """The column of the tests' module ``module`` with ``function``'s failure forced past its first
    level, on 1, 2 and 3 ranks: each completes with summary.json's ``key`` at that level, and
    they give the serial probes and Newton counts."""
    import importlib
    import subprocess
    import sys
    from helpers import MPI_ENV, ROOT
    case = importlib.import_module(f"solving.{module}")
    driver = tmp_path / "driver.py"
    driver.write_text(FORCED.format(root=ROOT, tests=os.path.join(ROOT, "tests"), module=module, function=function))
    tables, its = {}, set()
    for n in (1, 2, 3):
        raw = case.column()
        raw["output"]["dir"] = str(tmp_path / f"n{n}")
        for b in raw["beams"]:
            b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
        cmd = [sys.executable, str(driver), write_config(raw, tmp_path / f"c{n}.yaml"), "--quiet", str(case.STEPS[0])]
        if n > 1:
            cmd = ["mpirun", "--oversubscribe", "-n", str(n)] + cmd
        p = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, **MPI_ENV), timeout=600)
        assert p.returncode == 0, p.stdout + p.stderr
        s = read_summary(tmp_path / f"n{n}")
        assert s["status"] == "completed" and s["ranks"] == n and s[key] == case.STEPS[0]
        tables[n], _ = probes_table(s), its.add(s["newton_iterations"])
    assert_same_as_serial(tables)
    assert len(its) == 1


@pytest.mark.mpi
@pytest.mark.slow
def test_the_switch_to_pointwise_fade_forces_gives_the_serial_answer(tmp_path):
    """``contact.fade_forces: auto`` (solving/fade_switch.py) with the variational solves made to
    fail past the first level: 1, 2 and 3 ranks switch there, rebuild the Jacobian as AIJ with
    LU, and give the serial probes and Newton counts."""
    forced_on_ranks(tmp_path, "test_fade_switch", "fail_variational_past", "fade_forces_pointwise_from")


@pytest.mark.mpi
@pytest.mark.slow
def test_the_widened_search_windows_give_the_serial_answer(tmp_path):
    """solving/window_widening.py with the solves made to lose a contact point from its window
    past the first level: 1, 2 and 3 ranks widen there and give the serial probes and Newton
    counts."""
    forced_on_ranks(tmp_path, "test_window_widening", "lose_points_past", "search_window_whole_from")


@pytest.mark.mpi
@pytest.mark.slow
@pytest.mark.parametrize("forces", ["variational", "pointwise"])
def test_differentiated_fade_weights_give_the_serial_answer(tmp_path, forces):
    """The paper's ψ = 45° sliding column with ``contact.fade: newton`` (contact/weights.py): at
    400 N a point's partner sits in the fade band past the end of its interface curve (weight
    0.399 on every rank count); 1, 2 and 3 ranks give the serial probes and Newton counts, with
    the weights' forces variational (LDLᵀ) and pointwise (``contact.fade_forces``, LU)."""
    import meshio
    import numpy as np
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["contact"]["fade"] = "newton"
    raw["contact"]["fade_forces"] = forces
    runs = run_on_ranks(raw, tmp_path)
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
    assert len({s["newton_iterations"] for _, s in runs.values()}) == 1
    w = meshio.read(os.path.join(tmp_path, "n2", f"contact_{len(raw['steps']):04d}.vtu")).point_data["weight"]
    assert np.any((w > 0.05) & (w < 0.95))


def _unilateral_mixed_column() -> dict:
    """The paper's tendon with 33103 elements (2 per beam), ``locking: mixed`` on the soleus
    alone, unilateral contact, 100 N in one level (three increments from rest)."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b.update(elements=2, element="33103")
        b.pop("axial_points", None)
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["beams"][0]["locking"] = "mixed"
    raw["contact"] = {"mode": "unilateral"}
    raw["steps"] = [100.0]
    return raw


@pytest.mark.mpi
@pytest.mark.slow
def test_unilateral_column_takes_the_serial_path_on_every_rank_count(tmp_path):
    """Two equilibria of this column satisfy the discrete equations and the unilateral conditions
    (|F| 2e-11; one or two active pressure functions; probes 23 % apart), and the Newton path
    decides which one a run reaches.  2 and 3 ranks took another path than one rank: the
    closest-point descent ran a rank's points until all of its batch were done (a point off B
    wandered on), and an exchange rebuilt at the state of the last evaluation dropped the kept
    evaluation, whose projections, made again from their own results, moved where one rank's did
    not.  Now every rank count reaches the serial answer.  (Not always in the serial Newton count:
    in the first solve from rest a point off B whose descent cycles counts with its kept weight,
    and its place after the iteration limit amplifies rounding: 41 iterations on one rank, 106 on
    two and three, measured.)"""
    runs = run_on_ranks(_unilateral_mixed_column(), tmp_path)
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})


@pytest.mark.mpi
@pytest.mark.slow
def test_a_level_passed_over_gives_the_serial_answer(tmp_path):
    """solving/step_over.py: the second subject's column whose 1600 N level lies in a gap of the
    load path (tests/solving/test_step_over.py); 1, 2 and 3 ranks report it at the same load
    factor, past the same last converged state, with the serial probes."""
    from solving.test_step_over import gap_column
    runs = run_on_ranks(gap_column(), tmp_path)
    gaps = {n: s["steps"][-1]["passed_over"] for n, (_, s) in runs.items()}
    assert all(g == gaps[1] for g in gaps.values()) and gaps[1]["reported_at"] == 1640.0, gaps
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
