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


def test_every_level_has_units_probes_section_forces_and_surface_fields(tmp_path):
    """Issue 39: units on the nodal vectors, the load factor, the reactions and the differences;
    the probes (with their vector's unit) and the surface fields (the VTU's, in double) beside
    summary.json and the VTU; the force each cross-section carries: 45 N along the pulled bar."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["probes"].append({"name": "tip_ry", "beam": "bar", "node": "last", "vector": "r_y"})
    raw["steps"] = [0.5, 1.0]
    s = run_inline(raw, tmp_path)
    with h5py.File(tmp_path / "results.h5") as h5:
        assert h5["model/reference_nodal_vectors"].attrs["units"].startswith("r [m]; r_y [1]")
        g = h5["steps/step_0002"]
        assert g["nodal_vectors"].attrs["units"].startswith("r [m]")
        assert "multiple" in g.attrs["load_factor_units"]
        assert g["reactions"].attrs["units"].startswith("N")
        tip, ry = g["probes/tip"], g["probes/tip_ry"]
        assert tip.attrs["units"] == "m" and ry.attrs["units"] == "1" and ry.attrs["vector"] == "r_y"
        assert np.allclose(tip[0], s["steps"][-1]["probes"]["tip"]["displacement"])
        f = g["section_forces/bar"][()]
        assert f.shape == (2, 4) and np.allclose(f[:, 1], 45.0, rtol=1e-6) and np.allclose(f[:, 2:], 0.0, atol=1e-6)
        assert g["surface/displacement"].attrs["units"] == "m" and g["surface/points"].shape[1] == 3
        assert "fibre_stress" not in g["surface"]
        # every dataset says its units, as docs/running.md states (restart/blocks and
        # increment_blocks did not, nor /model/beams/<beam>/x_nodes)
        bare = []
        g.visititems(lambda name, obj: bare.append(name) if isinstance(obj, h5py.Dataset)
                     and not {"units", "columns"} & set(obj.attrs) else None)
        assert bare == [] and h5["model/beams/bar/x_nodes"].attrs["units"].startswith("m")


def test_section_forces_carry_the_tendon_load_between_the_subtendons(tmp_path):
    """The paper's tendon at 100 N on the soleus: every element's mean section force, summed over
    the three subtendons, is the load to 1 % (measured 0.1 %); the soleus carries nearly all of
    it (frictionless sliding); with the gastrocnemii pulled instead, they carry it."""
    for name, carrier in (("achilles_type3_psi45.yaml", "soleus"), ("achilles_psi45_gastrocnemii.yaml", None)):
        raw = load_raw(name)
        raw["steps"] = [100.0]
        raw["output"] = {"vtk": False}
        run_inline(raw, tmp_path / name)
        with h5py.File(tmp_path / name / "results.h5") as h5:
            g = h5["steps/step_0001/section_forces"]
            means = {b: g[f"{b}_mean"][()] for b in ("soleus", "medial_gastrocnemius", "lateral_gastrocnemius")}
        total = sum(m[:, 1] for m in means.values())
        assert np.allclose(total, 100.0, rtol=0.01), total
        if carrier:
            assert np.all(means[carrier][1:, 1] > 95.0), means[carrier]
        else:
            assert np.all(np.abs(means["soleus"][1:, 1]) < 5.0), means["soleus"]


def test_fibre_fields_are_in_results_h5(tmp_path):
    """Fibre stretch and stress were in the VTU only; now also in results.h5, in Pa."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["material"] = {"model": "goh", "mu": 1.0e6, "bulk_modulus": 50.0e6, "k1": 2.0e6,
                                   "k2": 5.0, "fibres": {"follow": "axis"}}
    raw["steps"] = [1.0]
    run_inline(raw, tmp_path)
    with h5py.File(tmp_path / "results.h5") as h5:
        g = h5["steps/step_0001/surface"]
        assert g["fibre_stress"].attrs["units"] == "Pa" and g["fibre_stress"].dtype == np.float64
        assert np.all(g["fibre_stretch"][()] > 1.0) and np.all(g["fibre_stress"][()] > 0.0)


def test_a_new_run_replaces_only_the_files_a_run_writes(tmp_path):
    """A run in a directory that holds an older run's files replaces those (results.h5,
    summary.json, the VTU series and their .pvd) and nothing else: a user's ``surface_plots/``
    folder and ``contact_notes.txt`` stay.  Before, every name starting with surface or contact
    was removed, and a folder so named stopped the run with 'Is a directory' half-way through
    the clean-up, leaving the old series mixed with the new."""
    import os
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.05, 0.1, 0.15]
    run_inline(raw, tmp_path)
    assert (tmp_path / "surface_0003.vtu").exists()
    (tmp_path / "surface_plots").mkdir()
    (tmp_path / "contact_notes.txt").write_text("mine")
    (tmp_path / "surface_analysis.py").write_text("mine")
    raw["steps"] = [0.1]
    run_inline(raw, tmp_path)
    names = set(os.listdir(tmp_path))
    assert {"surface_plots", "contact_notes.txt", "surface_analysis.py"} <= names
    assert {"surface_0000.vtu", "surface_0001.vtu", "surface.pvd"} <= names
    assert "surface_0002.vtu" not in names and "surface_0003.vtu" not in names
    assert (tmp_path / "contact_notes.txt").read_text() == "mine"


def test_a_subtendons_end_force_includes_a_grips_reaction(tmp_path):
    """``subtendons.<beam>.end_force`` is what acts on the beam's last node from outside: under
    displacement control the grip's reaction (it was the sum of the beam's loads: 0 here, and a
    pressed strip's pressing loads along it), and no other beam's."""
    import os
    from helpers import CONFIGS
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
        b["elements"] = 2
    raw["loads"] = []
    raw["boundary_conditions"].append({"beam": "soleus", "node": "last", "name": "grip",
                                       "displacement": {"r": {"x": 2e-3}}})
    raw["steps"] = [1.0]
    raw["output"] = {"vtk": False}
    st = run_inline(raw, tmp_path)["steps"][-1]
    assert st["reactions"]["grip"][0] > 50.0
    assert st["subtendons"]["soleus"]["end_force"] == st["reactions"]["grip"]
    assert st["subtendons"]["medial_gastrocnemius"]["end_force"] == [0.0, 0.0, 0.0]


def test_a_subtendons_elongation_is_last_minus_first(tmp_path):
    """A bar held at its last node and pulled at its first by 45 N stretches as the uniaxial bar
    pulled the other way (2.4604e-2 m); its elongation and strain were the last node's x-motion
    alone: 0 and 0."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["boundary_conditions"][0]["node"] = "last"
    raw["loads"][0].update(node="first", traction_force=[-45.0, 0.0, 0.0])
    raw["probes"][0]["node"] = "first"
    raw["steps"] = [1.0]
    raw["output"] = {"vtk": False}
    st = run_inline(raw, tmp_path)["steps"][-1]
    bar = st["subtendons"]["bar"]
    assert abs(st["probes"]["tip"]["displacement"][0] + 2.4604212883e-2) < 1e-12
    assert abs(bar["elongation"] - 2.4604212883e-2) < 1e-12
    assert abs(bar["strain"] - 0.24604212883) < 1e-10


def test_a_reader_holding_results_h5_does_not_stop_the_run(tmp_path, monkeypatch):
    """A reader that holds results.h5 open while the run goes on (``ancf-report --existing`` on
    it, a notebook's ``h5py.File``, both with HDF5's file lock) made the run's next level fail:
    'output error: results.h5: cannot write level 53: Resource temporarily unavailable', failed,
    OUTPUT_ERROR, exit 2.  The writer now opens it without HDF5's lock (the directory's own lock
    keeps other runs out), and every level is written."""
    import subprocess
    import sys
    from ancf_petsc.io import results
    held, check = [], results.ResultsWriter._check_space
    hold = ("import h5py, sys, time; f = h5py.File(sys.argv[1], 'r', locking=True); "
            "print('open', flush=True); time.sleep(300)")

    def held_then_check(self, k, q):
        if not held:                            # before level 1 is written: another process reads
            held.append(subprocess.Popen([sys.executable, "-c", hold, self.h5_path], stdout=subprocess.PIPE,
                                         text=True))
            assert held[0].stdout.readline().strip() == "open"
        return check(self, k, q)

    monkeypatch.setattr(results.ResultsWriter, "_check_space", held_then_check)
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.5, 1.0]
    try:
        s = run_inline(raw, tmp_path)
    finally:
        for p in held:
            p.kill()
            p.wait()
    assert held and s["status"] == "completed" and len(s["steps"]) == 2, s.get("message")
    with h5py.File(tmp_path / "results.h5", "r") as f:
        assert f["steps"].attrs["converged"] == 2 and f.attrs["status"] == "completed"
