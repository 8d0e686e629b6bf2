#!/usr/bin/env python3
"""Build the package's Cython modules (``ancf_petsc/**/*.pyx``) in place; run by scripts/setup.sh.

Only a module whose ``.pyx`` (or a ``.pxd`` beside it) is newer than its extension is rebuilt, so
a second run does nothing.  Flags: ``-O3 -march=native`` (the extension is built on the machine
that runs it).  Without a compiler or Cython it says so and exits 1: the numpy kernels then run
(``ancf_petsc.native`` tells which path is in use)."""
import glob
import os
import sys
import sysconfig

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def extension_path(pyx: str) -> str:
    return pyx[:-4] + sysconfig.get_config_var("EXT_SUFFIX")


def stale(pyx: str) -> bool:
    so = extension_path(pyx)
    if not os.path.exists(so):
        return True
    sources = [pyx] + glob.glob(os.path.join(os.path.dirname(pyx), "*.pxd"))
    return max(os.path.getmtime(s) for s in sources) > os.path.getmtime(so)


def main() -> int:
    os.chdir(ROOT)
    todo = [p for p in sorted(glob.glob("ancf_petsc/**/*.pyx", recursive=True)) if stale(p)]
    if not todo:
        return 0
    try:
        from Cython.Build import cythonize
        from setuptools import Extension, setup
    except ImportError as exc:
        print(f"[setup] cannot build the compiled kernels: {exc} (apt-get install cython3)",
              file=sys.stderr)
        return 1
    exts = [Extension(p[:-4].replace(os.sep, "."), [p],
                      extra_compile_args=["-O3", "-march=native", "-Wno-unused-function"])
            for p in todo]
    print(f"[setup] building {len(todo)} compiled kernel module(s): {', '.join(todo)}")
    try:
        setup(name="ancf-petsc-native", script_args=["-q", "build_ext", "--inplace"],
              ext_modules=cythonize(exts, language_level=3, quiet=True))
    except (SystemExit, Exception) as exc:   # setuptools reports a compiler failure by SystemExit
        print(f"[setup] the compiled kernels did not build ({exc}): the numpy kernels run instead",
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
