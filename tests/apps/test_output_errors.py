"""A full disk before level 1 (issue 25): the run ends with exit 2 / OutputError, and the files
that exist say ``failed`` with ``OUTPUT_ERROR``: summary.json is written if the disk lets it
(the 64 KB reserve is released for it), results.h5 never stays ``running``."""
from __future__ import annotations

import copy
import errno
import json
import os

import h5py
import pytest

from helpers import load_raw, run_inline

UNIAXIAL = load_raw("uniaxial_neohookean.yaml")


def _enospc(path: str) -> OSError:
    return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path)


def _fault(monkeypatch, target: str) -> str:
    """Make the first write of ``target`` fail with ENOSPC; the file the message names."""
    import ancf_petsc.io.results as out
    import ancf_petsc.io.vtk as vtk
    if target == "first vtu":
        def write(path, *a, **k):
            raise _enospc(path)
        monkeypatch.setattr(vtk, "write_vtu", write)
        return "surface_0000.vtu"
    if target == "first summary":
        real = out.atomic_write

        def atomic(path, text):
            if path.endswith("summary.json") and json.loads(text).get("status") == "running":
                raise _enospc(path + ".tmp")
            return real(path, text)
        monkeypatch.setattr(out, "atomic_write", atomic)
        return "summary.json"
    real_file = h5py.File

    def file(path, mode="r", *a, **k):
        if mode == "w" and str(path).endswith("results.h5"):
            real_file(path, mode).close()         # the file exists, empty: then the disk is full
            raise _enospc(str(path))
        return real_file(path, mode, *a, **k)
    monkeypatch.setattr(h5py, "File", file)
    return "results.h5"


@pytest.mark.parametrize("target", ["first vtu", "first summary", "model in results.h5"])
def test_a_full_disk_before_level_1_leaves_failed_not_running(tmp_path, monkeypatch, target):
    from ancf_petsc.io.files import OutputError
    name = _fault(monkeypatch, target)
    raw = copy.deepcopy(UNIAXIAL)
    raw["steps"] = [0.5, 1.0]
    out = tmp_path / "out"
    with pytest.raises(OutputError) as info:
        run_inline(raw, out)
    assert name in str(info.value) and "No space left on device" in str(info.value)
    with open(out / "summary.json") as fh:
        s = json.load(fh)
    assert s["status"] == "failed" and s["reason_code"] == "OUTPUT_ERROR" and s["steps"] == []
    assert name in s["message"] and s["message"].startswith("output error: ")
    if (out / "results.h5").exists():
        with h5py.File(out / "results.h5", "r") as h5:
            assert h5.attrs["status"] == "failed" and h5.attrs["reason_code"] == "OUTPUT_ERROR"
    assert target != "first vtu" or (out / "results.h5").exists()
    assert not [f for f in os.listdir(out) if f.startswith(".ancf") or f.endswith(".tmp")]


def test_the_api_exports_the_error_of_an_output_directory_that_cannot_hold_results(tmp_path):
    """``ancf_petsc.solve`` on an output.dir under a file raised io.files.OutputError, which the
    API (``ancf_petsc``, ``ancf_petsc.api``) did not export: a script caught it by a private path."""
    import ancf_petsc
    from ancf_petsc import api
    (tmp_path / "afile").write_text("")
    with pytest.raises(ancf_petsc.OutputError) as info:
        run_inline(UNIAXIAL, tmp_path / "afile" / "out")
    assert info.value.path == str(tmp_path / "afile" / "out")
    assert "OutputError" in api.__all__ and "OutputError" in ancf_petsc.__all__
