"""The layout of results.h5 (docs/running.md, "results.h5 layout")."""
import h5py
import numpy as np

from helpers import load_raw, run_inline


def test_section_outlines_say_their_frame(tmp_path):
    """Section points and outlines are stored relative to the section centroid, and say so."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.1]
    raw["beams"][0]["section"]["center"] = [0.01, -0.02]      # off the tendon axis
    run_inline(raw, tmp_path)
    with h5py.File(tmp_path / "results.h5") as h5:
        beam = h5["model/beams/bar"]
        for name in ("section_outline", "section_points"):
            assert beam[name].attrs["frame"].startswith("section centroid, m"), name
        assert beam["section_weights"].attrs["units"] == "m^2"
        # relative to the centroid: the ellipse's outline is centred on 0, its centroid is not
        outline = beam["section_outline"][()]
        assert np.allclose(outline.mean(axis=0), 0.0, atol=1e-12)
        assert np.allclose(beam.attrs["centroid"], [0.01, -0.02])
