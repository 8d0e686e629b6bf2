"""A level whose cut-backs creep towards a bifurcation switches branch from the saddle it met,
without waiting for every halving (solving/early_switch.py).

The second subject's sliding column at twist 90°, gastrocnemius-biased (4 elements): the step
1000 → 1200 N converges on a saddle (1 negative tangent eigenvalue), the smaller steps stall
near the bifurcation at 1034.02 N.  The switch from the 1200 N saddle reaches a stable state
0.4 mm away; taken after every halving it cost 519 Newton iterations at the level (32 cut-backs),
and the level was reported with the last failed attempt's reason (DIVERGED_MAX_IT, |F| 4e-7).
It is now taken at the first failure from the 8th on whose last converged state is near the
critical point (14 cut-backs, 238 iterations).
"""
import numpy as np
import pytest

from helpers import assert_same_as_serial, probe, probes_table, read_summary, run_inline, run_on_ranks


def _column() -> dict:
    from ancf_petsc.workflows.envelope import SUBJECT2, EnvelopeCell, cell_config
    raw = cell_config(EnvelopeCell(SUBJECT2, 90, "gastrocnemius", "sliding", levels=(400.0, 800.0, 1000.0, 1200.0)))
    raw["output"] = {"vtk": False}
    return raw


def test_a_creep_towards_a_bifurcation_switches_from_the_saddle_at_once(tmp_path):
    run_inline(_column(), str(tmp_path))
    s = read_summary(tmp_path)
    assert s["status"] == "completed"
    last = s["steps"][-1]
    assert last["load_factor"] == 1200.0 and last["negative_eigenvalues"] == 0
    (switch,) = last["branch_switches"]
    assert switch["kind"] == "bifurcation" and switch["load_factor"] == 1200.0 and switch["negative_before"] == 1
    assert 0.2e-3 < switch["jump"] < 1e-3                  # a stable state 0.4 mm from the saddle
    # not every halving down to the smallest increment (32 cut-backs, 519 Newton iterations)
    assert 9 <= last["cutbacks"] <= 16 and last["iterations"] < 300
    # the level is reported with the state's own solve, not the last failed attempt's
    assert last["reason"].startswith("CONVERGED") and last["residual_norm"] < 1e-7
    # the same state as the switch after every halving gave (its probes at 1200 N)
    assert np.allclose(probe(s, "medial_gastrocnemius"), [7.6765e-3, -9.9903e-4, 8.9799e-4], atol=2e-8)


@pytest.mark.mpi
def test_the_early_switch_is_the_same_on_two_and_three_ranks(tmp_path):
    """The critical-point reading and the failure count are collective: 1, 2 and 3 ranks switch at
    the same failure, to the same state."""
    runs = run_on_ranks(_column(), tmp_path, ranks=(1, 2, 3))
    last = {n: s["steps"][-1] for n, (_, s) in runs.items()}
    for n in (2, 3):
        assert last[n]["cutbacks"] < 20 and last[n]["load_factor"] == 1200.0
        (switch,) = last[n]["branch_switches"]
        assert switch["sign"] == last[1]["branch_switches"][0]["sign"] and switch["load_factor"] == 1200.0
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()}, rtol=1e-8)
