"""3D Slicer markups files (outline_formats/slicer_markups.py), written here as Slicer's schema
(markups-schema-v1.0.3.json) defines them: shapes with known areas and centroids drawn on axial
and sagittal slices, the curve Slicer draws through the control points (VTK's equations written
out here), LPS against RAS, markups picked by name, and the one-line errors."""
import json

import numpy as np
import pytest

from ancf_petsc.config.parse import parse_config
from ancf_petsc.config.sections import parse_sections
from ancf_petsc.config.values import ConfigError
from ancf_petsc.geometry_input.build import build_station
from ancf_petsc.model.build import build_model
from ancf_petsc.physics.section import make_outline
from helpers import solve_cli, write_config

SCHEMA = "https://raw.githubusercontent.com/Slicer/Slicer/main/Modules/Loadable/Markups/Resources/Schema/markups-schema-v1.0.3.json#"


def markup(points, kind="ClosedCurve", system="LPS", name=None, units="mm", status=None):
    """One markup with control points ``points`` given in RAS (turned into LPS if asked)."""
    P = np.asarray(points, dtype=float) * ([-1.0, -1.0, 1.0] if system == "LPS" else 1.0)
    cps = [{"id": str(k + 1), "label": f"C-{k + 1}", "position": p.tolist(),
            "positionStatus": (status or {}).get(k, "defined")} for k, p in enumerate(P)]
    m = {"type": kind, "coordinateSystem": system, "coordinateUnits": units, "locked": False,
         "labelFormat": "%N-%d", "controlPoints": cps, "measurements": [], "display": {"visibility": True}}
    return m if name is None else {"name": name, **m}


def write(path, *markups):
    path.write_text(json.dumps({"@schema": SCHEMA, "markups": list(markups)}, indent=2))
    return path.name


def ellipse(a, b, c, n=48):
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False) + 0.2
    return np.column_stack([c[0] + a * np.cos(t), c[1] + b * np.sin(t)])


def axial(uv, s=37.25):
    return np.column_stack([uv, np.full(len(uv), s)])


def station(desc, base_dir):
    spec = parse_sections(desc, "geometry.sections", str(base_dir), 0.05)
    return build_station(spec.stations[0][1], spec)


def section(st, name):
    return make_outline(st.loops[name], 6)


def test_closed_curve_on_an_axial_slice_lps_and_ras(tmp_path):
    a, b, c = 4.0, 2.5, (1.5, -2.0)                                       # mm, R and A
    write(tmp_path / "lps.mrk.json", markup(axial(ellipse(a, b, c))))
    write(tmp_path / "ras.mrk.json", markup(axial(ellipse(a, b, c)), system="RAS"))
    desc = {"units": "mm", "axes": ["y", "z"], "outlines": {"e": {"file": "lps.mrk.json"}}}
    st = station(desc, tmp_path)
    sec = section(st, "e")
    # an interpolating spline through 48 points of the ellipse: area and centroid to 1e-4
    assert sec.area == pytest.approx(np.pi * a * b * 1e-6, rel=1e-4)
    assert np.allclose(sec.centroid, np.array(c) * 1e-3, rtol=0, atol=1e-4 * b * 1e-3)
    assert any("axial plane S = 37.25 mm, u = R, v = A (RAS)" in ln for ln in st.report), st.report
    ras = station({**desc, "outlines": {"e": {"file": "ras.mrk.json"}}}, tmp_path)
    assert np.array_equal(section(ras, "e").points, sec.points)           # LPS read as Slicer does


def vtk_closed_curve(P, m=2000):
    """Slicer's closed curve through P, written out here from VTK's vtkCardinalSpline::FitClosed1D
    with unit parameter steps (vtkCurveGenerator: not by length): slopes D from
    D[k-1] + 4 D[k] + D[k+1] = 3 (P[k+1] - P[k-1]) (cyclic), Hermite cubics, m samples each."""
    n = len(P)
    A = 4.0 * np.eye(n) + np.roll(np.eye(n), 1, axis=1) + np.roll(np.eye(n), -1, axis=1)
    D = np.linalg.solve(A, 3.0 * (np.roll(P, -1, axis=0) - np.roll(P, 1, axis=0)))
    s = np.linspace(0.0, 1.0, m, endpoint=False)[:, None]
    h = (2 * s ** 3 - 3 * s ** 2 + 1, s ** 3 - 2 * s ** 2 + s, -2 * s ** 3 + 3 * s ** 2, s ** 3 - s ** 2)
    Q, DQ = np.roll(P, -1, axis=0), np.roll(D, -1, axis=0)
    return np.vstack([h[0] * P[k] + h[1] * D[k] + h[2] * Q[k] + h[3] * DQ[k] for k in range(n)])


def area_centroid(C):
    x, y = C[:, 0], C[:, 1]
    c = x * np.roll(y, -1) - np.roll(x, -1) * y
    a = 0.5 * c.sum()
    return a, np.array([((x + np.roll(x, -1)) * c).sum(), ((y + np.roll(y, -1)) * c).sum()]) / (6 * a)


def test_the_outline_is_the_curve_slicer_draws_not_the_polygon(tmp_path):
    """Ten irregular control points: the section is Slicer's cardinal-spline curve through them
    (to 3e-5 in area and 0.1 um in centroid with a 1 um fit tolerance; within 2e-4 and 1 um with
    the default 12.5 um), not the polygon through them (6 % less area)."""
    k = np.arange(10)
    th, r = np.linspace(0.0, 2 * np.pi, 10, endpoint=False) + 0.15 * np.sin(3 * k), 3.0 + 0.5 * np.cos(2 * k)
    P = np.column_stack([1.0 + 1.6 * r * np.cos(th), -0.5 + r * np.sin(th)])
    write(tmp_path / "c.mrk.json", markup(axial(P)))
    a, c = area_centroid(vtk_closed_curve(P))
    assert area_centroid(P)[0] / a - 1.0 < -0.05
    for opts, rel, atol in (({"fit_tolerance": 1e-6}, 3e-5, 1e-7), ({}, 2e-4, 1e-6)):
        sec = section(station({"units": "mm", "axes": ["y", "z"], "outlines": {"c": {"file": "c.mrk.json"}},
                               **opts}, tmp_path), "c")
        assert sec.area == pytest.approx(a * 1e-6, rel=rel), opts
        assert np.allclose(sec.centroid, c * 1e-3, rtol=0, atol=atol), opts


def test_markups_picked_by_name_from_one_file(tmp_path):
    """Two subtendons drawn as named closed curves in one file beside a point list (Fiducial)."""
    write(tmp_path / "t.mrk.json", markup(axial([[0, 0], [1, 1], [2, 0]]), kind="Fiducial", name="F"),
          markup(axial(ellipse(3.0, 2.0, (-4.0, 1.0))), name="soleus"),
          markup(axial(ellipse(2.0, 1.5, (3.0, -1.0))), name="medial"))
    desc = {"units": "mm", "axes": ["y", "z"], "source": "t.mrk.json",
            "outlines": {"medial": {"markup": "medial"}, "soleus": {"markup": "soleus"}}}
    st = station(desc, tmp_path)
    for name, (a, b, c) in (("soleus", (3.0, 2.0, (-4.0, 1.0))), ("medial", (2.0, 1.5, (3.0, -1.0)))):
        sec = section(st, name)
        assert sec.area == pytest.approx(np.pi * a * b * 1e-6, rel=2e-4), name
        assert np.allclose(sec.centroid, np.array(c) * 1e-3, rtol=0, atol=2e-4 * b * 1e-3), name


def test_sagittal_curve_in_micrometres(tmp_path):
    """On a sagittal slice (R constant) u = A and v = S; coordinateUnits um as a UCUM triple."""
    uv = ellipse(2000.0, 1500.0, (500.0, -800.0), n=60)                   # um: A, S
    P = np.column_stack([np.full(len(uv), -12.5), uv])
    write(tmp_path / "s.mrk.json", markup(P, units=["um", "UCUM", "micrometer"], system="RAS"))
    st = station({"units": "um", "axes": ["y", "z"], "outlines": {"s": {"file": "s.mrk.json"}}}, tmp_path)
    sec = section(st, "s")
    assert sec.area == pytest.approx(np.pi * 2e-3 * 1.5e-3, rel=2e-4)
    assert np.allclose(sec.centroid, [0.5e-3, -0.8e-3], rtol=0, atol=2e-4 * 1.5e-3)
    assert any("sagittal plane R = -12.5 um, u = A, v = S" in ln for ln in st.report)


def test_points_not_placed_are_left_out(tmp_path):
    uv = ellipse(4.0, 2.5, (0.0, 0.0))
    P = axial(np.vstack([uv, [[40.0, 40.0], [-9.0, 3.0]]]))           # two stray, unplaced points
    write(tmp_path / "p.mrk.json", markup(P, status={48: "undefined", 49: "preview"}))
    st = station({"units": "mm", "axes": ["y", "z"], "outlines": {"e": {"file": "p.mrk.json"}}}, tmp_path)
    assert section(st, "e").area == pytest.approx(np.pi * 10e-6, rel=1e-4)
    assert any("2 control point(s) not placed" in ln for ln in st.report)


def tilted(uv, deg=2.0):
    t = np.deg2rad(deg)
    return np.column_stack([uv[:, 0], uv[:, 1] * np.cos(t), 30.0 + uv[:, 1] * np.sin(t)])


ERRORS = [
    ("oblique", lambda: [markup(tilted(ellipse(4.0, 2.5, (0, 0))))], {}, "mm",
     "o.mrk.json markup #0 (unnamed) does not lie in a plane normal to a patient axis: its points spread "
     "0.1742 mm along S (the least) over 7.985 mm; draw the curve in Slicer's Axial, Sagittal or Coronal slice "
     "view (not a reformatted, oblique one)"),
    ("two curves, no name", lambda: [markup(axial(ellipse(4, 2, (0, 0))), name="a"),
                                     markup(axial(ellipse(2, 1, (9, 0))), name="b")], {}, "mm",
     "o.mrk.json holds 2 curve markups ('a', 'b'); name one per subtendon with markup: <name>"),
    ("unknown name", lambda: [markup(axial(ellipse(4, 2, (0, 0))), name="a")], {"markup": "soleus"}, "mm",
     "o.mrk.json has no curve markup named 'soleus' (curve markups: 'a')"),
    ("units differ", lambda: [markup(axial(ellipse(4000, 2000, (0, 0))), units="um")], {}, "mm",
     "o.mrk.json: its coordinates are in um (coordinateUnits); declare units: um (the description says units: mm)"),
    ("point list only", lambda: [markup(axial(ellipse(4, 2, (0, 0))), kind="Fiducial")], {}, "mm",
     "o.mrk.json holds no curve markup (types: Fiducial); draw the outline with Slicer's closed curve tool"),
]


@pytest.mark.parametrize("name,marks,keys,units,text", ERRORS, ids=[e[0] for e in ERRORS])
def test_errors_name_the_file_and_the_fix(tmp_path, name, marks, keys, units, text):
    write(tmp_path / "o.mrk.json", *marks())
    desc = {"units": units, "axes": ["y", "z"], "outlines": {"a": {"file": "o.mrk.json", **keys}}}
    with pytest.raises(ConfigError) as err:
        station(desc, tmp_path)
    msg = str(err.value)
    assert msg.startswith("geometry.sections.outlines.a: ") and text in msg and "\n" not in msg, msg


def test_markup_key_belongs_to_markups_files(tmp_path):
    (tmp_path / "a.csv").write_text("0,0\n1,0\n1,1\n")
    with pytest.raises(ConfigError, match=r"^geometry.sections.outlines.a.markup: markup belongs to 3D "
                                          r"Slicer markups files \(.mrk.json\), not to a point list"):
        parse_sections({"units": "mm", "axes": ["y", "z"], "outlines": {"a": {"file": "a.csv", "markup": "x"}}},
                       "geometry.sections", str(tmp_path), 0.05)


def config(desc):
    return {"name": "slicer", "geometry": {"length": 0.02, "sections": desc},
            "beams": [{"name": "a", "section": {"shape": "outline", "loop": "a"}, "elements": 1,
                       "material": {"model": "neo-hookean", "mu": 1e6, "bulk_modulus": 1e7}}],
            "steps": [1.0]}


def test_a_model_from_a_markups_file_and_its_error_through_ancf_solve(tmp_path):
    write(tmp_path / "a.mrk.json", markup(axial(ellipse(4.0, 2.5, (0.0, 0.0)))))
    write(tmp_path / "o.mrk.json", markup(tilted(ellipse(4.0, 2.5, (0.0, 0.0)))))
    desc = {"units": "mm", "axes": ["y", "z"], "outlines": {"a": {"file": "a.mrk.json"}}}
    model = build_model(parse_config(config(desc), base_dir=str(tmp_path)))
    assert model.beams[0].section.area == pytest.approx(np.pi * 10e-6, rel=1e-4)
    raw = config({**desc, "outlines": {"a": {"file": "o.mrk.json"}}})
    raw["output"] = {"dir": str(tmp_path / "out")}
    p = solve_cli(write_config(raw, tmp_path / "bad.yaml"), cwd=str(tmp_path))
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode == 2 and len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    assert lines[0].startswith("ancf-solve: config error: geometry.sections.outlines.a: o.mrk.json markup "
                               "#0 (unnamed) does not lie in a plane normal to a patient axis"), lines[0]


def test_open_curve_must_come_back_to_its_start(tmp_path):
    """An open curve (type Curve) is an outline when its last control point is its first (Slicer:
    end slopes 0 there, a corner); ends apart are the point lists' open-outline error."""
    uv = ellipse(4.0, 2.5, (0.0, 0.0), n=48)
    write(tmp_path / "round.mrk.json", markup(axial(np.vstack([uv, uv[:1]])), kind="Curve"))
    write(tmp_path / "open.mrk.json", markup(axial(uv[:40]), kind="Curve"))
    desc = {"units": "mm", "axes": ["y", "z"], "outlines": {"a": {"file": "round.mrk.json"}}}
    assert section(station(desc, tmp_path), "a").area == pytest.approx(np.pi * 10e-6, rel=5e-4)
    with pytest.raises(ConfigError, match=r"^geometry.sections.outlines.a: the outline is open"):
        station({**desc, "outlines": {"a": {"file": "open.mrk.json"}}}, tmp_path)
