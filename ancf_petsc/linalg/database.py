"""PETSc's options database, read and written here only (issue 29): every module asks
``option(name, prefix)`` for a value, ``option_names()`` for what is set; the solve's defaults and
config options go in and out with ``insert`` / ``remove``.  The database holds the command line,
``PETSC_OPTIONS`` and options files; what the program adds around ``setFromOptions`` is in
options.py."""
from __future__ import annotations

import itertools
from contextlib import contextmanager

from petsc4py import PETSc

__all__ = ["option", "option_names", "option_values", "insert", "remove", "own_prefix", "SOLVE_FAMILIES"]

#: the option families of one solve (its SNES and line search, KSP, PC, matrix and factorisation
#: package) that a workflow's solves inherit from the command line
SOLVE_FAMILIES = ("snes_", "ksp_", "pc_", "mat_")
_SOLVES = itertools.count(1)


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
    removed after."""
    if solver.options_prefix:
        yield solver.options_prefix
        return
    prefix = f"{base}{next(_SOLVES)}_"
    copied = []
    for name in option_names():
        if name.startswith(SOLVE_FAMILIES) and option(name, prefix) is None:
            insert(prefix + name, option(name) or "")
            copied.append(prefix + name)
    solver.options_prefix = prefix
    try:
        yield prefix
    finally:
        solver.options_prefix = ""
        for name in copied:
            remove(name)
