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
