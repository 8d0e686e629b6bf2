"""Issue 25: contact points with slip, gap and pressure exactly 0 drawn as "no slip".

They are points out of contact: their partner place on B lies past the end of the interface curve
(or of B's beam) beyond the fade band of ``contact.projection.end_weight``, so they have weight 0,
and ``contact.reports.point_fields`` writes their fields as 0.  results.h5 now stores each point's
``weight``; the slip figure marks weightless points apart and says why."""
import json
import os

import numpy as np
import pytest

from helpers import CONFIGS, solved_config

pytest.importorskip("matplotlib")

from ancf_petsc import viz  # noqa: E402
from ancf_petsc.contact.fade import CURVE_FADE_END  # noqa: E402
from ancf_petsc.io.reader import read_contact  # noqa: E402


@pytest.fixture(scope="module")
def psi45(tmp_path_factory):
    """configs/achilles_type3_psi45.yaml solved (13 levels, ~6 s)."""
    return solved_config(tmp_path_factory, "achilles_type3_psi45.yaml")


def test_exact_zeros_are_the_weightless_points(psi45):
    """At 400 N the points of weight 0 are exactly those with gap, pressure and slip exactly 0,
    and their partner place is clamped past the end of the curve or beam.  Since the curve's fade
    band runs to 50 % of its length (contact/fade.py, 2026-11-28) the two soleus-interface points
    that slide past 25 % at 400 N keep most of their weight (none is weightless, two are partly
    weighted); before, with the band ending at 30 %, they had none."""
    summary = json.loads((psi45 / "summary.json").read_text())
    last = read_contact(str(psi45 / "results.h5"), len(summary["steps"]))
    assert last["load_factor"] == 400.0
    w = last["weight"]
    zeros = ((last["gap"] == 0.0) & (last["pressure"] == 0.0) & np.all(last["slip"] == 0.0, axis=1))
    assert np.array_equal(zeros, w == 0.0)
    assert ((w > 0.0) & (w < 1.0)).sum() >= 1
    assert np.array_equal(viz.counted_points(last), w > 0.0)
    # each of them: t_B clamped (1 + CURVE_FADE_END) of the curve past its end, or xi_B past the beam end
    from ancf_petsc.config.parse import load_config
    from ancf_petsc.contact.interfaces import find_interfaces
    from ancf_petsc.model.build import build_model
    spec = load_config(os.path.join(CONFIGS, "achilles_type3_psi45.yaml"))
    itfs = find_interfaces(build_model(spec), spec.contact)
    for p in np.flatnonzero(zeros):
        _, xi, t = last["projection"][p]
        T = itfs[int(last["interface"][p])].curve_b.t_end
        assert t <= -CURVE_FADE_END * T * (1 - 1e-9) or t >= (1 + CURVE_FADE_END) * T * (1 - 1e-9) \
            or abs(xi) > 1.0


def test_slip_figure_marks_points_out_of_contact(psi45, tmp_path):
    summary = json.loads((psi45 / "summary.json").read_text())
    levels = [read_contact(str(psi45 / "results.h5"), k) for k in (1, len(summary["steps"]))]
    names = [n.split(" ")[0] for n in summary["contact_interfaces"]]
    out = viz.plot_slip(levels, names, str(tmp_path / "slip.png"), (0, 1), 0.07)
    assert os.path.getsize(out) > 20_000


def test_counted_points_without_a_weight_field():
    """Files written before the weight was stored: all three fields exactly 0 means out of contact."""
    level = {"gap": np.array([0.0, 1e-12, 0.0]), "pressure": np.array([0.0, 0.0, 3.0]),
             "slip": np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])}
    assert viz.counted_points(level).tolist() == [False, True, True]
    level["weight"] = np.array([0.0, 0.5, 1.0])
    assert viz.counted_points(level).tolist() == [False, True, True]
