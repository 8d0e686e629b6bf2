"""workflows/stride_bench.tolerance_sweep (scripts/bench_stride.py --tolerances): each factor's run
gets factor × the reference run's own absolute tolerance, and the changes are the largest over
every frame relative to the reference's largest value."""
import numpy as np
import pytest

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


def test_option_pairs_alternate_the_sides_and_take_the_ratio_pair_by_pair(monkeypatch, tmp_path):
    """scripts/bench_stride.py --vs-petsc: without, with, without, with …; each pair's ratio of
    frames/s (without / with), medians per side, the options only on the 'with' side."""
    seen, solve = [], iter([0.5, 1.0, 0.25, 1.0, 0.5, 0.5])

    def fake_solve(cmd, cfg, out):
        seen.append(((cfg.get("petsc") or {}).get("mat_mumps_icntl_6"), out.rsplit("/", 1)[-1]))
        t = next(solve)
        return None, 1.0, {"status": "completed", "newton_iterations": 7, "steps": [{}] * 10,
                           "timings": {"solve": t, "linear_solve": t / 2}}

    monkeypatch.setattr(stride_bench, "solve_config", fake_solve)
    case = stride_bench.StrideCase("x", EnvelopeCell(NEO, 45.0, "uniform", "sliding", 0.0, 4, stride=True))
    r = stride_bench.option_pairs(case, ["ancf-solve"], str(tmp_path), {"mat_mumps_icntl_6": "3"}, 3)
    assert seen == [(None, "without_options"), ("3", "with_options")] * 3
    # frames/s: without 20, 40, 20; with 10, 10, 20 -> pairs 2, 4, 1
    assert r["ratio"] == (2.0, 1.0, 4.0)
    assert r["without"]["per_solve"] == 20.0 and r["with"]["per_solve"] == 10.0
    assert r["without"]["linear_solve"] == 0.25 and r["with"]["iterations"] == [7]


def test_parse_options_reads_pairs_and_names_a_bad_one():
    assert stride_bench.parse_options("mat_mumps_icntl_6=3, -snes_atol=1e-6") == {
        "mat_mumps_icntl_6": "3", "snes_atol": "1e-6"}
    with pytest.raises(ValueError, match="OPTION=VALUE"):
        stride_bench.parse_options("mat_mumps_icntl_6")


def test_only_that_matches_no_case_is_refused(capsys):
    """scripts/bench_stride.py --only X with no case labelled X printed the header, ran nothing and
    exited 0; now it names the option and the cases, exit 2."""
    import importlib
    main = importlib.import_module("apps.stride_bench").main
    with pytest.raises(SystemExit) as exc:
        main(["--only", "nothing", "--work", "unused"])
    err = capsys.readouterr().err.splitlines()[-1]
    assert exc.value.code == 2
    assert err.startswith("bench_stride: error: --only: no case's label contains 'nothing'; cases: "
                          "neo-Hookean sliding 4 el.;"), err
