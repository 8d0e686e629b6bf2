"""One of scipy's compiled modules loaded by its path, without importing its subpackage.

``scipy.interpolate`` and ``scipy.optimize`` import all their routines when imported (~0.1 s of
every run's start-up together); the sections need two compiled routines of theirs (B-spline
evaluation, NNLS).  Loading the extension module by its file calls exactly scipy's code."""
from __future__ import annotations

import importlib.machinery
import importlib.util
import os


def load(subpackage: str, name: str, needs: str):
    """``scipy.<subpackage>.<name>`` loaded from its file, or None where scipy has no such module
    with the function ``needs`` (another layout or version: the callers then fall back)."""
    try:
        import scipy
        folder = os.path.join(os.path.dirname(scipy.__file__), subpackage)
        for suffix in importlib.machinery.EXTENSION_SUFFIXES:
            path = os.path.join(folder, name + suffix)
            if os.path.exists(path):
                spec = importlib.util.spec_from_file_location(f"scipy.{subpackage}.{name}", path)
                module = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(module)
                return module if hasattr(module, needs) else None
    except (ImportError, OSError):
        pass
    return None
