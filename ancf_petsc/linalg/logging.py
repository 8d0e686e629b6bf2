"""PETSc log stages and events of the program, created on first use: importing ancf_petsc creates
no PETSc object, and a program that never solves never registers them.  ``-log_view`` shows them
under these names."""
from __future__ import annotations

import functools

from petsc4py import PETSc

from .database import insert, option
from .option_syntax import AT_FINISH_OPTIONS

SETUP = "ANCF setup"
ASSEMBLY = "ANCF assembly"
SOLVE = "ANCF load stepping"
OUTPUT = "ANCF output"
STAGES = (SETUP, OUTPUT, SOLVE, ASSEMBLY)
ELEMENTS = "ANCF element kernels"
CONTACT = "ANCF contact"


@functools.cache
def stage(name: str) -> PETSc.Log.Stage:
    """The log stage ``name`` (registered once per process)."""
    return PETSc.Log.Stage(name)


@functools.cache
def event(name: str) -> PETSc.Log.Event:
    """The log event ``name`` (registered once per process)."""
    return PETSc.Log.Event(name)


def _over_stages(name: str, key: str) -> float:
    """``key`` ('time', 'count', ...) of event ``name``, summed over the main stage and the
    program's stages."""
    ev = event(name)
    ids = sorted({0} | {stage(s).id for s in STAGES})
    return sum(ev.getPerfInfo(i)[key] for i in ids)


def event_time(name: str) -> float:
    """Seconds spent in event ``name`` (every stage)."""
    return float(_over_stages(name, "time"))


def event_count(name: str) -> int:
    """How often event ``name`` ran (every stage)."""
    return int(_over_stages(name, "count"))


def view_at_exit(config_options: dict) -> None:
    """Put the config's ``log_view`` and ``options_left`` (``AT_FINISH_OPTIONS``) into PETSc's
    options database for the rest of the process: PETSc prints the log (and the options never
    used) in PetscFinalize, as for ``-log_view`` on the command line (which wins), and
    ``options_left`` turns ancf-solve's own report off as on the command line (it was itself
    reported as never used).  The log itself runs already (``PETSc.Log.begin`` in each run)."""
    for key in AT_FINISH_OPTIONS:
        if key in config_options and option(key) is None:
            insert(key, config_options[key])
