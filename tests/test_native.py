"""The compiled-kernel plumbing (ancf_petsc/native.py): which path runs,
and when a module counts as out of date.  The kernels themselves are tested against their numpy
originals beside them (tests/physics)."""
import os

from ancf_petsc import native


def test_switched_off_by_the_environment(monkeypatch):
    monkeypatch.setenv("ANCF_NATIVE", "0")
    assert not native.enabled()
    assert native.load("physics.kernels") is None
    assert native.status("physics.kernels") == "numpy (ANCF_NATIVE=0)"


def test_a_missing_module_says_why(monkeypatch):
    monkeypatch.delenv("ANCF_NATIVE", raising=False)
    assert native.load("physics.no_such_kernel") is None
    assert native.status("physics.no_such_kernel").startswith("numpy: not built")


def test_a_source_newer_than_its_extension_is_rebuilt(tmp_path):
    build = native
    pyx = tmp_path / "k.pyx"
    pyx.write_text("# a kernel\n")
    assert build.stale(str(pyx))                      # no extension yet
    so = build.extension_path(str(pyx))
    open(so, "w").close()
    os.utime(pyx, (1.0e9, 1.0e9))
    os.utime(so, (2.0e9, 2.0e9))
    assert not build.stale(str(pyx))
    (tmp_path / "k.pxd").write_text("# declarations\n")
    os.utime(tmp_path / "k.pxd", (3.0e9, 3.0e9))       # a .pxd beside it changed
    assert build.stale(str(pyx))
