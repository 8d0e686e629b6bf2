"""A damaged restart state is refused (issue 25): the residual of the stored state at its load
factor must be at the tolerance the level was accepted at, else one line naming the level and
the residual against the tolerance, exit 2, nothing solved.  An intact state restarts."""
from __future__ import annotations

import copy
import json

import h5py
import numpy as np
import pytest

from helpers import load_raw, read_summary, solve_cli, write_config

TIMEOUT = 120


def _cut_to_level_1(tmp_path):
    """The uniaxial bar (two elements, levels 0.5 and 1.0) as if killed after level 1."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["elements"] = 2
    raw["steps"] = [0.5, 1.0]
    raw["output"] = {"vtk": False, "dir": str(tmp_path / "run")}
    cfg = write_config(copy.deepcopy(raw), tmp_path / "c.yaml")
    p = solve_cli(cfg, extra=["--quiet"], timeout=TIMEOUT)
    assert p.returncode == 0, p.stderr
    out = tmp_path / "run"
    with h5py.File(out / "results.h5", "a") as h5:
        del h5["steps/step_0002"]
        h5["steps"].attrs["converged"] = 1
        h5["steps"].attrs["last_load_factor"] = 0.5
    s = read_summary(out)
    s["status"], s["steps"] = "interrupted", s["steps"][:1]
    (out / "summary.json").write_text(json.dumps(s))
    return cfg, out


def _damage(out, how: str) -> None:
    with h5py.File(out / "results.h5", "a") as h5:
        blocks = h5["steps/step_0001/restart/blocks"]
        b = blocks[()]
        if how == "perturbed":
            b[-1, 0] += 1e-4                       # the tip's x moved by 0.1 mm
        else:
            b[:, 3:6] *= -1.0                      # every r_y flipped: J < 0 everywhere
        blocks[...] = b


@pytest.mark.parametrize("how,words", [
    ("perturbed", ("level 1 (load factor 0.5)", "is not an equilibrium", "|F| =", "above the tolerance")),
    ("inverted", ("level 1 (load factor 0.5)", "an element of it is inverted")),
])
def test_a_damaged_restart_state_is_refused(tmp_path, how, words):
    cfg, out = _cut_to_level_1(tmp_path)
    _damage(out, how)
    p = solve_cli(cfg, extra=["--restart", str(out), "--quiet"], timeout=TIMEOUT)
    lines = [ln for ln in p.stderr.splitlines() if ln.startswith("ancf-solve:")]
    assert p.returncode == 2 and len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    for w in words:
        assert w in lines[0], lines[0]
    assert str(out) in lines[0] and "--restart" in lines[0]
    with h5py.File(out / "results.h5", "r") as h5:       # nothing solved, nothing written
        assert sorted(h5["steps"]) == ["step_0001"]


def test_an_intact_restart_state_is_accepted(tmp_path):
    cfg, out = _cut_to_level_1(tmp_path)
    p = solve_cli(cfg, extra=["--restart", str(out), "--quiet"], timeout=TIMEOUT)
    assert p.returncode == 0, p.stderr
    s = read_summary(out)
    assert s["status"] == "completed" and [st["load_factor"] for st in s["steps"]] == [0.5, 1.0]
    assert np.isfinite(s["steps"][-1]["residual_norm"])


def test_a_truncated_results_file_names_the_way_on(tmp_path):
    """results.h5 cut short (a kill while it was written): the refusal named the HDF5 error
    alone ('not a readable results file (Unable to open file (truncated file: ...))'); now it
    says what to do."""
    from ancf_petsc.errors import InputError
    from ancf_petsc.io.restart import read_restart
    _, out = _cut_to_level_1(tmp_path)
    with open(out / "results.h5", "r+b") as fh:
        fh.truncate(4096)
    with pytest.raises(InputError, match=r"not a readable results file \(.*truncated.*\); a run killed "
                                         r"while writing it leaves it so: run afresh with --output-dir"):
        read_restart(str(out))
