"""Solving a model: ``snes_solver`` (the SNES and its options), ``load_control`` (increments and
cut-backs, pure Python), ``stepper`` (Newton inside adaptive load stepping), ``newton`` (an
increment's solves: the contact law's phases), ``run`` (one run from spec to results, its PETSc
objects destroyed at the end), ``samples`` (warm-started solves for calibration), ``supports``
(rigid motions left free), ``interrupt`` (signals between Newton solves).  The PETSc options and
the choice of linear solver are in ``linalg``."""

#: the sub-modules (imported on use: a plain import of the package loads none of them)
__all__ = ["chord", "interrupt", "load_control", "newton", "records", "restart_check", "run", "samples",
           "snes_solver", "solver_messages", "spread", "stepper", "supports"]
