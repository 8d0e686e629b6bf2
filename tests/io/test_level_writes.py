"""The per-level output's fast paths (issue 38 item 4): h5py's low-level writes (io/h5fast.py)
store what h5py's high-level calls store, summary.json's levels come back from results.h5 when
summary.json lags (in a long history it is rewritten only while that takes at most SUMMARY_SHARE of the run), and the VTU cells encoded
once per run make the same files."""
import json

import h5py
import numpy as np
import pytest

from helpers import load_raw, run_inline

VALUES = {"float": np.linspace(0.0, 1.0, 12).reshape(4, 3), "scalar": 2.5, "int": 7,
          "np_int": np.int64(-3), "bool": np.array([True, False, True]), "int8": np.arange(4, dtype=np.int8),
          "text": "m: some units", "texts": ["fix_a", "fix_b"], "empty": np.zeros((0, 3)),
          "vector": np.array([1.0, -2.0, 3.0])}


def _attrs(obj) -> dict:
    return {k: obj.attrs[k] for k in obj.attrs}


def test_fast_writes_read_back_as_h5py_high_level_writes(tmp_path):
    """Every kind of value a level holds: the same dtype, shape and value as dataset and as
    attribute, strings as str, paths with their intermediate groups."""
    from ancf_petsc.io import h5fast
    with h5py.File(tmp_path / "x.h5", "w") as h5:
        slow, fast = h5.create_group("slow"), h5.create_group("fast")
        for name, value in VALUES.items():
            slow.create_dataset(f"sub/{name}", data=value).attrs["value"] = value
            h5fast.attribute(h5fast.dataset(fast.id, f"sub/{name}", value), "value", value)
            slow.attrs[name] = value
        h5fast.attributes(fast.id, VALUES)
        h5fast.group(fast.id, "deep/er")
    with h5py.File(tmp_path / "x.h5") as h5:
        assert "deep/er" in h5["fast"]
        for name in VALUES:
            a, b = h5["slow/sub"][name], h5["fast/sub"][name]
            assert a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a[()], b[()]), name
            assert b.chunks is None and b.compression is None
        for pa, pb in ((h5["slow"], h5["fast"]),) + tuple((h5["slow/sub"][n], h5["fast/sub"][n]) for n in VALUES):
            A, B = _attrs(pa), _attrs(pb)
            assert sorted(A) == sorted(B)
            for k in A:
                assert type(A[k]) is type(B[k]) and np.array_equal(A[k], B[k]), (pb.name, k)
        assert h5["fast"].attrs["text"] == "m: some units"
        assert list(h5["fast"].attrs["texts"]) == ["fix_a", "fix_b"]


def _uniaxial(tmp_path):
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.25, 0.5, 0.75, 1.0]
    return run_inline(raw, tmp_path)


def test_a_summary_that_lags_results_h5_is_completed_from_it(tmp_path):
    """A run killed between two rewrites of summary.json: read_results and --restart get every
    level results.h5 holds, each entry exactly as the final summary.json lists it."""
    from ancf_petsc.io.reader import read_results
    from ancf_petsc.io.restart import read_restart
    full = _uniaxial(tmp_path)
    final = json.loads((tmp_path / "summary.json").read_text())
    lagging = dict(final, status="running", steps=final["steps"][:1])
    (tmp_path / "summary.json").write_text(json.dumps(lagging))
    res = read_results(str(tmp_path))
    assert len(res.summary["steps"]) == 4 and res.summary["steps"] == final["steps"] == json.loads(
        json.dumps(full["steps"]))
    assert res.summary["last_converged"] == {"step": 4, "load_factor": 1.0}
    assert np.array_equal(res.load_factors, [0.25, 0.5, 0.75, 1.0])
    point = read_restart(str(tmp_path))
    assert point.step == 4 and point.summary["steps"] == final["steps"]
    # levels as Python indexes them; a level the run has not: IndexError naming the ones it has
    assert np.array_equal(res.nodal_vectors(-1), res.nodal_vectors(4))
    assert np.array_equal(res.nodal_vectors(-5), res.nodal_vectors(0))
    for bad in (5, -6):
        with pytest.raises(IndexError, match=r"the run has 4 converged level\(s\): 1 … 4, 0 the reference"):
            res.nodal_vectors(bad)
    with pytest.raises(KeyError, match="the run has no contact"):
        res.contact(-1)


def test_an_older_results_h5_without_entries_restarts_where_summary_json_ends(tmp_path):
    """results.h5 written before the levels carried their summary entry: the restart continues
    from the last level both files hold, as before."""
    from ancf_petsc.io.restart import read_restart
    _uniaxial(tmp_path)
    with h5py.File(tmp_path / "results.h5", "a") as h5:
        for name in h5["steps"]:
            del h5["steps"][name].attrs["summary_entry"]
    final = json.loads((tmp_path / "summary.json").read_text())
    (tmp_path / "summary.json").write_text(json.dumps(dict(final, status="running", steps=final["steps"][:2])))
    point = read_restart(str(tmp_path))
    assert point.step == 2 and len(point.summary["steps"]) == 2


def test_vtu_cells_encoded_once_make_the_same_files(tmp_path):
    """A series' second file, its cells' XML kept from the first, is byte for byte the file
    ``write_vtu`` writes from scratch."""
    from ancf_petsc.io.vtk import VtkSeries
    from ancf_petsc.io.vtu import write_vtu
    pts = np.random.default_rng(0).random((8, 3))
    cells = [("quad", np.array([[0, 1, 2, 3], [4, 5, 6, 7]])), ("polygon", np.array([[3, 2, 1, 0]]))]
    series = VtkSeries(str(tmp_path))
    for k in (1, 2):
        series.write("surface", k, 0.5 * k, k * pts, cells, {"J": np.full(8, float(k))})
        write_vtu(str(tmp_path / f"ref_{k}.vtu"), (k * pts).astype(np.float32), cells,
                  {"J": np.full(8, float(k), dtype=np.float32)})
        assert (tmp_path / f"surface_{k:04d}.vtu").read_bytes() == (tmp_path / f"ref_{k}.vtu").read_bytes()


def test_summary_rewrites_take_a_bounded_share_of_a_long_run(tmp_path, monkeypatch):
    """A summary.json that costs 4 ms per level it lists to write (as a long history's grows):
    while the run goes on its rewrites take at most SUMMARY_SHARE of the run's time (and one
    rewrite more), instead of one per level (which here would be most of the run), and the
    final summary.json and read_results list every level."""
    import time

    from ancf_petsc.io import results
    from ancf_petsc.io.reader import read_results
    costs = []
    real = results.atomic_write

    def slow(path, text):
        t0 = time.monotonic()
        doc = json.loads(text)
        if doc["status"] == "running":
            time.sleep(0.004 * len(doc["steps"]))
        real(path, text)
        if doc["status"] == "running":
            costs.append(time.monotonic() - t0)

    monkeypatch.setattr(results, "atomic_write", slow)
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.02 * k for k in range(1, 41)]
    t0 = time.monotonic()
    s = run_inline(raw, tmp_path)
    wall = time.monotonic() - t0
    assert s["status"] == "completed" and len(s["steps"]) == 40
    assert len(costs) < 40                                   # the level-1 rewrite and some others
    assert sum(costs) <= results.SUMMARY_SHARE * wall + max(costs) + 0.01, (sum(costs), wall)
    assert len(read_results(str(tmp_path)).summary["steps"]) == 40
