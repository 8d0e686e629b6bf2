"""workflows/stride_bench.tolerance_sweep (scripts/bench_stride.py --tolerances): each factor's run
gets factor × the reference run's own absolute tolerance, and the changes are the largest over
every frame relative to the reference's largest value."""
import numpy as np

from ancf_petsc.workflows import stride_bench
from ancf_petsc.workflows.envelope import NEO, EnvelopeCell


def test_tolerance_sweep_scales_the_runs_own_tolerance_and_measures_against_it(monkeypatch, tmp_path):
    seen = []

    def fake_solve(cmd, cfg, out):
        atol = (cfg.get("petsc") or {}).get("snes_atol", 2.2e-7)
        seen.append(cfg.get("petsc"))
        steps = [{"probes": {"a": {"displacement": [1.0 + 10.0 * atol * k, 0.0, 2.0]}},
                  "displacement_differences": {"a|b": {"profile": [0.0, 1e-3 + atol]}}} for k in range(4)]
        return None, 1.0, {"status": "completed", "tolerances": {"rtol": 1e-10, "atol": atol, "stol": 1e-12},
                           "newton_iterations": 10, "steps": steps, "timings": {"solve": 0.5}}

    monkeypatch.setattr(stride_bench, "solve_config", fake_solve)
    case = stride_bench.StrideCase("x", EnvelopeCell(NEO, 45.0, "uniform", "sliding", 0.0, 4, stride=True))
    rows = stride_bench.tolerance_sweep(case, ["ancf-solve"], str(tmp_path), [10.0, 100.0])
    assert seen[0] is None and seen[1]["snes_atol"] == 2.2e-6 and abs(seen[2]["snes_atol"] - 2.2e-5) < 1e-20
    assert [r["factor"] for r in rows] == [1.0, 10.0, 100.0]
    assert rows[0]["changes"] == (0.0, 0.0) and rows[0]["per_solve"] == 8.0
    # probes: the largest change at the last frame, 10 (atol - 2.2e-7) 3, over the largest value 2
    assert np.isclose(rows[2]["changes"][0], 30.0 * (2.2e-5 - 2.2e-7) / 2.0)
    assert np.isclose(rows[1]["changes"][1], (2.2e-6 - 2.2e-7) / (1e-3 + 2.2e-7))


def test_tolerance_sweep_stops_when_the_reference_run_gives_no_summary(monkeypatch, tmp_path):
    """Without the reference run's tolerance there is nothing to scale: one crashed row."""
    monkeypatch.setattr(stride_bench, "solve_config", lambda cmd, cfg, out: (None, 1.0, None))
    case = stride_bench.StrideCase("x", EnvelopeCell(NEO, 45.0, "uniform", "sliding", 0.0, 4, stride=True))
    assert stride_bench.tolerance_sweep(case, ["ancf-solve"], str(tmp_path), [10.0]) == [
        {"factor": 1.0, "status": "crashed"}]
