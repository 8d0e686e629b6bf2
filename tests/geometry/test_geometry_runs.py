"""Runs from measured sections: a three-subtendon tendon from independently traced, noisy outlines
with sliding contact on 1, 2 and 3 ranks, and the worked example of docs/geometry.md."""
import pytest
import os
import subprocess
import sys

import numpy as np

import geometry_cases as gc
from helpers import (CONFIGS, ROOT, assert_same_as_serial, load_raw, probe, probes_table, read_summary, run_on_ranks,
                     solve_cli, write_config)


def traced_tendon(tmp_path) -> str:
    """CSV tracings (mm, one file per subtendon, each with its own start, spacing and noise) and
    a geometry file that names them; returns the config path."""
    rng = np.random.default_rng(7)
    for name, P in gc.strip_tendon().items():
        Q = gc.trace(P, rng)
        (tmp_path / f"{name}.csv").write_text("y [mm],z [mm]\n" + "\n".join(f"{y:.6f},{z:.6f}" for y, z in Q))
    (tmp_path / "geometry.yaml").write_text(
        "units: mm\naxes: [y, z]\noutlines:\n" + "".join(f"  {n}: {{file: {n}.csv}}\n" for n in ("left", "middle", "right")))
    names = ("left", "middle", "right")
    raw = {"name": "traced", "geometry": {"length": 0.04, "twist_deg": 20.0,
                                          "sections": {"file": "geometry.yaml"}},
           "beams": [{"name": n, "section": {"shape": "outline", "loop": n}, "elements": 2,
                      "material": {"model": "neo-hookean", "mu": 100e6, "bulk_modulus": 1e9}} for n in names],
           "boundary_conditions": [{"beam": n, "node": "first", "fix": "reduced"} for n in names],
           "loads": [{"beam": "middle", "node": "last", "force": [1.0, 0.0, 0.0]}],
           "steps": [5.0, 10.0], "probes": [{"name": n, "beam": n, "node": "last"} for n in names],
           "contact": {"mode": "sliding"}, "solver": {"initial_increment": 2.5}}
    return write_config(raw, tmp_path / "traced.yaml")


@pytest.mark.mpi
@pytest.mark.slow
def test_traced_noisy_tendon_with_contact_same_on_1_2_3_ranks(tmp_path):
    cfg = traced_tendon(tmp_path)
    tables = {}
    for n in (1, 2, 3):
        out = tmp_path / f"n{n}"
        p = solve_cli(cfg, ranks=n, extra=["--output-dir", str(out)], cwd=str(tmp_path))
        assert p.returncode == 0, p.stdout + p.stderr
        s = read_summary(out)
        assert s["status"] == "completed" and s["ranks"] == n
        tables[n] = probes_table(s)
        if n == 1:
            log, serial = p.stdout, s
    # two merged interfaces (left and right do not touch), contact on both, twist about the centroid
    assert "interface left/middle" in log and "interface middle/right" in log
    # named in config order (left, middle, right), the later beam carrying the points (issue 39)
    assert "left/middle (left|middle): " in log and "middle/right (middle|right): " in log
    assert "points on middle, projected onto left" in log and "points on right, projected onto middle" in log
    assert "twist axis: area centroid of all sections at x = 0" in log and "default rule" in log
    assert np.abs(probe(serial, "left")).max() > 1e-6        # the neighbours are dragged along
    assert_same_as_serial(tables)


def test_worked_example_from_the_mask_script(tmp_path):
    """scripts/make_geometry_demo.py reproduces the committed mask and volume; the mask config
    runs with sliding contact on the merged interfaces, the two-station config without."""
    from PIL import Image
    import nibabel as nib
    p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "make_geometry_demo.py"),
                        "--out", str(tmp_path), "--no-figure"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    data = os.path.join(CONFIGS, "data")
    assert np.array_equal(np.array(Image.open(tmp_path / "demo_tendon_labels.png")),
                          np.array(Image.open(os.path.join(data, "demo_tendon_labels.png"))))
    assert np.array_equal(np.asanyarray(nib.load(tmp_path / "demo_tendon_labels.nii.gz").dataobj),
                          np.asanyarray(nib.load(os.path.join(data, "demo_tendon_labels.nii.gz")).dataobj))
    p = solve_cli(os.path.join(CONFIGS, "geometry_mask_demo.yaml"), extra=["--output-dir", str(tmp_path / "mask")])
    assert p.returncode == 0, p.stdout + p.stderr
    s = read_summary(tmp_path / "mask")
    assert s["status"] == "completed" and len(s["steps"]) == 2
    assert any(ln.startswith("twist axis: area centroid") for ln in s["geometry"])   # also on disk
    assert len(s["twist_axis"]) == 2
    assert p.stdout.count("interface ") >= 6                # 3 merged, 3 with contact points
    assert "dropped 1 separate region" in p.stdout           # the stray pixel
    areas = [float(ln.split("->")[1].split("mm^2")[0]) for ln in p.stdout.splitlines()
             if "area" in ln and "->" in ln]
    assert len(areas) == 3 and 22.0 < sum(areas) < 24.0     # 9223 pixels of 0.0025 mm^2 = 23.06 mm^2


@pytest.mark.mpi
@pytest.mark.slow
def test_sections_varying_along_x_same_on_1_2_3_ranks(tmp_path):
    """Per-element section rules (two NIfTI slices, 3 elements per beam) on 1, 2 and 3 ranks."""
    raw = load_raw("geometry_stations_demo.yaml")
    raw["steps"] = [1.0]
    for st in raw["geometry"]["sections"]["stations"]:       # the config is written elsewhere
        st["source"] = os.path.join(CONFIGS, st["source"])
    runs = run_on_ranks(raw, tmp_path)
    assert "outlines registered (shift and rotation) and blended, section rotation +24.85 deg" in runs[1][0].stdout   # docs/geometry.md
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
