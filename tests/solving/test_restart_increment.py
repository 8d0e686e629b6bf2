"""A restart whose stored next load increment is not > 0 (a results.h5 written before f0a0e19
for a level passed over with the one before it: 0.0; or edited): the stepper stepped by 0 at the
last converged level forever (0 Newton iterations, killed after 60 s).  It now goes on with the
last accepted increment and says so."""
import h5py
import numpy as np
import pytest

from helpers import cantilever

from solving.test_fade_switch import run


def test_the_next_increment_of_a_restart_is_above_zero():
    """The stored increment when > 0; else the last accepted one, else the way to the next level."""
    from types import SimpleNamespace
    from ancf_petsc.solving.records import restart_increment
    point = SimpleNamespace(step=3, load_factor=2.0, increment=0.5, last_increment=0.25)
    assert restart_increment(point, [3.0]) == 0.5
    said = []
    assert restart_increment(SimpleNamespace(**{**vars(point), "increment": 0.0}), [3.0], said.append) == 0.25
    assert said and "steps/step_0003/restart" in said[0]
    none = SimpleNamespace(**{**vars(point), "increment": -1.0, "last_increment": 0.0})
    assert restart_increment(none, [3.0]) == 1.0
    assert restart_increment(none, [1.9, 2.5]) == 0.5          # 1.9: a level the step over passed too


@pytest.mark.parametrize("increment", [0.0, -0.25, float("nan")])
def test_a_restart_with_a_stored_increment_not_above_zero_goes_on(tmp_path, increment):
    whole = run(cantilever([0.5, 1.0]), tmp_path / "whole")
    assert run(cantilever([0.5]), tmp_path / "run").status == "completed"
    with h5py.File(tmp_path / "run" / "results.h5", "a") as h5:
        h5["steps/step_0001/restart"].attrs["increment"] = increment
    said = []
    res = run(cantilever([0.5, 1.0]), tmp_path / "run", restart=str(tmp_path / "run"), log=said.append)
    assert res.status == "completed", res.message
    assert any("gives the next load increment" in s and "going on with 0.5" in s for s in said), said
    u = [np.array(s["steps"][-1]["probes"]["tip"]["displacement"]) for s in (res.summary, whole.summary)]
    assert np.abs(u[0] - u[1]).max() <= 1e-10 * np.abs(u[1]).max()
