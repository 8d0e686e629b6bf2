"""ancf-petsc: ANCF 3363 continuum beams for tendon mechanics, assembled and solved with PETSc.

Implements Obrezkov, Finni, Matikainen (2022), Materials 15:8906.  The Python API (``api.py``):
``load_config``, ``parse_config``, ``build_model``, ``solve``, ``read_results``.  Importing the
package loads neither PETSc nor MPI; ``solve`` does, on first use.
"""
from .version import __version__

_API = ("ConfigError", "InputError", "Model", "ModelSpec", "OutputError", "Results", "build_model",
        "load_config", "parse_config", "read_results", "solve")
__all__ = ["__version__", *_API]


def __getattr__(name: str):
    """The API names, imported on first use (PEP 562), so that ``import ancf_petsc`` stays light."""
    if name in _API:
        from . import api
        return getattr(api, name)
    raise AttributeError(f"module 'ancf_petsc' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(list(globals()) + list(_API))
