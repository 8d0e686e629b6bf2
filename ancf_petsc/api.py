"""The Python API: load a config, build its model, solve it, read its results.

    import ancf_petsc as ap
    spec = ap.load_config("configs/uniaxial_neohookean.yaml")
    spec.output.dir = "/tmp/bar"
    result = ap.solve(spec)                      # collective on PETSc.COMM_WORLD
    print(result.status, ap.read_results("/tmp/bar").probe("tip")[-1])

``solve`` initialises PETSc on first use (with no command-line options; call
``petsc4py.init(argv)`` first to pass some).  Everything here is re-exported by ``ancf_petsc``.
"""
from __future__ import annotations

from typing import Callable

from .config import ConfigError, ModelSpec, load_config, parse_config
from .errors import InputError
from .io.reader import Results, read_results
from .model.beams import Model
from .model.build import build_model


def solve(spec: ModelSpec, comm=None, log: Callable[[str], None] = print, restart: str | None = None):
    """Solve ``spec`` and return a ``solving.run.RunResult`` (status, message, exit code, summary
    on rank 0); every converged level is written to ``spec.output.dir`` as it is reached.
    With ``accuracy:`` in the config the element count is chosen first (workflows/accuracy.py);
    ``restart``: continue the run in that directory from its last converged level."""
    _init_petsc()
    from petsc4py import PETSc

    from .solving.run import run_model
    comm = PETSc.COMM_WORLD if comm is None else comm
    if spec.accuracy is not None:
        if restart is not None:
            raise InputError("--restart", "a run with accuracy: chooses its mesh first; restart "
                                          "the chosen run's config instead")
        from .workflows.accuracy import select_and_run
        return select_and_run(spec, comm, log, run_model)
    return run_model(spec, comm, log, restart=restart)


def _init_petsc() -> None:
    """Initialise MPI, then PETSc (once; a no-op when the program already did)."""
    import petsc4py
    from mpi4py import MPI  # noqa: F401  (MPI before PETSc)
    petsc4py.init()


__all__ = ["ConfigError", "InputError", "Model", "ModelSpec", "Results", "build_model", "load_config",
           "parse_config", "read_results", "solve"]
