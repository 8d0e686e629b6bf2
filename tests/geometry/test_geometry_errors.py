"""Bad geometry gets one clear line through ancf-solve: exit code 2, the key path, no traceback."""
import numpy as np
import pytest

from helpers import solve_cli, write_config


def disc(r=4.0, n=40, c=(0.0, 0.0)):
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return (np.array(c) + r * np.column_stack([np.cos(t), np.sin(t)])).tolist()


def config(sections, beams=("a",), contact=False):
    raw = {"name": "bad", "geometry": {"length": 0.02, "sections": sections},
           "beams": [{"name": b, "section": {"shape": "outline", "loop": b}, "elements": 1,
                      "material": {"model": "neo-hookean", "mu": 1e6, "bulk_modulus": 1e7}} for b in beams],
           "steps": [1.0]}
    if contact:
        raw["contact"] = {"mode": "sliding"}
    return raw


def inline(outlines, units="mm", axes=("y", "z"), **kw):
    return {"units": units, "axes": axes if isinstance(axes, str) else list(axes), "outlines": outlines, **kw}


def three(mirror=False, r=3.0):
    """Three sectors of a disc of radius r (points, mm, closed); mirrored in z if asked."""
    out = {}
    for k, name in enumerate(("p", "q", "r")):
        th = np.deg2rad(np.linspace(120 * k, 120 * (k + 1), 30))
        P = np.vstack([[0.0, 0.0], r * np.column_stack([np.cos(th), np.sin(th)]), [0.0, 0.0]])
        if mirror:
            P = P * [1.0, -1.0]
        out[name] = {"points": P.tolist()}
    return out


def halves(gap=0.0):
    """The two halves of an ellipse 6 x 4 mm, each traced with its own copy of the border y = 0
    (each moved away from it by half ``gap`` [mm])."""
    arc = np.linspace(np.pi / 2, 3 * np.pi / 2, 60)
    border = np.column_stack([np.zeros(19), np.linspace(-1.8, 1.8, 19)])
    left = np.vstack([np.column_stack([3 * np.cos(arc), 2 * np.sin(arc)]), border]) - [gap / 2, 0.0]
    right = np.vstack([np.column_stack([-3 * np.cos(arc), -2 * np.sin(arc)]), border[::-1]]) + [gap / 2, 0.0]
    return {"l": {"points": left.tolist()}, "r": {"points": right.tolist()}}


def test_points_written_twice_a_hair_apart_are_one_outline(tmp_path):
    """Each point of a closed point list repeated with 1e-6 mm added: the median spacing was 0
    and the outline was refused as open ('points are 0.000 mm apart')."""
    t = np.linspace(0.0, 2 * np.pi, 60, endpoint=False)
    P = np.column_stack([3.0 * np.cos(t), 1.5 * np.sin(t)])
    twice = np.repeat(P, 2, axis=0)
    twice[1::2] += 1e-6
    raw = config(inline({"a": {"points": twice.tolist()}}))
    raw["beams"][0]["material"] = {"model": "neo-hookean", "mu": 1e6, "bulk_modulus": 1e7}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["--check", "--output", str(tmp_path / "g.png")])
    assert p.returncode == 0 and "open" not in p.stderr, p.stderr


def write_files(tmp):
    from PIL import Image
    lab = np.zeros((60, 60), dtype=np.uint8)
    lab[10:30, 10:30], lab[30:50, 10:30] = 1, 2
    Image.fromarray(lab, mode="L").save(tmp / "m.png")
    small = np.zeros((40, 40), dtype=np.uint8)
    small[18:21, 18:21] = 1                              # 3 x 3 pixels: 2-pixel smoothing took 42 %
    Image.fromarray(small, mode="L").save(tmp / "small.png")
    t = np.linspace(0.0, 2 * np.pi, 40, endpoint=False)
    (tmp / "idx.csv").write_text("i,u,v\n" + "".join(f"{k},{4 * np.cos(a):.5f},{3 * np.sin(a):.5f}\n"
                                                       for k, a in enumerate(t)))
    (tmp / "dec.csv").write_text("u;v\n" + "".join(f"{4 * np.cos(a):.5f};{3 * np.sin(a):.5f}\n".replace(".", ",")
                                                    for a in t))
    (tmp / "open.svg").write_text('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 20 20">'
                                  '<path id="a" d="M 1,1 L 10,1 L 10,10"/>'
                                  '<path id="b" d="M 12,12 C 14,12 16,14 16,16"/></svg>')


CASES = [
    ("self-intersecting", config(inline({"a": {"points": [[0, 0], [2, 2], [2, 0], [0, 2]]}})),
     "geometry.sections.outlines.a", "crosses itself near (1.000, 1.000) mm"),
    # two squares traced as one loop touching at (3, 3): the message said near (3.000, 6.000) mm
    ("pinched at a point", config(inline({"a": {"points": [[0, 0], [3, 0], [3, 3], [6, 3], [6, 6], [3, 6], [3, 3],
                                                           [0, 3]]}})),
     "geometry.sections.outlines.a", "crosses itself near (3.000, 3.000) mm"),
    # points on one line: 'too small for a tendon: check units: mm (in m the outlines would enclose 0 mm^2)'
    ("outline on a line", config(inline({"a": {"points": [[0, 0], [1, 0], [2, 0]]}})),
     "geometry.sections.outlines.a", "the outline encloses no area: its 3 points lie on one line"),
    ("open outline", config(inline({"a": {"points": disc()[:25]}})),
     "geometry.sections.outlines.a", "the outline is open"),
    # traced 1.1 times round: 'the outline is open ... trace it all the way round (repeat the first point)'
    ("traced past its start", config(inline({"a": {"points": [[4 * float(np.cos(t)), 4 * float(np.sin(t))]
                                                              for t in np.linspace(0.0, 2.2 * np.pi, 111)]}})),
     "geometry.sections.outlines.a", "the outline runs past its start: it crosses itself near"),
    ("wrong orientation of a curve", config(inline(
        {"a": {"curves": ["base", "right", "left"]}},
        curves={"base": [[0, 0], [2, 0]], "right": [[1, 2], [1.8, 1], [2, 0]], "left": [[1, 2], [0, 0]]})),
     "geometry.sections.outlines.a.curves", "curve 'right' runs the wrong way round in this loop "
                                           "(wrong orientation); write '-right'"),
    ("mirrored station", config({"stations": [dict(inline(three()), x=0.0),
                                               dict(inline(three(mirror=True)), x=0.02)]}, beams=("p", "q", "r")),
     "geometry.sections.stations[1]", "mirror image of station 0"),
    ("tendon of 50 m^2", config(inline({"a": {"points": disc()}}, units="m")),
     "geometry.sections.units", "too large for a tendon"),
    ("tendon of 50 um^2", config(inline({"a": {"points": disc()}}, units="um")),
     "geometry.sections.units", "in mm the outlines would enclose 50.1 mm^2"),
    ("mask without the label", config(inline({"a": {"label": 7}}, units="px", pixel_size="0.05 mm",
                                             axes="image", source="m.png")),
     "geometry.sections.outlines.a", "m.png: no pixel has label 7 (labels present: 0, 1, 2)"),
    # a mask read with units: mm took each pixel for 1 mm; a slice beside a PNG was unread
    ("mask in millimetres", config(inline({"a": {"label": 1}}, units="mm", axes="image", source="m.png")),
     "geometry.sections.units", "a label mask image is in pixels: give units: px and its pixel_size (e.g. 0.05 mm); "
                                "got mm"),
    ("slice of an image", config(inline({"a": {"label": 1}}, units="px", pixel_size="0.05 mm", axes="image",
                                        source="m.png", slice={"axis": 2, "index": 0})),
     "geometry.sections.slice", "only a NIfTI label volume is sliced, none of these outlines comes from one: "
                                "remove it; got {axis: 2, index: 0}"),
    ("a region smoothing erases", config(inline({"a": {"label": 1}}, units="px", pixel_size="0.05 mm",
                                                axes="image", source="small.png")),
     "geometry.sections.outlines.a", "change its area by -41.9 % (0.02125 -> 0.01235 mm^2): it is small "
                                     "against them; give geometry.sections.smoothing a smaller value"),
    # an index column was read as u ('the outline is open ... 39 mm apart'), columns past two were dropped
    ("three columns", config(inline({"a": {"file": "idx.csv"}})),
     "geometry.sections.outlines.a", "idx.csv line 2: 3 columns ['0', '4.00000', '0.00000']; a point list has two "
                                     "columns u, v: remove the others"),
    ("decimal commas", config(inline({"a": {"file": "dec.csv"}})),
     "geometry.sections.outlines.a", "(decimal commas are not read: write 1.5, not 1,5)"),
    ("SVG without closed paths", config(inline({"a": {"file": "open.svg"}}, axes="image")),
     "geometry.sections.outlines.a", "open.svg: none of its 2 path(s) is closed"),
    ("overlap", config(inline({"a": {"points": disc(2.0)}, "b": {"points": disc(2.0, c=(3.5, 0.0))}}),
                       beams=("a", "b")),
     "geometry.sections.outlines", "subtendons 'a' and 'b' overlap by 0.498 mm near (2.000, 0.000) mm"),
    ("outlines on each other", config(inline({"a": {"points": disc(1.0, c=(2.0, 0.0))},
                                              "b": {"points": disc(1.0, c=(2.0, 0.0))}}), beams=("a", "b")),
     "geometry.sections.outlines", "subtendons 'a' and 'b' overlap: the inside of 'a' near "),
    # millimetres written as metres: smoothing 0.05 collapsed the outline (a NaN traceback), merge_tolerance
    # 0.05 said 'no neighbour within the merge tolerance' of two touching halves; 0.74 mm blamed smoothing (0)
    ("smoothing in mm", config(inline({"a": {"points": disc()}}, smoothing=0.05)),
     "geometry.sections.smoothing", "0.05 m is 6.27 x the width of the narrowest outline, a (7.975 mm), which it "
                                    "would erase: it is in metres (50 um = 5e-05); give at most 0.002 m; got 0.05"),
    ("merge tolerance in mm", config(inline(halves(), merge_tolerance=0.05), beams=("l", "r")),
     "geometry.sections.merge_tolerance", "0.05 m is 16.7 x the width of the narrowest outline"),
    # a gap of 0.6 mm closed, half from each side: +12 % (without it, the merge and a coarse fit
    # of the touching halves gave -6.1 %, -4.4 % once the fit took the nearest trace points)
    ("merge tolerance that moves a border", config(inline(halves(0.6), merge_tolerance=0.00074), beams=("l", "r")),
     "geometry.sections.outlines.l", "give geometry.sections.merge_tolerance (0.74 mm) a smaller value"),
    # two beams on one outline filled one region; a center moved an outline into its neighbour by 1 mm
    ("one outline for two beams", dict(config(inline(three()), beams=("p", "q")), beams=[
        {"name": b, "section": {"shape": "outline", "loop": "p"}, "elements": 1,
         "material": {"model": "neo-hookean", "mu": 1e6, "bulk_modulus": 1e7}} for b in ("p", "q")]),
     "beams[1].section.loop", "outline 'p' is already the section of beams[0] (p): two beams would fill one region"),
    ("an outline moved by center", dict(config(inline(three()), beams=("p", "q", "r")), beams=[
        {"name": b, "section": {"shape": "outline", "loop": b, **({"center": [0.001, 0.0]} if b == "q" else {})},
         "elements": 1, "material": {"model": "neo-hookean", "mu": 1e6, "bulk_modulus": 1e7}} for b in ("p", "q", "r")]),
     "beams[1].section.center", "an outline of geometry.sections sits where its file places it"),
    ("a shared inline curve moved by center", dict(config(None, beams=()), geometry={"length": 0.02}, beams=[
        {"name": b, "elements": 1, "material": {"model": "neo-hookean", "mu": 1e6, "bulk_modulus": 1e7},
         "section": {"shape": "outline", "curves": [{"name": "mid", "points": [[0, -2e-3], [0, 2e-3]][::sgn]},
                                                    {"name": b, "points": [[0, 2e-3], [3e-3 * sgn, 0], [0, -2e-3]][::sgn]}],
                     **({"center": [0.0005, 0.0]} if b == "r" else {})}} for b, sgn in (("l", 1), ("r", -1))]),
     "beams[1].section.center", "its curve 'mid' is also the section curve of beams[0] (l), one curve, their interface"),
    # a curve shared by two outlines on the same side of it: overlapping beams ran to 'completed', the
    # curve a contact interface (the whole 20.7 mm of an ellipse's outline for two beams on one closed curve)
    ("two inline outlines on one side of their curve", dict(config(None, beams=()), geometry={"length": 0.02}, beams=[
        {"name": b, "elements": 1, "material": {"model": "neo-hookean", "mu": 1e6, "bulk_modulus": 1e7},
         "section": {"shape": "outline", "curves": [{"name": "mid", "points": [[-2e-3, 0], [2e-3, 0]]},
                                                    {"points": [[2e-3, 0], [0, -d], [-2e-3, 0]]}]}}
        for b, d in (("disc", 2e-3), ("lens", 1e-3))]),
     "beams[1].section.curves", "its curve 'mid' is also a border of beams[0] (disc), and both sections lie on the "
                                "same side of it: they overlap"),
    ("two inline outlines on one closed curve", dict(config(None, beams=()), geometry={"length": 0.02}, beams=[
        {"name": b, "elements": 1, "material": {"model": "neo-hookean", "mu": 1e6, "bulk_modulus": 1e7},
         "section": {"shape": "outline", "curves": [{"name": "c", "points": (1e-3 * np.array(
             disc(n=8) + disc(n=8)[:1]))[::sgn].tolist()}]}} for b, sgn in (("a", 1), ("b", -1))]),
     "beams[1].section.curves", "a curve closing on itself is a whole outline: give beams[1] its own"),
    ("two outlines of geometry.sections on one closed curve", config(
        inline({"a": {"curves": ["c"]}, "b": {"curves": ["-c"]}}, curves={"c": disc(n=8) + disc(n=8)[:1]}),
        beams=("a", "b"), contact=True),
     "beams[1].section.loop", "a curve closing on itself is a whole outline: give beams[1] its own"),
    ("contact with stations whose interfaces differ", config(
        {"stations": [dict(inline(three()), x=0.0), dict(inline(three(r=2.5)), x=0.02)]},
        beams=("p", "q", "r"), contact=True),
     "contact", "interface curve is the same at every station"),
]


@pytest.mark.parametrize("name,raw,path,text", CASES, ids=[c[0] for c in CASES])
def test_bad_geometry_is_one_line_exit_2(tmp_path, name, raw, path, text):
    write_files(tmp_path)
    raw = dict(raw, output={"dir": str(tmp_path / "out")})
    p = solve_cli(write_config(raw, tmp_path / "bad.yaml"), cwd=str(tmp_path))
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode == 2, p.stdout + p.stderr
    assert "Traceback" not in p.stderr and len(lines) == 1, p.stderr
    assert lines[0].startswith(f"ancf-solve: config error: {path}:"), lines[0]
    assert text in lines[0], lines[0]


def test_an_svg_width_that_is_no_length_is_one_line(tmp_path):
    """width="1.2.3mm" stopped ancf-solve with a ValueError traceback (float('1.2.3'))."""
    (tmp_path / "w.svg").write_text('<svg xmlns="http://www.w3.org/2000/svg" width="1.2.3mm" viewBox="0 0 10 10">'
                                    '<rect id="a" x="1" y="1" width="4" height="3"/></svg>')
    raw = dict(config(inline({"a": {"file": "w.svg"}}, axes="image")), output={"dir": str(tmp_path / "out")})
    p = solve_cli(write_config(raw, tmp_path / "bad.yaml"), cwd=str(tmp_path))
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert p.stderr.strip() == ("ancf-solve: config error: geometry.sections.outlines.a: w.svg: its width '1.2.3mm' "
                                "is not a length (a number and a unit, e.g. 40mm): correct it in the file"), p.stderr


KEY_CASES = [
    ("units missing", {"axes": ["y", "z"], "outlines": {"a": {"points": disc()}}}, "geometry.sections.units", "missing"),
    ("axes not a frame", inline({"a": {"points": disc()}}, axes=("y", "y")), "geometry.sections.axes", "[y, -z]"),
    ("px without size", inline({"a": {"points": disc()}}, units="px"), "geometry.sections.pixel_size", "0.05 mm"),
    ("unknown outline", inline({"b": {"points": disc()}}), "beams[0].section.loop", "available: b"),
    ("material in the geometry file", {"file": "g.yaml"}, "geometry.sections.file", "g.yaml: length_m: a geometry description holds geometry only"),
    ("label on a point list", inline({"a": {"file": "g.yaml", "label": 3}}), "geometry.sections.outlines.a.label", "mask images"),
    # degree 4 raised a ValueError traceback ('Odd degree for now only. Got 4.')
    # a loop of one open curve was told to reverse it; merging options beside named curves were ignored
    ("one open curve as a loop", inline({"a": {"curves": ["-mid"]}}, curves={"mid": [[0, -2], [1, 0], [0, 2]]}),
     "geometry.sections.outlines.a.curves", "curve 'mid' alone does not close the loop: it starts at (0.000, 2.000) mm"),
    ("merge tolerance beside named curves", inline({"a": {"curves": ["c"]}}, merge_tolerance=1e-4,
                                                   curves={"c": [[0, 0], [2, 0], [1, 2], [0, 0]]}),
     "geometry.sections.merge_tolerance", "loops of named curves are taken exactly as given (no smoothing or "
                                          "merging): remove it; got 0.0001"),
    ("even spline degree", inline({"a": {"points": disc()}}, spline_degree=4), "geometry.sections.spline_degree",
     "must be one of 1, 2, 3, 5: interpolating splines of even degree above 2 are not built"),
    ("station beyond the tendon", {"stations": [dict(inline({"a": {"points": disc()}}), x=0.0),
                                                dict(inline({"a": {"points": disc()}}), x=0.5)]},
     "geometry.sections.stations[1].x", "beyond the tendon"),
]


@pytest.mark.parametrize("name,sections,path,text", KEY_CASES, ids=[c[0] for c in KEY_CASES])
def test_geometry_keys_are_checked_with_their_path(tmp_path, name, sections, path, text):
    from ancf_petsc.config.values import ConfigError
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    (tmp_path / "g.yaml").write_text("units: mm\naxes: [y, z]\nlength_m: 0.05\noutlines: {a: {points: [[0, 0], [1, 0], [0, 1]]}}\n")
    with pytest.raises(ConfigError) as err:
        build_model(parse_config(config(sections), base_dir=str(tmp_path)))
    msg = str(err.value)
    assert msg.startswith(path + ":") and text in msg and "\n" not in msg, msg


def test_twist_axis_rule_errors():
    from ancf_petsc.config.values import ConfigError
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    raw = config(inline({"a": {"points": disc()}}))
    raw["geometry"]["twist_axis"] = "junction"               # one outline: nothing to meet
    with pytest.raises(ConfigError, match=r"^geometry.twist_axis: junction needs one point where all "
                                          r"measured outlines meet; found 0"):
        build_model(parse_config(raw))
    raw["geometry"]["twist_axis"] = {"centroid_of": "zz"}
    with pytest.raises(ConfigError, match=r"^geometry.twist_axis.centroid_of: unknown beam 'zz'"):
        parse_config(raw)
