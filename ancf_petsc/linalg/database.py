"""PETSc's options database, read and written here only (issue 29): every module asks
``option(name, prefix)`` for a value, ``option_names()`` for what is set; the solve's defaults and
config options go in and out with ``insert`` / ``remove``.  The database holds the command line,
``PETSC_OPTIONS`` and options files; what the program adds around ``setFromOptions`` is in
options.py.  ``options_used`` reads PETSc's own used flags (through ``petsc_library``)."""
from __future__ import annotations

import ctypes
import itertools
import os
from contextlib import contextmanager

from petsc4py import PETSc

__all__ = ["option", "option_names", "option_values", "insert", "remove", "own_prefix", "copies",
           "options_used", "petsc_library", "SOLVE_FAMILIES"]

#: the option families of one solve (its SNES and line search, KSP, PC, matrix and factorisation
#: package) that a workflow's solves inherit from the command line
SOLVE_FAMILIES = ("snes_", "ksp_", "pc_", "mat_")
_SOLVES = itertools.count(1)
_COPIES: dict[str, str] = {}     # the copies own_prefix made and has not removed: copy -> original


def option(name: str, prefix: str = "") -> str | None:
    """The value of ``-<prefix><name>`` as text: None when it is not set, '' for a flag given
    without a value."""
    opts = PETSc.Options()
    key = prefix + name
    if not opts.hasName(key):
        return None
    value = opts.getString(key, "")
    return "" if value is None else str(value)


def option_names() -> list[str]:
    """The names of every option set (without the leading '-'), sorted."""
    return sorted(PETSc.Options().getAll())


def option_values() -> dict[str, str | None]:
    """Every option set, name (without the '-') to value (None for a flag given without one),
    read without marking any as used: a check of their values must leave PETSc's unused report
    intact."""
    return dict(PETSc.Options().getAll())


def insert(name: str, value: str) -> None:
    """Set ``-<name> <value>`` (the name with its prefix)."""
    PETSc.Options().setValue(name, value)


def remove(name: str) -> None:
    """Delete ``-<name>`` (the name with its prefix)."""
    PETSc.Options().delValue(name)


@contextmanager
def own_prefix(solver, base: str):
    """An in-process solve of a workflow under its own options prefix ``<base><n>_`` (``solver``
    a SolverSpec; a prefix the config gives, ``solver.options_prefix``, is kept).  What the
    solve puts into the database (its defaults, the config's ``petsc:``) then stays under its
    prefix and cannot reach the next solve, and PETSc's used-flags tell its unused options
    apart.  The solver options given without a prefix (``SOLVE_FAMILIES``: command line,
    PETSC_OPTIONS) are copied under the prefix for the solve, so they still apply to it, and
    removed after.  The originals are copied without being read: one is marked used when its
    copy was (a misspelt one stays in PETSc's unused report)."""
    if solver.options_prefix:
        yield solver.options_prefix
        return
    prefix = f"{base}{next(_SOLVES)}_"
    copied = []
    values = option_values()
    for name, value in values.items():
        if name.startswith(SOLVE_FAMILIES) and prefix + name not in values:
            insert(prefix + name, value or "")
            copied.append(name)
            _COPIES[prefix + name] = name
    solver.options_prefix = prefix
    try:
        yield prefix
    finally:
        solver.options_prefix = ""
        _remove_copies(prefix, copied)


def _remove_copies(prefix: str, names: list[str]) -> None:
    """Remove ``-<prefix><name>`` of each name; an original whose copy a solve read is read
    here, so PETSc counts it as used (this rank's flags, not collective)."""
    for name, used in zip(names, options_used([prefix + n for n in names])):
        if used:
            option(name)
        remove(prefix + name)
        _COPIES.pop(prefix + name, None)


def copies() -> dict[str, str]:
    """The options ``own_prefix`` copied under a solve's prefix, live now: copy -> original."""
    return dict(_COPIES)


_LIB = None


def petsc_library():
    """The libpetsc that petsc4py runs on (already loaded)."""
    global _LIB
    if _LIB is None:
        import petsc4py
        base = os.path.join(petsc4py.get_config()["PETSC_DIR"], "lib")
        names = sorted((f for f in os.listdir(base) if f.startswith("libpetsc") and ".so" in f), key=len)
        if not names:
            raise OSError(f"no libpetsc in {base}")
        # RTLD_NOLOAD: the copy petsc4py loaded, with its symbols kept local (RTLD_GLOBAL would
        # let them shadow later libraries': pymetis then called PT-Scotch's METIS shim and hung)
        _LIB = ctypes.CDLL(os.path.join(base, names[0]), mode=os.RTLD_NOLOAD | os.RTLD_LAZY)
    return _LIB


def options_used(names: list[str]) -> list[bool]:
    """PETSc's own 'used' flag of each option in the global database (this rank's view)."""
    lib = petsc_library()
    out = []
    for name in names:
        flag = ctypes.c_int(0)                   # PetscBool is a C enum
        if lib.PetscOptionsUsed(None, name.encode(), ctypes.byref(flag)) != 0:
            flag.value = 1                        # cannot tell: do not accuse it
        out.append(bool(flag.value))
    return out
