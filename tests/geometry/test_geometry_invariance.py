"""The same section given another way (start point, image turned, mirrored) gives the same model
(docs/geometry.md): the traced outline's start point must not matter."""
import os

import numpy as np
import pytest

import geometry_cases as gc
from ancf_petsc.config.sections import parse_sections
from ancf_petsc.config.values import ConfigError
from ancf_petsc.geometry_input.build import build_station
from ancf_petsc.physics.section import make_outline
from helpers import CONFIGS

H = 0.05e-3                                         # pixel size of the demo mask [m]
NAMES = {"soleus": 1, "medial_gastrocnemius": 2, "lateral_gastrocnemius": 3}


def station(desc: dict, base_dir="."):
    spec = parse_sections(desc, "geometry.sections", str(base_dir), 0.05)
    return build_station(spec.stations[0][1], spec)


def properties(st, shift=(0.0, 0.0)) -> dict:
    """Per loop: area [m^2], then centroid (moved back by ``shift``) over sqrt(area) and Syy, Szz,
    Syz over area^2 (dimensionless)."""
    out = {}
    for n, loop in st.loops.items():
        s = make_outline(loop, 6)
        c = (s.centroid - np.asarray(shift)) / np.sqrt(s.area)
        out[n] = np.r_[s.area, c, np.array([s.Syy, s.Szz, s.Syz]) / s.area ** 2]
    return out


def assert_same(p, q, rel):
    for n in p:
        assert q[n][0] == pytest.approx(p[n][0], rel=rel), n
        assert np.allclose(q[n][1:], p[n][1:], rtol=0, atol=rel), (n, q[n] - p[n])


def test_a_free_outline_started_elsewhere_is_the_same_section():
    """A noisy traced ellipse (a subtendon touching no other) given from another point of its
    trace: its area differed by up to 4.4e-4 (one point later) and its moments likewise, the fit
    starting where the list did."""
    rng = np.random.default_rng(2)
    th = np.linspace(0, 2 * np.pi, 4000, endpoint=False)
    P = gc.trace(np.column_stack([4 * np.cos(th), 2.5 * np.sin(th)]), rng)
    ref = None
    for k in (0, 1, 17, 50, len(P) - 3):
        Q = np.roll(P, k, axis=0)
        st = station({"units": "mm", "axes": ["y", "z"], "outlines": {"a": {"points": Q.tolist()}}})
        p = properties(st)
        ref = ref or p
        assert_same(ref, p, 1e-12)


def _demo_mask():
    from PIL import Image
    return np.array(Image.open(os.path.join(CONFIGS, "data", "demo_tendon_labels.png"))).astype(np.uint8)


def _mask_station(tmp_path, img, axes, tag):
    from PIL import Image
    Image.fromarray(img).save(tmp_path / f"{tag}.png")
    return station({"units": "px", "pixel_size": "0.05 mm", "axes": axes, "source": f"{tag}.png",
                    "outlines": {n: {"label": v} for n, v in NAMES.items()}}, tmp_path)


def test_a_mask_saved_turned_or_flipped_with_its_axes_is_the_same_section(tmp_path):
    """The demo mask saved turned by 90 deg, flipped left-right or transposed, with the axes that
    say so (the very same pixels in the tendon frame): the soleus area differed by 1.0e-3 and its
    Szz by 3.3e-3 (the traced contour starts where the image scan meets the region first, and the
    smoothing resampled from there); the twist axis (the centroid) moved with them."""
    lab = _demo_mask()
    w = lab.shape[1]
    ref = properties(_mask_station(tmp_path, lab, "image", "base"))
    for img, axes, shift in ((np.rot90(lab), ["-z", "-y"], (-(w - 1) * H, 0.0)),
                             (np.fliplr(lab), ["-y", "-z"], (-(w - 1) * H, 0.0)),
                             (lab.T.copy(), ["-z", "y"], (0.0, 0.0))):
        p = properties(_mask_station(tmp_path, np.ascontiguousarray(img), axes, "turned"), shift)
        assert_same(ref, p, 1e-9)


def test_the_demo_mask_as_png_and_as_nifti_slice_is_one_section(tmp_path):
    """configs/data/demo_tendon_labels.nii.gz slice 0 holds the PNG's labels (voxel axis 0 =
    columns): the two gave soleus areas 7.861 and 7.872 mm^2 (1.4e-3 apart), the scan meeting each
    region at another pixel."""
    data = os.path.join(CONFIGS, "data")
    png = station({"units": "px", "pixel_size": "0.05 mm", "axes": "image", "source": "demo_tendon_labels.png",
                   "outlines": {n: {"label": v} for n, v in NAMES.items()}}, data)
    nii = station({"units": "px", "pixel_size": "header", "axes": "image", "source": "demo_tendon_labels.nii.gz",
                   "slice": {"axis": 2, "index": 0}, "outlines": {n: {"label": v} for n, v in NAMES.items()}}, data)
    assert_same(properties(png), properties(nii), 1e-9)


def _mirrored(p: dict, shift_y: float) -> dict:
    """Properties of the mirror image y -> shift_y - y: centroid y and Syz change sign."""
    return {n: v * [1, -1, 1, 1, 1, -1] + [0, shift_y / np.sqrt(v[0]), 0, 0, 0, 0] for n, v in p.items()}


def test_the_left_leg_gives_the_mirrored_section(tmp_path):
    """The demo mask flipped left-right, read with the same axes (the other leg), and three traced
    subtendons with y negated: their areas, centroids and moments differed from the mirror image's
    by up to 2.1e-4 and 1.1e-4 (relative), each outline running the other way along the same points
    and the fit taking the trace point after each spacing target (now the nearest)."""
    lab = _demo_mask()
    w = lab.shape[1]
    right = properties(_mask_station(tmp_path, lab, "image", "right"))
    left = properties(_mask_station(tmp_path, np.ascontiguousarray(np.fliplr(lab)), "image", "left"))
    assert_same(_mirrored(right, (w - 1) * H), left, 1e-9)
    rng = np.random.default_rng(1)
    traced = {n: gc.trace(P, rng) for n, P in gc.strip_tendon(800).items()}
    sides = [properties(station({"units": "mm", "axes": ["y", "z"], "outlines": {
        n: {"points": (P * [sign, 1]).tolist()} for n, P in traced.items()}})) for sign in (1, -1)]
    assert_same(_mirrored(sides[0], 0.0), sides[1], 1e-9)


def test_outlines_listed_in_another_order_give_the_same_sections():
    """The demo mask's outlines listed lateral, medial, soleus: the areas, centroids and moments
    differed by up to 3.1e-3 (relative) from soleus first, the interface being the midline of the
    first-listed side's points only."""
    data = os.path.join(CONFIGS, "data")
    got = [properties(station({"units": "px", "pixel_size": "0.05 mm", "axes": "image",
                               "source": "demo_tendon_labels.png",
                               "outlines": {n: {"label": NAMES[n]} for n in order}}, data))
           for order in (list(NAMES), list(NAMES)[::-1])]
    assert_same(got[0], got[1], 1e-9)


@pytest.mark.parametrize("tol", [None, 2e-4])
def test_two_halves_traced_along_one_border_keep_it(tol):
    """The halves of an ellipse 6 x 4 mm, each traced with the same border y = 0: the merged
    border ended 23 um (default tolerance 50 um) or 80 um (0.2 mm) inside the first-listed half,
    whose area came out 7.7e-4 (9.2e-3) below the other's. The border now ends on y = 0 and the
    areas agree to the fit (measured 1.7e-6 and 7.9e-5)."""
    arc = np.linspace(np.pi / 2, 3 * np.pi / 2, 60)
    border = np.column_stack([np.zeros(19), np.linspace(-1.8, 1.8, 19)])
    left = np.vstack([np.column_stack([3 * np.cos(arc), 2 * np.sin(arc)]), border])
    opts = {} if tol is None else {"merge_tolerance": tol}
    st = station({"units": "mm", "axes": ["y", "z"], "outlines": {
        "l": {"points": left.tolist()}, "r": {"points": (left * [-1, 1]).tolist()}}, **opts})
    assert np.abs(st.junctions[:, 0]).max() < 1e-12
    p = properties(st)
    assert p["l"][0] == pytest.approx(p["r"][0], rel=2e-4)
    assert p["l"][0] == pytest.approx(np.pi * 3e-3 * 2e-3 / 2, rel=1e-3)


def test_interfaces_are_fitted_alike_whichever_neighbour_is_listed_first():
    """Three traced subtendons at 0.9 of their size, listed right, middle, left: their sections
    differed by 5.1e-4 (relative) from left first, each interface's control points being capped at
    1/12 of the perimeter of its first-listed side (now of the shorter side)."""
    rng = np.random.default_rng(3)
    traced = {n: 0.9 * gc.trace(P, rng) for n, P in gc.strip_tendon(800).items()}
    got = [properties(station({"units": "mm", "axes": ["y", "z"],
                               "outlines": {n: {"points": traced[n].tolist()} for n in order}}))
           for order in (["left", "middle", "right"], ["right", "middle", "left"])]
    assert_same(got[0], got[1], 1e-9)


def test_the_left_leg_measured_at_two_stations_gives_the_mirrored_field():
    """Three traced subtendons at x = 0 and, 0.8 x smaller, turned by 20 deg and shifted, at
    x = L; the same with y negated at both stations (the other leg): the stated section rotations
    were +19.97 and -19.95 deg and the sections between the stations differed from the mirror
    image's by 2.4e-4 (relative), the stations' rings and the blended outline's fit starting
    where each loop's first curve did. Both legs now turn by 19.99 deg."""
    from ancf_petsc.geometry_input.tendon import build_tendon
    rng = np.random.default_rng(3)
    near = {n: gc.trace(P, rng) for n, P in gc.strip_tendon(800).items()}
    t = np.deg2rad(20.0)
    far = {n: 0.8 * P @ np.array([[np.cos(t), np.sin(t)], [-np.sin(t), np.cos(t)]]) + [0.5, 0.2]
           for n, P in near.items()}
    legs = []
    for sign in (1, -1):
        st = [{"x": x, "units": "mm", "axes": ["y", "z"],
               "outlines": {n: {"points": (P * [sign, 1]).tolist()} for n, P in t_.items()}}
              for x, t_ in ((0.0, near), (0.05, far))]
        legs.append(build_tendon(parse_sections({"stations": st}, "geometry.sections", ".", 0.05)))
    assert legs[0].field.theta[0] == pytest.approx(-legs[1].field.theta[0], abs=1e-12)
    assert np.rad2deg(legs[0].field.theta[0]) == pytest.approx(20.0, abs=0.05)
    for x in (0.0125, 0.025):
        right, left = ({n: make_outline(T.loop(n, x), 6) for n in T.names} for T in legs)
        for n in right:
            for q in ("area", "Syy", "Szz"):
                assert getattr(left[n], q) == pytest.approx(getattr(right[n], q), rel=1e-9), (n, q, x)
            assert left[n].Syz == pytest.approx(-right[n].Syz, rel=1e-9)
            assert np.allclose(left[n].centroid * [-1, 1], right[n].centroid, rtol=0, atol=1e-9 * 3e-3)


def _two_stations(order1, axes1):
    from ancf_petsc.geometry_input.tendon import build_tendon
    rng = np.random.default_rng(3)
    traced = {n: gc.trace(P, rng) for n, P in gc.strip_tendon(800).items()}
    st = [{"x": x, "units": "mm", "axes": axes, "outlines": {n: {"points": traced[n].tolist()} for n in order}}
          for x, order, axes in ((0.0, ["left", "middle", "right"], ["y", "z"]), (0.05, order1, axes1))]
    return build_tendon(parse_sections({"stations": st}, "geometry.sections", ".", 0.05))


@pytest.mark.parametrize("order1", [["right", "left", "middle"], ["middle", "right", "left"]])
def test_a_station_listing_its_outlines_in_another_order(order1):
    """Station 1 the same tracings listed in another order: it was taken for another section (its
    interfaces, fitted the other way round, did not match station 0's: outlines registered and
    blended, rotation +0.01 deg, and contact refused); with axes [-y, z] (the mirror image) it was
    accepted and blended with a section rotation of -176 deg, the mirror check starting each
    station's round of outlines at its own first-listed one."""
    same = _two_stations(order1, ["y", "z"])
    assert same.field.structured, same.report()
    with pytest.raises(ConfigError, match=r"stations\[1\]: this station is the mirror image of station 0"):
        _two_stations(order1, ["-y", "z"])
