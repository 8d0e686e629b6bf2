"""Compiled kernels: the Cython modules beside their numpy originals, and which path runs.

``build`` (scripts/build_native.py, run by ``scripts/setup.sh``) compiles every
``ancf_petsc/**/*.pyx`` in place with Cython (Debian's cython3), ``-O3 -march=native`` (the
extension is built on the machine that runs it), and only a module whose ``.pyx`` (or a ``.pxd``
beside it) is newer than its extension, so a second run does nothing.  ``load`` returns the compiled module, or None when it is not built, older than its source, or
switched off by ``ANCF_NATIVE=0`` (for side-by-side checks and benchmarks); callers then run
the numpy code, which stays the reference that the compiled code is tested against.
"""
from __future__ import annotations

import glob
import importlib
import os
import sys
import sysconfig
from types import ModuleType

_loaded: dict[str, ModuleType | None] = {}
_why: dict[str, str] = {}


def enabled() -> bool:
    """False when ``ANCF_NATIVE=0`` is set."""
    return os.environ.get("ANCF_NATIVE", "1") != "0"


def load(name: str) -> ModuleType | None:
    """The compiled module ``ancf_petsc.<name>`` or None (see the module docstring)."""
    if not enabled():
        return None
    if name not in _loaded:
        _loaded[name] = _import(name)
    return _loaded[name]


def _import(name: str) -> ModuleType | None:
    pyx = os.path.join(os.path.dirname(__file__), *name.split(".")) + ".pyx"
    try:
        module = importlib.import_module(f"{__package__}.{name}")
    except ImportError as exc:
        _why[name] = f"not built ({exc}): run scripts/setup.sh"
        return None
    if os.path.exists(pyx) and os.path.getmtime(pyx) > os.path.getmtime(module.__file__):
        _why[name] = f"{os.path.basename(module.__file__)} is older than its source: run scripts/setup.sh"
        return None
    return module


def status(name: str) -> str:
    """'compiled', or why the numpy path runs."""
    if not enabled():
        return "numpy (ANCF_NATIVE=0)"
    return "compiled" if load(name) is not None else f"numpy: {_why.get(name, 'unknown')}"


def extension_path(pyx: str) -> str:
    """The compiled extension of a ``.pyx`` file, beside it."""
    return pyx[:-4] + sysconfig.get_config_var("EXT_SUFFIX")


def stale(pyx: str) -> bool:
    """True when ``pyx`` has no extension or it, or a ``.pxd`` beside it, is newer."""
    so = extension_path(pyx)
    if not os.path.exists(so):
        return True
    sources = [pyx] + glob.glob(os.path.join(os.path.dirname(pyx), "*.pxd"))
    return max(os.path.getmtime(s) for s in sources) > os.path.getmtime(so)


def build(root: str) -> int:
    """Compile the out-of-date ``.pyx`` modules of the checkout at ``root`` in place; 0 when all
    are current, 1 (with the reason on stderr) when Cython or the compiler fails."""
    os.chdir(root)
    todo = [p for p in sorted(glob.glob("ancf_petsc/**/*.pyx", recursive=True)) if stale(p)]
    if not todo:
        return 0
    try:
        from Cython.Build import cythonize
        from setuptools import Extension, setup
    except ImportError as exc:
        print(f"[setup] cannot build the compiled kernels: {exc} (apt-get install cython3)", file=sys.stderr)
        return 1
    exts = [Extension(p[:-4].replace(os.sep, "."), [p],
                      extra_compile_args=["-O3", "-march=native", "-Wno-unused-function"]) for p in todo]
    print(f"[setup] building {len(todo)} compiled kernel module(s): {', '.join(todo)}")
    try:
        setup(name="ancf-petsc-native", script_args=["-q", "build_ext", "--inplace"],
              ext_modules=cythonize(exts, language_level=3, quiet=True))
    except (SystemExit, Exception) as exc:   # setuptools reports a compiler failure by SystemExit
        print(f"[setup] the compiled kernels did not build ({exc}): the numpy kernels run instead",
              file=sys.stderr)
        return 1
    return 0


def main(argv: list[str] | None = None) -> int:
    """scripts/build_native.py: ``build`` on this checkout (``--help``: what it does)."""
    import argparse
    argparse.ArgumentParser(prog="build_native.py", allow_abbrev=False, description=(
        "Build the package's Cython modules in place: every ancf_petsc/**/*.pyx newer than its "
        "extension (run by scripts/setup.sh; quick when current).")).parse_args(argv)
    return build(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
