"""The compiled-kernel plumbing (ancf_petsc/native.py): which path runs,
and when a module counts as out of date.  The kernels themselves are tested against their numpy
originals beside them (tests/physics)."""
import glob
import importlib.util
import os

import pytest

from ancf_petsc import native

PACKAGE = os.path.dirname(os.path.abspath(native.__file__))
#: every compiled module of the package, by its ``native.load`` name
MODULES = sorted(os.path.relpath(p, PACKAGE)[:-4].replace(os.sep, ".")
                 for p in glob.glob(os.path.join(PACKAGE, "**", "*.pyx"), recursive=True))


def test_the_package_has_compiled_modules():
    assert {"physics.element_kernels", "contact.descent_native"} <= set(MODULES), MODULES


@pytest.mark.parametrize("name", MODULES)
def test_every_compiled_module_is_built_wherever_cython_is(name):
    """No silent fallback: with Cython importable (CI runs scripts/setup.sh, which builds every
    .pyx), the compiled module is the one that runs, not the numpy code beside it."""
    if not native.enabled():
        pytest.skip("ANCF_NATIVE=0 switches the compiled kernels off for this run")
    if importlib.util.find_spec("Cython") is None:
        pytest.skip("no Cython here: the numpy code runs")
    assert native.status(name) == "compiled"


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
    pyx = tmp_path / "k.pyx"
    pyx.write_text("# a kernel\n")
    assert native.stale(str(pyx))                      # no extension yet
    so = native.extension_path(str(pyx))
    open(so, "w").close()
    os.utime(pyx, (1.0e9, 1.0e9))
    os.utime(so, (2.0e9, 2.0e9))
    assert not native.stale(str(pyx))
    (tmp_path / "k.pxd").write_text("# declarations\n")
    os.utime(tmp_path / "k.pxd", (3.0e9, 3.0e9))       # a .pxd beside it changed
    assert native.stale(str(pyx))
