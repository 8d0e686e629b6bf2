"""The datasets of results.h5's ``steps/…/contact`` (docs/running.md, "Contact outputs"): each
carries its units, and the fields agree with summary.json's per-interface statistics."""
import h5py
import numpy as np

from helpers import load_raw, run_inline


def test_every_contact_dataset_carries_its_units(tmp_path):
    """docs/running.md: every dataset of a level carries its units; the contact fields had only
    the group's summary line (area, gap, pressure, slip, ... had no ``units``).  The friction
    strips carry every field a law writes (shear, stick, slip increments, its history); the
    pressure, weight included, times the area is the point's normal force (pressing_force)."""
    raw = load_raw("friction_pressed_strips.yaml")
    raw["steps"] = [1.0, 1.05]
    raw["output"] = {"vtk": False}
    s = run_inline(raw, tmp_path)
    with h5py.File(tmp_path / "results.h5") as h5:
        c = h5["steps/step_0002/contact"]
        missing = [k for k in c if not c[k].attrs.get("units")]
        assert not missing, missing
        assert c["gap"].attrs["units"].startswith("m") and c["area"].attrs["units"].startswith("m^2")
        assert c["pressure"].attrs["units"].startswith("Pa") and c["shear_stress"].attrs["units"].startswith("Pa")
        force = float(np.sum(c["area"][()] * np.maximum(c["pressure"][()], 0.0)))
    assert np.isclose(force, s["steps"][-1]["contact"]["interface (base|slider)"]["pressing_force"], rtol=1e-12)


def test_the_contact_series_starts_at_rest(tmp_path):
    """contact.pvd had no rest state: at ParaView time 0 the contact points showed level 1's
    pressure and slip over the undeformed surface (surface_0000.vtu).  Now contact_0000.vtu is
    the reference state at time 0: the points at their reference positions, no pressure, no slip,
    and the gaps of the reference configuration (touching); the run's answers are unchanged."""
    import re
    import meshio
    raw = load_raw("friction_pressed_strips.yaml")
    raw["steps"] = [1.0]
    raw["output"] = {"vtk": True}
    s = run_inline(raw, tmp_path / "vtk")
    listed = re.findall(r'timestep="([^"]+)" part="0" file="([^"]+)"', (tmp_path / "vtk" / "contact.pvd").read_text())
    assert listed == [("0", "contact_0000.vtu"), ("1", "contact_0001.vtu")]
    rest = meshio.read(tmp_path / "vtk" / "contact_0000.vtu")
    with h5py.File(tmp_path / "vtk" / "results.h5") as h5:
        x0, gap = h5["steps/step_0001/contact/x0"][()], h5["steps/step_0001/contact/gap"][()]
    assert np.allclose(rest.points, x0, atol=1e-7) and np.abs(gap).max() > 0.0
    assert np.abs(rest.point_data["gap"]).max() < 1e-12
    assert not rest.point_data["pressure"].any() and not rest.point_data["slip"].any()
    raw["output"] = {"vtk": False}
    plain = run_inline(raw, tmp_path / "plain")
    assert [st["newton_history"] for st in plain["steps"]] == [st["newton_history"] for st in s["steps"]]
