"""The default merge tolerance of measured outlines follows the size of the sections: the demo
tendon mask read at fascicle size (its pixels 20 and 5 times finer) gives the same outlines
scaled, instead of being merged across a fixed 50 µm."""
import pytest
import yaml

from ancf_petsc.config.sections import parse_sections
from ancf_petsc.geometry_input.build import build_station
from helpers import CONFIGS


def demo_station(pixel_mm: float):
    """configs/data/demo_tendon_geometry.yaml (0.05 mm pixels) with pixels of ``pixel_mm``."""
    desc = yaml.safe_load(open(f"{CONFIGS}/data/demo_tendon_geometry.yaml"))
    desc["pixel_size"] = f"{pixel_mm} mm"
    spec = parse_sections(desc, "geometry.sections", f"{CONFIGS}/data", 0.05)
    return build_station(spec.stations[0][1], spec)


def test_a_fascicle_sized_mask_is_merged_on_its_own_scale():
    """Before: at 2.5 µm pixels (0.05 mm² in all) 'outlines.soleus: smoothing (0.005 mm), merging
    and fitting change its area by -19.4 %', refused; at 10 µm the merge across 50 µm changed the
    areas by -0.43 / +0.41 / +0.88 % where 2.5 µm, scaled, gives -0.26 / +0.32 / +0.69 %.  Now the
    default is at most a tenth of the narrowest outline's width: both sizes give the same
    outlines scaled (areas to 1e-6), the areas within 1 % of the traced ones."""
    small, larger = demo_station(0.0025), demo_station(0.01)
    assert larger.merge_tolerance == pytest.approx(4 * small.merge_tolerance, rel=1e-9)
    for name, area in small.area.items():
        assert larger.area[name] == pytest.approx(16 * area, rel=1e-6)
        assert area == pytest.approx(small.raw_area[name], rel=0.01)


def test_tendon_sized_masks_keep_50_um_or_1_5_pixels():
    """The demo at its own 0.05 mm pixels merges across 1.5 pixels (75 µm), as before."""
    assert demo_station(0.05).merge_tolerance == pytest.approx(75e-6, rel=1e-9)
