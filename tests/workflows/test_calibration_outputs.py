"""The files of an ancf-fit output directory are the last fit's: a figure this fit does not draw
is not left there from an earlier one (docs/calibration.md lists profiles.png among them)."""
from __future__ import annotations

import os
import subprocess

from calibration_cases import MU, bar_case
from helpers import MPI_ENV, ROOT, VENV_BIN


def _fit(path: str) -> None:
    p = subprocess.run([os.path.join(VENV_BIN, "ancf-fit"), path, "--fresh"], capture_output=True, text=True,
                       env=dict(os.environ, **MPI_ENV), cwd=ROOT, timeout=300)
    assert p.returncode == 0, p.stderr


def test_a_fit_without_profiles_leaves_no_earlier_profiles_png(tmp_path):
    """The bar's mu fitted with profiles, then (the data or the fit file edited) again without:
    the first fit's profiles.png stayed beside the second's report.md and fit.png, a figure of
    another fit read as this one's.  Now it is removed."""
    d = str(tmp_path)
    _fit(bar_case(d, parameters=(MU,), lateral=False, identifiability={"profiles": True, "points": 3}))
    assert os.path.exists(tmp_path / "out" / "profiles.png")
    _fit(bar_case(d, parameters=(MU,), lateral=False, identifiability={"profiles": False}))
    assert sorted(f for f in os.listdir(tmp_path / "out") if not f.startswith(".")) == [
        "fit.json", "fit.png", "report.md", "samples.jsonl"]
