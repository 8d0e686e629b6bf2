"""The solid stack: MPI/PETSc first, then gmsh, ufl and dolfinx; a missing package is one SolidError line."""
from __future__ import annotations

import logging
import signal
import threading


class SolidError(RuntimeError):
    """A missing dependency or a failed solve: reported as one line, exit status 1."""


def import_stack():
    """Import MPI/PETSc, then gmsh, ufl and dolfinx (they must see the initialised PETSc)."""
    from mpi4py import MPI  # noqa: F401
    import petsc4py
    petsc4py.init([])
    session = signal.getsignal(signal.SIGINT)
    try:
        import gmsh  # noqa: F401  (its import sets SIGINT to SIG_DFL until gmsh.finalize)
        import ufl  # noqa: F401
        import dolfinx  # noqa: F401
        import dolfinx.fem.petsc  # noqa: F401
        import dolfinx.io.gmshio  # noqa: F401
    except ImportError as exc:
        raise SolidError(f"dolfinx/gmsh missing ({exc}); run: bash scripts/setup_solid.sh") from None
    finally:
        # the session's Ctrl-C stays a KeyboardInterrupt (SIG_DFL killed the process outright)
        if session is not None and threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, session)
    # the FFCx JIT's C build logs through the root logger at INFO (distutils resets its level)
    logging.getLogger().addFilter(lambda rec: rec.levelno >= logging.WARNING)
