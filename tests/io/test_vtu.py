"""io/vtu.py (issue 40): the VTU files are meshio's, line for line (the comment naming the writer
aside), compressed or not, and meshio reads them back."""
import re

import meshio
import numpy as np
import pytest

from ancf_petsc.io.vtu import write_vtu


@pytest.mark.parametrize("compress", [False, True])
def test_same_file_as_meshio(tmp_path, compress):
    rng = np.random.default_rng(0)
    pts = rng.random((40000, 3)).astype(np.float32)       # > 32 KiB: several zlib blocks
    cells = [("quad", rng.integers(0, 40000, (300, 4))), ("polygon", np.arange(7)[None, :]),
             ("polygon", np.arange(9)[None, :])]
    data = {"displacement": rng.random((40000, 3)).astype(np.float32),
            "J": rng.random(40000).astype(np.float32)}
    a, b = tmp_path / "meshio.vtu", tmp_path / "ours.vtu"
    meshio.write(a, meshio.Mesh(pts, cells, point_data=data), binary=True,
                 compression="zlib" if compress else None)
    write_vtu(str(b), pts, cells, data, compress)
    la, lb = a.read_text().split("\n"), b.read_text().split("\n")
    assert len(la) == len(lb)
    assert [i for i, (x, y) in enumerate(zip(la, lb)) if x != y] == [2]     # the comment
    back = meshio.read(b)
    assert np.array_equal(back.points, pts) and np.array_equal(back.point_data["J"], data["J"])
    assert [c.type for c in back.cells] == ["quad", "polygon", "polygon"]


def test_pvd_collections_rewritten_when_due_and_complete_at_the_end(tmp_path, monkeypatch):
    """A series' .pvd is written with its first VTU, then at most every INDEX_INTERVAL, and
    ``write_indexes`` lists every VTU; a collection that cannot be written is named, not raised."""
    from ancf_petsc.io import vtk
    clock = [100.0]
    monkeypatch.setattr(vtk.time, "monotonic", lambda: clock[0])
    series = vtk.VtkSeries(str(tmp_path), compress=False)
    pts = np.zeros((2, 3))
    cells = [("vertex", np.arange(2)[:, None])]
    pvd = tmp_path / "surface.pvd"
    for k in range(3):                                      # at 0, 0.2 and 0.4 s
        series.write("surface", k, float(k), pts, cells, {"a": np.ones(2)})
        clock[0] += 0.2
        assert pvd.read_text().count("<DataSet") == 1       # the first level's
    series.write("surface", 3, 3.0, pts, cells, {"a": np.ones(2)})      # 0.6 s: due
    assert pvd.read_text().count("<DataSet") == 4
    series.write("surface", 4, 4.0, pts, cells, {"a": np.ones(2)})
    assert pvd.read_text().count("<DataSet") == 4
    assert series.write_indexes() is None
    assert pvd.read_text().count("<DataSet") == 5
    pvd.unlink()
    pvd.mkdir()                                             # a directory where the file goes
    reason = series.write_indexes()
    assert reason is not None and "surface.pvd: cannot write" in reason


def test_a_collection_that_cannot_be_written_is_named_not_the_vtu(tmp_path):
    """A folder named surface.pvd in the output directory: the run failed with 'output error:
    DIR/surface_0000.vtu: cannot write: Is a directory', naming the VTU it had written, not the
    collection in the way; now 'DIR/surface.pvd: cannot write: Is a directory'."""
    import json
    from ancf_petsc.errors import OutputError
    from helpers import load_raw, run_inline
    (tmp_path / "surface.pvd").mkdir()
    with pytest.raises(OutputError) as err:
        run_inline(dict(load_raw("uniaxial_neohookean.yaml"), steps=[0.5]), tmp_path)
    assert str(err.value) == f"{tmp_path / 'surface.pvd'}: cannot write: Is a directory"
    s = json.load(open(tmp_path / "summary.json"))
    assert s["status"] == "failed" and str(err.value) in s["message"], s

def test_a_restart_removes_only_the_run_s_later_vtus(tmp_path):
    """``VtkSeries.resume`` (a restart after level 1) removed every name starting with
    surface_/contact_ whose last '_' part was a number past it: a user's surface_notes_7.txt went,
    and a folder surface_run_9 stopped the restart ('output error: …/surface_run_9: Is a
    directory', exit 2).  Now only the series' own later VTUs go."""
    from ancf_petsc.io import vtk
    ours = ["surface_0000.vtu", "surface_0001.vtu", "surface_0002.vtu", "surface_0003.vtu",
            "contact_0001.vtu", "contact_0002.vtu"]
    users = ["surface_notes_7.txt", "contact_figure_12.png", "surface_12.vtu", "surface_0005.vtu.bak"]
    for name in ours + users:
        (tmp_path / name).write_text("x")
    (tmp_path / "surface_run_9").mkdir()
    series = vtk.VtkSeries(str(tmp_path))
    series.resume([0.0, 0.5])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["surface_0000.vtu", "surface_0001.vtu", "contact_0001.vtu", "surface_run_9"] + users)
    assert series.entries == {"surface": [(0.0, "surface_0000.vtu"), (0.5, "surface_0001.vtu")],
                              "contact": [(0.5, "contact_0001.vtu")]}


def test_each_time_of_a_series_has_one_file(tmp_path):
    """A level passed over with the one before it (solver.step_over_jumps: 2500 and 2500.2 N both
    reported at 2500.5 N, the same state) was listed twice at one time in surface.pvd, and ParaView
    showed either; a history's rest state (no time of its clock) is not listed.  Each VTU is still
    written, and a restart lists the files the same way."""
    from ancf_petsc.io import vtk
    pts, cells = np.zeros((2, 3)), [("vertex", np.arange(2)[:, None])]
    times = [0.0, 1000.0, 2500.5, 2500.5, 2600.0]
    series = vtk.VtkSeries(str(tmp_path), compress=False)
    for k, t in enumerate(times):
        series.write("surface", k, t, pts, cells, {"a": np.ones(2)})
    series.write_indexes()
    listed = re.findall(r'timestep="([^"]+)" part="0" file="([^"]+)"', (tmp_path / "surface.pvd").read_text())
    assert listed == [("0", "surface_0000.vtu"), ("1000", "surface_0001.vtu"), ("2500.5", "surface_0002.vtu"),
                      ("2600", "surface_0004.vtu")]
    assert (tmp_path / "surface_0003.vtu").exists()
    again = vtk.VtkSeries(str(tmp_path))
    again.resume([None, 0.1, 0.2, 0.2])                 # a history's rest, then frames at 0.1, 0.2 s
    assert again.entries["surface"] == [(0.1, "surface_0001.vtu"), (0.2, "surface_0002.vtu")]


def test_a_level_s_field_data_is_read_back(tmp_path):
    """The grid's field data (a level's ``stable`` flag, ...) as VTK reads it: one tuple per array,
    NumberOfTuples given (VTK's XML reader needs it in FieldData); meshio reads the values."""
    pts, cells = np.zeros((2, 3), dtype=np.float32), [("vertex", np.arange(2)[:, None])]
    fields = {"stable": np.array([0], dtype=np.int32), "load_factor": np.array([2500.5])}
    for compress in (False, True):
        write_vtu(str(tmp_path / "a.vtu"), pts, cells, {"J": np.ones(2, dtype=np.float32)}, compress,
                  field_data=fields)
        text = (tmp_path / "a.vtu").read_text()
        assert '<DataArray type="Int32" Name="stable" NumberOfTuples="1" format="binary">' in text
        back = meshio.read(tmp_path / "a.vtu")
        assert back.field_data["stable"].tolist() == [0] and back.field_data["load_factor"].tolist() == [2500.5]
